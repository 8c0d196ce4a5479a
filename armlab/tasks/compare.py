"""`armlab eval --compare A.json B.json`: do two evaluations differ beyond chance, per job and level?

A file is what `armlab eval --json` prints or `--out` writes ({"runs", "summary", "record"}: one job and
level) or what `bench/competition.py --json-out` writes ({"cells": [that, ...]}: many). Jobs are matched by
(job, level, workcell); each pair present in both files is compared:

- full-points rate: Newcombe's hybrid score 95 % interval of the difference B - A (Newcombe 1998, method 10;
  armlab.tasks.stats); the rates differ beyond chance when it excludes 0. The test treats the runs as
  independent samples; when both used the same seeds a paired test would be more sensitive, so a "no
  difference" between such runs is conservative.
- mean points fraction (when both files list their runs): the seeded percentile bootstrap 95 % interval of
  the difference of the means B - A; the same rule.
"""

from __future__ import annotations

import json
from pathlib import Path

from armlab.errors import InvalidInput
from armlab.tasks.run_record import seed_text
from armlab.tasks.stats import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    bootstrap_difference_interval,
    excludes_zero,
    newcombe_difference_interval,
    wilson_interval,
)
from armlab.workcell import DEFAULT_WORKCELL

TEST_FULL_POINTS = ("full-points rate: Newcombe's hybrid score 95 % interval of the difference B - A (Newcombe 1998, "
                    "method 10, from the two Wilson intervals); different beyond chance when it excludes 0")
TEST_MEAN_POINTS = (f"mean points fraction: percentile bootstrap 95 % interval of the difference B - A ({BOOTSTRAP_RESAMPLES} "
                    f"resamples, seed {BOOTSTRAP_SEED}); different beyond chance when it excludes 0")


class CompareError(InvalidInput):
    """A file --compare cannot use (missing, not JSON, not an evaluation's output); the message names it."""


def _cell(path: Path, data, where: str) -> dict:
    """One (job, level) of a file: its key, name, run and full-points counts, points fractions, record."""
    def bad(what: str) -> CompareError:
        return CompareError(f"{path}{where} is not an armlab eval result: {what}")

    if not isinstance(data, dict):
        raise bad(f"expected a JSON object, got {type(data).__name__}")
    summary = data.get("summary")
    if not isinstance(summary, dict):
        raise bad('no "summary" object (write it with armlab eval --json or --out)')
    n, full = summary.get("runs"), summary.get("full_points_runs")
    for name, value in (("runs", n), ("full_points_runs", full)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise bad(f'summary "{name}" must be a non-negative integer, not {value!r}'
                      + (" (an output from before error bars? run it again)"
                         if value is None and name == "full_points_runs" and "full_rate" in summary else ""))
    if full > n:
        raise bad(f"summary says {full} full-points runs of {n}")
    record = data.get("record") if isinstance(data.get("record"), dict) else {}
    runs = data.get("runs") if isinstance(data.get("runs"), list) else []
    first = runs[0] if runs and isinstance(runs[0], dict) else {}
    event = record.get("event", first.get("event"))
    if not isinstance(event, str) or not event:
        raise bad('no job named (record "event" or the runs\' "event")')
    level = record.get("level", first.get("level"))
    workcell = record.get("workcell", first.get("workcell")) or DEFAULT_WORKCELL
    fractions = None
    if len(runs) == n and all(isinstance(run, dict) and isinstance(run.get("points"), int | float) for run in runs):
        fractions = [run["points"] / run["max_points"] if run.get("max_points") else 0.0 for run in runs]
    name = event if level is None else f"{event} L{level}"
    return {"key": (event, level, workcell), "name": name if workcell == DEFAULT_WORKCELL else f"{name} @{workcell}",
            "runs": n, "full_points_runs": full, "fractions": fractions, "record": record}


def load_cells(path: str | Path) -> list[dict]:
    """The evaluated (job, level)s of an `armlab eval` or `bench/competition.py` JSON file; CompareError saying
    what is wrong with a missing, unreadable, non-JSON or malformed file."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise CompareError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise CompareError(f"{path}: cannot read it: {error}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise CompareError(f"{path} is not JSON: {error}") from None
    if isinstance(data, dict) and "cells" in data:
        if not isinstance(data["cells"], list) or not data["cells"]:
            raise CompareError(f'{path} is not an armlab eval result: "cells" must be a non-empty list')
        cells = [_cell(path, cell, f' (cell {i})') for i, cell in enumerate(data["cells"])]
    else:
        cells = [_cell(path, data, "")]
    keys = [cell["key"] for cell in cells]
    repeated = next((key for i, key in enumerate(keys) if key in keys[:i]), None)
    if repeated is not None:
        raise CompareError(f"{path} holds {cells[keys.index(repeated)]['name']} more than once")
    return cells


def _side(cell: dict) -> dict:
    n, full = cell["runs"], cell["full_points_runs"]
    low, high = wilson_interval(full, n)
    return {"runs": n, "full_points_runs": full, "full_points_rate": round(full / n, 4) if n else None,
            "full_points_ci95": [round(low, 6), round(high, 6)]}


def compare_cells(cells_a: list[dict], cells_b: list[dict]) -> dict:
    """Every (job, level, workcell) in both, in A's order: both sides' rates with their Wilson intervals, the
    difference B - A with its Newcombe interval and `differs`; the same for the mean points fraction when both
    list their runs (None otherwise). Plus the names found in only one of them."""
    by_key_b = {cell["key"]: cell for cell in cells_b}
    keys_a = {cell["key"] for cell in cells_a}
    comparisons = []
    for a in cells_a:
        b = by_key_b.get(a["key"])
        if b is None:
            continue
        interval = newcombe_difference_interval(b["full_points_runs"], b["runs"], a["full_points_runs"], a["runs"])
        side_a, side_b = _side(a), _side(b)
        difference = (None if side_a["full_points_rate"] is None or side_b["full_points_rate"] is None
                      else round(side_b["full_points_rate"] - side_a["full_points_rate"], 4))
        mean_points = None
        if a["fractions"] and b["fractions"]:
            mean_a, mean_b = (sum(f) / len(f) for f in (a["fractions"], b["fractions"]))
            points_interval = bootstrap_difference_interval(a["fractions"], b["fractions"])
            mean_points = {"a": round(mean_a, 4), "b": round(mean_b, 4), "difference": round(mean_b - mean_a, 4),
                           "difference_ci95": [round(v, 6) for v in points_interval],
                           "differs": excludes_zero(points_interval)}
        comparisons.append({"job": a["name"], "event": a["key"][0], "level": a["key"][1], "workcell": a["key"][2],
                            "a": side_a, "b": side_b, "difference": difference,
                            "difference_ci95": [round(v, 6) for v in interval], "differs": excludes_zero(interval),
                            "mean_points_fraction": mean_points})
    return {"test": TEST_FULL_POINTS, "test_mean_points": TEST_MEAN_POINTS, "comparisons": comparisons,
            "only_in_a": [cell["name"] for cell in cells_a if cell["key"] not in by_key_b],
            "only_in_b": [cell["name"] for cell in cells_b if cell["key"] not in keys_a]}


def _record_text(cells: list[dict]) -> str:
    """The provenance of a file's first record: commit, config hash, realism, seeds."""
    record = next((cell["record"] for cell in cells if cell["record"]), {})
    if not record:
        return "no record (made before records were written)"
    git = record.get("git") or {}
    commit = git.get("commit")
    parts = [f"commit {commit[:10]}{' + uncommitted changes' if git.get('dirty') else ''}" if commit else "commit unknown"]
    if record.get("config_sha256"):
        parts.append(f"config {record['config_sha256'][:12]}")
    if record.get("realism"):
        parts.append(f"realism {record['realism']}")
    seeds = record.get("seeds")
    if isinstance(seeds, list) and seeds and all(isinstance(s, int) for s in seeds):
        parts.append(f"seeds {seed_text(sorted(seeds))}")
    return ", ".join(parts)


def _seeds(cells: list[dict]) -> set[int]:
    """Every seed a file's records name."""
    seeds = (cell["record"].get("seeds") for cell in cells)
    return {seed for listed in seeds if isinstance(listed, list) for seed in listed if isinstance(seed, int)}


def _percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def comparison_lines(result: dict, path_a: Path, path_b: Path, cells_a: list[dict], cells_b: list[dict]) -> list[str]:
    """The comparison as text: the two runs' provenance, the tests used, a verdict per job and level."""
    def verdict(differs: bool) -> str:
        return "DIFFERENT beyond chance" if differs else "no difference beyond chance"

    lines = [f"A: {path_a} ({_record_text(cells_a)})", f"B: {path_b} ({_record_text(cells_b)})",
             f"test: {result['test']}", f"test: {result['test_mean_points']}"]
    seeds_a, seeds_b = (_seeds(cells) for cells in (cells_a, cells_b))
    if seeds_a & seeds_b:
        lines.append(f"note: A and B share {len(seeds_a & seeds_b)} seed(s); the tests treat the runs as independent, "
                     "which is conservative for runs on the same seeds (a paired test would be more sensitive)")
    for item in result["comparisons"]:
        a, b = item["a"], item["b"]
        low, high = item["difference_ci95"]
        difference = "-" if item["difference"] is None else f"{100 * item['difference']:+.1f}"
        lines.append(f"{item['job']}: full points A {a['full_points_runs']}/{a['runs']} = {_percent(a['full_points_rate'])} "
                     f"[{100 * a['full_points_ci95'][0]:.1f}, {100 * a['full_points_ci95'][1]:.1f}], "
                     f"B {b['full_points_runs']}/{b['runs']} = {_percent(b['full_points_rate'])} "
                     f"[{100 * b['full_points_ci95'][0]:.1f}, {100 * b['full_points_ci95'][1]:.1f}]; B - A {difference} "
                     f"percentage points, 95 % interval [{100 * low:+.1f}, {100 * high:+.1f}]: {verdict(item['differs'])}")
        points = item["mean_points_fraction"]
        if points is not None:
            p_low, p_high = points["difference_ci95"]
            lines.append(f"    mean points A {_percent(points['a'])}, B {_percent(points['b'])}; B - A "
                         f"{100 * points['difference']:+.1f} percentage points, 95 % interval [{100 * p_low:+.1f}, "
                         f"{100 * p_high:+.1f}]: {verdict(points['differs'])}")
        else:
            lines.append("    mean points not compared: a file does not list its runs")
    if result["only_in_a"]:
        lines.append(f"only in A (not compared): {', '.join(result['only_in_a'])}")
    if result["only_in_b"]:
        lines.append(f"only in B (not compared): {', '.join(result['only_in_b'])}")
    return lines
