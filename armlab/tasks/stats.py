"""Error bars for evaluation figures: pure functions, no I/O, deterministic for a given seed.

- `wilson_interval`: the Wilson score interval of a proportion (Wilson 1927; Newcombe 1998, "Two-sided
  confidence intervals for the single proportion", method 3: no continuity correction).
- `bootstrap_mean_interval`: the percentile bootstrap interval of a mean (Efron & Tibshirani 1993, ch. 13),
  resampled with a seeded generator, so the same values and seed give the same interval.
- `newcombe_difference_interval`: the interval of the difference of two independent proportions from their
  Wilson intervals (Newcombe 1998, "Interval estimation for the difference between independent proportions",
  method 10, the hybrid score interval); two rates differ beyond chance when it excludes 0.
- `bootstrap_difference_interval`: the percentile bootstrap interval of the difference of two independent
  means (each sample resampled on its own), seeded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 0
_CHUNK_DRAWS = 1_000_000  # index draws per chunk: bounded memory for 10 000 values x 2000 resamples


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval (Wilson 1927) of the proportion successes / n, without continuity correction:

        centre = (p + z^2 / 2n) / (1 + z^2 / n),  half-width = z sqrt(p (1 - p) / n + z^2 / 4n^2) / (1 + z^2 / n)

    with p = successes / n. Unlike the normal ("Wald") interval it stays inside [0, 1] and is not zero-wide at
    0 / n or n / n (0/10 -> [0, 0.2775]). n = 0 says nothing: [0, 1]. ValueError for counts that are not
    0 <= successes <= n."""
    if isinstance(successes, bool) or isinstance(n, bool) or int(successes) != successes or int(n) != n:
        raise ValueError(f"successes and n must be integers, not {successes!r} and {n!r}")
    if not 0 <= successes <= n:
        raise ValueError(f"need 0 <= successes <= n, not {successes} of {n}")
    if not z > 0:
        raise ValueError(f"z must be positive, not {z!r}")
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    denominator = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n)) / denominator
    # At 0/n and n/n one end is exactly 0 or 1; rounding must not put it a hair outside [0, 1].
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == n else min(1.0, centre + half)
    return low, high


def _resampled_means(values: np.ndarray, rng: np.random.Generator, n_resamples: int) -> np.ndarray:
    """n_resamples means of samples drawn with replacement from values (same size), in chunks."""
    n = values.size
    rows = max(1, _CHUNK_DRAWS // n)
    means = np.empty(n_resamples)
    for start in range(0, n_resamples, rows):
        stop = min(n_resamples, start + rows)
        means[start:stop] = values[rng.integers(0, n, size=(stop - start, n))].mean(axis=1)
    return means


def _check_bootstrap(n_resamples: int, confidence: float) -> None:
    if isinstance(n_resamples, bool) or not isinstance(n_resamples, int) or n_resamples < 1:
        raise ValueError(f"n_resamples must be a positive integer, not {n_resamples!r}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), not {confidence!r}")


def _as_values(values: Sequence[float], name: str = "values") -> np.ndarray:
    array = np.asarray(list(values), dtype=float)
    if array.size == 0:
        raise ValueError(f"{name}: no values to bootstrap")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: every value must be finite")
    return array


def bootstrap_mean_interval(values: Sequence[float], seed: int = BOOTSTRAP_SEED,
                            n_resamples: int = BOOTSTRAP_RESAMPLES, confidence: float = 0.95) -> tuple[float, float]:
    """The percentile bootstrap interval of the mean of `values` (Efron & Tibshirani 1993, ch. 13): the
    (1 - confidence) / 2 and (1 + confidence) / 2 quantiles (linear interpolation) of n_resamples means of
    samples drawn with replacement, from numpy's default generator seeded with `seed`, so it is reproducible.
    Values all equal give a zero-wide interval at that value. ValueError for no values or a non-finite one."""
    _check_bootstrap(n_resamples, confidence)
    array = _as_values(values)
    means = _resampled_means(array, np.random.default_rng(seed), n_resamples)
    tail = (1.0 - confidence) / 2.0
    low, high = np.quantile(means, [tail, 1.0 - tail])
    return float(low), float(high)


def bootstrap_difference_interval(values_a: Sequence[float], values_b: Sequence[float], seed: int = BOOTSTRAP_SEED,
                                  n_resamples: int = BOOTSTRAP_RESAMPLES, confidence: float = 0.95) -> tuple[float, float]:
    """The percentile bootstrap interval of mean(values_b) - mean(values_a) for two independent samples: each
    resampled on its own (Efron & Tibshirani 1993, ch. 8), one seeded generator for both, so reproducible."""
    _check_bootstrap(n_resamples, confidence)
    a, b = _as_values(values_a, "values_a"), _as_values(values_b, "values_b")
    rng = np.random.default_rng(seed)
    differences = _resampled_means(b, rng, n_resamples) - _resampled_means(a, rng, n_resamples)
    tail = (1.0 - confidence) / 2.0
    low, high = np.quantile(differences, [tail, 1.0 - tail])
    return float(low), float(high)


def newcombe_difference_interval(successes_1: int, n_1: int, successes_2: int, n_2: int,
                                 z: float = 1.96) -> tuple[float, float]:
    """The hybrid score interval of p1 - p2 for two independent proportions (Newcombe 1998, method 10), from
    each proportion's Wilson interval (l_i, u_i):

        low = (p1 - p2) - sqrt((p1 - l1)^2 + (u2 - p2)^2),  high = (p1 - p2) + sqrt((u1 - p1)^2 + (p2 - l2)^2)

    The two proportions differ beyond chance (at the level z gives) when the interval excludes 0. Either n = 0:
    [-1, 1]."""
    l1, u1 = wilson_interval(successes_1, n_1, z)
    l2, u2 = wilson_interval(successes_2, n_2, z)
    if n_1 == 0 or n_2 == 0:
        return -1.0, 1.0
    p1, p2 = successes_1 / n_1, successes_2 / n_2
    difference = p1 - p2
    low = difference - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)
    high = difference + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)
    return max(-1.0, low), min(1.0, high)


def excludes_zero(interval: tuple[float, float]) -> bool:
    """True when an interval of a difference lies wholly above or below 0."""
    low, high = interval
    return low > 0.0 or high < 0.0
