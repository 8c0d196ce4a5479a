"""armlab.tasks.stats: the Wilson interval on published cases and hand-computed ones, Newcombe's interval of a
difference on the published examples, and the seeded bootstrap: reproducible, covering the mean, as wide as
theory says. Pure: no simulation.

The literals below are not computed by the code under test: the Newcombe 1998 values are the papers' tables
(Stat. Med. 17: 857-872, Table I, method 3; 873-890, Table II, method 10), the others were worked out by hand
from the Wilson formula, centre (p + z^2/2n) / (1 + z^2/n) -/+ z sqrt(p(1-p)/n + z^2/4n^2) / (1 + z^2/n),
z = 1.96."""

import math

import pytest

from armlab.tasks.stats import (
    bootstrap_difference_interval,
    bootstrap_mean_interval,
    excludes_zero,
    newcombe_difference_interval,
    wilson_interval,
)


@pytest.mark.parametrize("successes, n, low, high", [
    (0, 10, 0.0, 0.277540),   # z^2/(n + z^2) = 3.8416 / 13.8416
    (10, 10, 0.722460, 1.0),
    (25, 50, 0.366443, 0.633557),
    (29, 50, 0.442332, 0.706252),
    (5, 50, 0.043475, 0.213605),
    (45, 50, 0.786395, 0.956525),
])
def test_wilson_interval_hand_computed(successes, n, low, high):
    got = wilson_interval(successes, n)
    assert got == pytest.approx((low, high), abs=1e-6)


@pytest.mark.parametrize("successes, n, low, high", [
    (81, 263, 0.2553, 0.3662),
    (15, 148, 0.0624, 0.1605),
    (0, 20, 0.0, 0.1611),
    (1, 29, 0.0061, 0.1718),
])
def test_wilson_interval_newcombe_1998_table_1(successes, n, low, high):
    assert wilson_interval(successes, n) == pytest.approx((low, high), abs=5e-5)


def test_wilson_ends_are_exact_and_inside_0_1():
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == 1.0
    assert wilson_interval(0, 0) == (0.0, 1.0)  # no runs: no knowledge
    for n in (1, 2, 7, 50, 1000):
        for k in range(0, n + 1, max(1, n // 10)):
            low, high = wilson_interval(k, n)
            assert 0.0 <= low <= k / n <= high <= 1.0


def test_25_of_50_and_29_of_50_overlap_but_5_and_45_do_not():
    a, b = wilson_interval(25, 50), wilson_interval(29, 50)
    assert a[0] < b[0] < a[1] < b[1]  # overlap: 0.4423 < 0.6336
    c, d = wilson_interval(5, 50), wilson_interval(45, 50)
    assert c[1] < d[0]


@pytest.mark.parametrize("args", [(-1, 10), (11, 10), (1.5, 10), (True, 3), (3, 2.5)])
def test_wilson_refuses_bad_counts(args):
    with pytest.raises(ValueError):
        wilson_interval(*args)


@pytest.mark.parametrize("counts, low, high", [
    ((56, 70, 48, 80), 0.0524, 0.3339),   # Newcombe 1998 Table II, method 10
    ((9, 10, 3, 10), 0.1705, 0.8090),
    ((5, 56, 0, 29), -0.0381, 0.1926),
    ((6, 7, 2, 7), 0.0582, 0.8063),       # by hand from the formula
    ((29, 50, 25, 50), -0.1118, 0.2638),  # by hand: includes 0
    ((45, 50, 5, 50), 0.6393, 0.8799),    # by hand: excludes 0
    ((3, 10, 9, 10), -0.8090, -0.1705),  # Table II's case the other way round: wholly below 0
])
def test_newcombe_difference_interval(counts, low, high):
    got = newcombe_difference_interval(*counts)
    assert got == pytest.approx((low, high), abs=1e-4)
    assert excludes_zero(got) == (low > 0 or high < 0)


def test_newcombe_is_antisymmetric_and_refuses_bad_counts():
    low, high = newcombe_difference_interval(29, 50, 25, 50)
    assert newcombe_difference_interval(25, 50, 29, 50) == pytest.approx((-high, -low), abs=1e-12)
    with pytest.raises(ValueError):
        newcombe_difference_interval(51, 50, 25, 50)


VALUES = [0.2, 0.5, 0.5, 0.7, 0.9, 1.0, 1.0, 1.0, 0.4, 0.8, 1.0, 0.6]


def test_bootstrap_reproducible_with_its_seed_and_covers_the_mean():
    first = bootstrap_mean_interval(VALUES, seed=7, n_resamples=2000)
    assert bootstrap_mean_interval(VALUES, seed=7, n_resamples=2000) == first
    assert bootstrap_mean_interval(VALUES, seed=8, n_resamples=2000) != first
    mean = sum(VALUES) / len(VALUES)
    assert first[0] < mean < first[1]
    assert min(VALUES) <= first[0] and first[1] <= max(VALUES)


def test_bootstrap_width_matches_the_standard_error():
    """25 zeros and 25 ones: the mean's standard error is sqrt(0.25 / 50) = 0.0707, so the 95 % interval is
    about 0.5 -/+ 0.139; a percentile bootstrap of 4000 resamples lands within 0.02 of that."""
    values = [0.0] * 25 + [1.0] * 25
    low, high = bootstrap_mean_interval(values, seed=1, n_resamples=4000)
    half = 1.96 * math.sqrt(0.25 / 50)
    assert low == pytest.approx(0.5 - half, abs=0.02) and high == pytest.approx(0.5 + half, abs=0.02)


def test_bootstrap_of_equal_values_is_that_value_and_bad_input_is_refused():
    assert bootstrap_mean_interval([1.0] * 20, seed=0) == (1.0, 1.0)
    with pytest.raises(ValueError):
        bootstrap_mean_interval([], seed=0)
    with pytest.raises(ValueError):
        bootstrap_mean_interval([0.5, float("nan")], seed=0)
    with pytest.raises(ValueError):
        bootstrap_mean_interval([0.5], seed=0, n_resamples=0)


def test_bootstrap_difference_reproducible_and_separates_different_means():
    low_a = [0.0] * 45 + [1.0] * 5
    high_b = [0.0] * 5 + [1.0] * 45
    interval = bootstrap_difference_interval(low_a, high_b, seed=3)
    assert interval == bootstrap_difference_interval(low_a, high_b, seed=3)
    assert interval[0] < 0.8 < interval[1] and excludes_zero(interval)
    same = bootstrap_difference_interval([0.0] * 25 + [1.0] * 25, [0.0] * 21 + [1.0] * 29, seed=3)
    assert same[0] < 0.08 < same[1] and not excludes_zero(same)
