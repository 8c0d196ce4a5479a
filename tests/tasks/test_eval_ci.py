"""`armlab eval`'s error bars without running episodes: the summary's intervals, --until-ci stopping at its width
and at its bound (a fake episode function stands in for `evaluate`), the record in --out, --compare on synthetic
files (25/50 vs 29/50: no difference beyond chance; 5/50 vs 45/50: different) and bad input refused."""

import json
import re
from pathlib import Path

import pytest

from armlab.cli import main
from armlab.tasks import evaluate as evaluate_module
from armlab.tasks.evaluate import UntilCi, summarize
from armlab.tasks.stats import BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, bootstrap_mean_interval

EVENT, LEVEL = "pick_sort", "1"


def fake_run(seed: int, full: bool, points: int | None = None) -> dict:
    """A run as evaluate() yields it: full points or 40 of 100."""
    points = (100 if full else 40) if points is None else points
    return {"event": EVENT, "level": 1, "seed": seed, "workcell": "rx200_armlab", "realism": "ideal", "points": points,
            "max_points": 100, "within_limit": True, "full": full, "sim_time_s": 30.0, "wall_time_s": 1.0,
            "cpu_time_s": 1.0, "breakdown": [], "failures": []}


def always_full(seeds):
    return (fake_run(seed, True) for seed in seeds)


def half_full(seeds):
    return (fake_run(seed, seed % 2 == 0) for seed in seeds)


# ---------------------------------------------------------------------------------------------------
# The summary


def test_summary_intervals_25_of_50():
    runs = [fake_run(seed, seed < 25, None if seed < 25 else 30 + seed) for seed in range(50)]  # 55..79 points
    summary = summarize(runs)
    assert summary["full_points_runs"] == 25 and summary["full_points_rate"] == 0.5 == summary["full_rate"]
    assert summary["full_points_ci95"] == pytest.approx([0.3664, 0.6336], abs=1e-4)  # Wilson, by hand
    mean = (25 * 100 + sum(range(55, 80))) / 50 / 100
    assert summary["mean_points_fraction"] == pytest.approx(mean, abs=1e-4)
    low, high = summary["mean_points_ci95"]
    assert low < mean < high and high - low < 0.2
    # Seeded with the documented seed: the same runs give the same interval, another seed another one.
    fractions = [run["points"] / 100 for run in runs]
    assert summarize(runs)["mean_points_ci95"] == [low, high]
    assert [low, high] == pytest.approx(bootstrap_mean_interval(fractions, seed=BOOTSTRAP_SEED,
                                                                n_resamples=BOOTSTRAP_RESAMPLES), abs=1e-6)
    assert [low, high] != pytest.approx(bootstrap_mean_interval(fractions, seed=BOOTSTRAP_SEED + 1), abs=1e-6)


def test_summary_counts_a_crash_as_no_full_points():
    runs = [fake_run(0, True), {**fake_run(1, False), "crashed": True, "points": 0, "max_points": None,
                                "sim_time_s": None}]
    summary = summarize(runs)
    assert summary["crashed"] == 1 and summary["full_points_runs"] == 1 and summary["full_points_rate"] == 0.5
    assert summary["full_points_ci95"] == pytest.approx([0.0945, 0.9055], abs=1e-4)  # Wilson 1/2, by hand


# ---------------------------------------------------------------------------------------------------
# --until-ci


def test_until_ci_stops_when_the_interval_is_narrow_enough():
    """Every run full: the Wilson width at n/n is 3.8416 / (n + 3.8416): 0.161 at 20, 0.114 at 30, 0.088 at 40;
    0.1 wanted -> 40 seeds in 4 batches, well under the bound."""
    batches = []

    def run_seeds(seeds):
        batches.append(list(seeds))
        return always_full(seeds)

    statuses = []
    until = UntilCi(run_seeds, range(10), 0.1, max_seeds=500, batch_seeds=10, on_batch=statuses.append)
    runs = list(until.runs())
    assert batches == [list(range(0, 10)), list(range(10, 20)), list(range(20, 30)), list(range(30, 40))]
    assert [run["seed"] for run in runs] == list(range(40))
    assert until.stopped_by == "width"
    status = until.status()
    assert status["seeds_run"] == 40 and status["width"] <= 0.1 and status["batches"] == 4
    assert [s["stopped_by"] for s in statuses] == [None, None, None, "width"]
    assert statuses[2]["width"] > 0.1  # 30 seeds were not enough


def test_until_ci_stops_at_its_bound_with_a_last_batch_cut_to_fit():
    """Half the runs full: 0.05 wide needs ~1500 seeds; the bound of 60 stops it (first 25, then 20, then 15)."""
    batches = []

    def run_seeds(seeds):
        batches.append(list(seeds))
        return half_full(seeds)

    until = UntilCi(run_seeds, [5, 1, 3] + list(range(7, 29)), 0.05, max_seeds=60, batch_seeds=20)
    runs = list(until.runs())
    assert [len(batch) for batch in batches] == [25, 20, 15]
    assert batches[1][0] == 29 and batches[2] == list(range(49, 64))  # the next seeds after the largest run
    assert len(runs) == 60 == len({run["seed"] for run in runs})
    assert until.stopped_by == "max_seeds" and until.status()["width"] > 0.05


@pytest.mark.parametrize("kwargs, message", [
    ({"width": 0.0}, "(0, 1]"),
    ({"width": 1.5}, "(0, 1]"),
    ({"max_seeds": 5}, "more than --max-seeds 5"),
    ({"batch_seeds": 0}, "--batch-seeds must be an integer"),
])
def test_until_ci_refuses_bad_requests(kwargs, message):
    from armlab.tasks.evaluate import EvalError

    args = {"width": 0.1, "max_seeds": 100, "batch_seeds": 10, **kwargs}
    with pytest.raises(EvalError, match=re.escape(message)):
        UntilCi(always_full, range(10), args.pop("width"), **args)


@pytest.fixture()
def fake_evaluate(monkeypatch):
    """armlab eval runs `outcome(seed) -> full?` instead of episodes; the seeds asked for are kept."""
    asked = []

    def install(outcome):
        def evaluate(event, level, seeds, **kwargs):
            asked.append(list(seeds))
            return (fake_run(seed, outcome(seed)) for seed in seeds)

        monkeypatch.setattr(evaluate_module, "evaluate", evaluate)
        return asked

    return install


def test_cli_until_ci_width_and_record_in_out_file(fake_evaluate, capsys, tmp_path):
    asked = fake_evaluate(lambda seed: True)
    out = tmp_path / "runs" / "a.json"
    code = main(["eval", EVENT, "--level", LEVEL, "--seeds", "0-9", "--until-ci", "0.2", "--batch-seeds", "10",
                 "--max-seeds", "100", "--json", "--out", str(out)])
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    assert asked == [list(range(10)), list(range(10, 20))]  # 0.278 wide after 10, 0.161 after 20
    until = printed["summary"]["until_ci"]
    assert until["stopped_by"] == "width" and until["seeds_run"] == 20 and until["width_wanted"] == 0.2
    assert printed["summary"]["full_points_ci95"] == pytest.approx([0.8389, 1.0], abs=1e-4)  # Wilson 20/20, by hand
    saved = json.loads(out.read_text())
    assert saved["summary"] == printed["summary"] and saved["runs"] == printed["runs"]
    record = saved["record"]
    assert record["event"] == EVENT and record["level"] == 1 and record["seeds"] == list(range(20))
    assert record["realism"] == "ideal" and record["workcell"] == "rx200_armlab"
    assert re.fullmatch(r"[0-9a-f]{64}", record["config_sha256"]) and record["config_files"] > 5
    assert record["git"]["commit"] is None or re.fullmatch(r"[0-9a-f]{40}", record["git"]["commit"])


def test_cli_until_ci_says_when_the_bound_stopped_it(fake_evaluate, capsys):
    asked = fake_evaluate(lambda seed: seed % 2 == 0)
    code = main(["eval", EVENT, "--level", LEVEL, "--seeds", "0-9", "--until-ci", "0.1", "--batch-seeds", "10",
                 "--max-seeds", "30"])
    assert code == 0
    text = capsys.readouterr().out
    assert [len(batch) for batch in asked] == [10, 10, 10]
    assert "STOPPED by the bound --max-seeds 30" in text
    assert "STOPPED BY THE BOUND (--max-seeds 30)" in text
    assert "full points within the time limit: 15/30 = 50.0 % of runs (95 % interval 33.2-66.8 %)" in text


@pytest.mark.parametrize("args, message", [
    (["--until-ci", "0"], "argument --until-ci: the interval width must be a fraction in (0, 1]"),
    (["--until-ci", "-0.1"], "argument --until-ci: the interval width must be a fraction in (0, 1]"),
    (["--until-ci", "1.5"], "argument --until-ci: the interval width must be a fraction in (0, 1]"),
    (["--until-ci", "nan"], "argument --until-ci: the interval width must be a fraction in (0, 1]"),
    (["--until-ci", "wide"], "argument --until-ci: the interval width must be a number"),
    (["--max-seeds", "50"], "--max-seeds only with --until-ci"),
    (["--until-ci", "0.1", "--max-seeds", "0"], "argument --max-seeds: expected an integer in 1..10000"),
])
def test_bad_until_ci_options_are_argparse_errors(args, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["eval", EVENT, "--level", LEVEL, "--seeds", "1", *args])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: armlab eval") and message in err


# ---------------------------------------------------------------------------------------------------
# --compare


def eval_file(path, full: int, n: int, event: str = EVENT, level: int | None = 1, seeds=None) -> str:
    """A synthetic `armlab eval --json` output: `full` of `n` runs with full points (the rest 40 of 100)."""
    seeds = list(range(n)) if seeds is None else seeds
    runs = [{**fake_run(seed, i < full), "event": event, "level": level} for i, seed in enumerate(seeds)]
    output = {"runs": [evaluate_module.public_run(run) for run in runs], "summary": summarize(runs),
              "record": {"format": 1, "event": event, "level": level, "workcell": "rx200_armlab", "seeds": seeds,
                         "realism": "ideal", "git": {"commit": "0123456789abcdef" * 2 + "01234567", "dirty": False},
                         "config_sha256": "ab" * 32}}
    path.write_text(json.dumps(output))
    return str(path)


def test_compare_25_of_50_against_29_of_50_is_no_difference(tmp_path, capsys):
    a, b = eval_file(tmp_path / "a.json", 25, 50), eval_file(tmp_path / "b.json", 29, 50, seeds=list(range(50, 100)))
    assert main(["eval", "--compare", a, b]) == 0
    out = capsys.readouterr().out
    assert "Newcombe's hybrid score 95 % interval" in out  # the test is named
    line = next(line for line in out.splitlines() if line.startswith("pick_sort L1:"))
    assert "A 25/50 = 50.0 %" in line and "B 29/50 = 58.0 %" in line
    assert "B - A +8.0 percentage points, 95 % interval [-11.2, +26.4]: no difference beyond chance" in line
    assert "seeds 0-49" in out and "seeds 50-99" in out and "commit 0123456789" in out
    assert "share" not in out  # different seeds: no note
    same_seeds = eval_file(tmp_path / "c.json", 29, 50)
    assert main(["eval", "--compare", a, same_seeds]) == 0
    assert "note: A and B share 50 seed(s); the tests treat the runs as independent" in capsys.readouterr().out


def test_compare_5_of_50_against_45_of_50_differs(tmp_path, capsys):
    a, b = eval_file(tmp_path / "a.json", 5, 50), eval_file(tmp_path / "b.json", 45, 50)
    assert main(["eval", "--compare", a, b, "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    (item,) = result["comparisons"]
    assert item["differs"] is True and item["difference"] == 0.8
    assert item["difference_ci95"] == pytest.approx([0.6393, 0.8799], abs=1e-4)  # Newcombe, by hand
    assert item["mean_points_fraction"]["differs"] is True
    assert "Newcombe" in result["test"]
    assert main(["eval", "--compare", a, b]) == 0
    assert ": DIFFERENT beyond chance" in capsys.readouterr().out
    assert main(["eval", "--compare", b, a, "--json"]) == 0  # the other way round: B worse than A
    (item,) = json.loads(capsys.readouterr().out)["comparisons"]
    assert item["differs"] is True and item["difference_ci95"] == pytest.approx([-0.8799, -0.6393], abs=1e-4)


def test_compare_matches_jobs_and_levels_across_a_bench_file(tmp_path, capsys):
    single = eval_file(tmp_path / "single.json", 25, 50)
    cells = [json.loads(Path(eval_file(tmp_path / f"c{i}.json", full, 50, event, level)).read_text()) for i, (full, event, level) in
             enumerate([(29, EVENT, 1), (50, EVENT, 3), (10, "line_up", 2)])]
    bench = tmp_path / "bench.json"
    bench.write_text(json.dumps({"cells": cells}))
    assert main(["eval", "--compare", single, str(bench)]) == 0
    out = capsys.readouterr().out
    assert sum(line.startswith("pick_sort L") for line in out.splitlines()) == 1
    assert "only in B (not compared): pick_sort L3, line_up L2" in out


def test_compare_without_runs_compares_the_rates_only(tmp_path, capsys):
    a, b = eval_file(tmp_path / "a.json", 25, 50), eval_file(tmp_path / "b.json", 29, 50)
    data = json.loads((tmp_path / "b.json").read_text())
    del data["runs"]
    (tmp_path / "b.json").write_text(json.dumps(data))
    assert main(["eval", "--compare", a, b]) == 0
    assert "mean points not compared: a file does not list its runs" in capsys.readouterr().out


@pytest.mark.parametrize("content, message", [
    (None, "no such file"),
    ("{not json", "is not JSON"),
    ("[1, 2]", "is not an armlab eval result: expected a JSON object, got list"),
    ('{"runs": []}', 'no "summary" object'),
    ('{"summary": {"runs": 50, "full_rate": 0.5}, "record": {"event": "pick_sort"}}',
     'summary "full_points_runs" must be a non-negative integer, not None (an output from before error bars?'),
    ('{"summary": {"runs": 10, "full_points_runs": 11}, "record": {"event": "pick_sort"}}', "11 full-points runs of 10"),
    ('{"summary": {"runs": 10, "full_points_runs": 5}}', "no job named"),
    ('{"cells": []}', '"cells" must be a non-empty list'),
])
def test_compare_refuses_a_missing_or_malformed_file(content, message, tmp_path, capsys):
    good = eval_file(tmp_path / "good.json", 25, 50)
    bad = tmp_path / "bad.json"
    if content is not None:
        bad.write_text(content)
    assert main(["eval", "--compare", good, str(bad)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"armlab eval: --compare: {bad}") and message in captured.err
    assert captured.err.count("\n") == 1


def test_compare_with_nothing_in_common_is_an_error(tmp_path, capsys):
    a = eval_file(tmp_path / "a.json", 25, 50)
    b = eval_file(tmp_path / "b.json", 25, 50, event="line_up", level=2)
    assert main(["eval", "--compare", a, b]) == 2
    assert "no job and level in common (A: pick_sort L1; B: line_up L2)" in capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["--compare", "a.json"], "expected 2 arguments"),
    ([EVENT, "--seeds", "1", "--compare", "a.json", "b.json"], "--compare runs nothing: leave out a job, --seeds"),
    (["--level", "1"], "give a job and --seeds"),
])
def test_compare_argument_errors(args, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["eval", *args])
    assert exit_info.value.code == 2 and message in capsys.readouterr().err
