"""Competition benchmark (issue 8): every job in armlab.tasks.JOBS that has levels, at every level, over the
same seeds (>= 20 by default), run headless by `armlab.tasks.evaluate` and scored by the judge; plus the
success rate of the jobs without levels (sort_by_tag, clear_table, stack_here) on random scenes.

Per (job, level): mean and minimum points as a fraction of the maximum (the mean with its seeded percentile
bootstrap 95 % interval), full-points rate within the time limit (with its Wilson 95 % score interval; both
from armlab.tasks.stats), mean simulated time, mean wall time per run, the real-time factor per worker (simulated / wall
seconds; also per CPU second, which other load on a shared machine does not lower), and the reasons of
every failure grouped with counts. Targets, printed next to the figures:
- full points within the time limit in >= 95 % of seeds: pick_sort L3, pick_stack L3, line_up L3,
  stack_high L2, sort_stack L3;
- pick_sort L3 in <= 120 s simulated (mean; the rule allows 180);
- to_the_sky >= 12 large blocks standing in one tower (mean; the judge's "tower" rule names them);
- eval at >= 10x real time per worker.
- sort_by_tag L3 and stack_here (issue 12, the UR3 write-up's jobs) full points in >= 95 % of seeds on every
  workcell run (--workcells rx200_armlab,ur3_suction: the RX200 with fingers, the UR3 with the suction cup).
Prints figures; asserts nothing. --json-out FILE writes every (job, level)'s runs, summary (with the intervals)
and record (git commit, config hash, seeds, realism) as {"cells": [...]}, which `armlab eval --compare` reads.

    MUJOCO_GL=egl .venv/bin/python bench/competition.py [--seeds 0-19] [--workers 2] [--jobs pick_sort,line_up]
        [--workcells rx200_armlab,ur3_suction] [--json-out FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field

os.environ.setdefault("MUJOCO_GL", "egl")
# This tree's armlab, not the one the venv's editable install points at (a worktree sharing main's .venv ran main's).
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from armlab.scene import COLORS  # noqa: E402
from armlab.tasks import JOBS  # noqa: E402
from armlab.tasks.evaluate import EvalError, episode_unsupported, evaluate, parse_seeds, public_run, summarize  # noqa: E402
from armlab.tasks.run_record import now_utc, run_record  # noqa: E402
from armlab.workcell import DEFAULT_WORKCELL  # noqa: E402
from armlab.workcell.loading import known_workcells  # noqa: E402

DEFAULT_SEEDS = "0-19"
FULL_RATE_TARGETS = {("pick_sort", 3): 0.95, ("pick_stack", 3): 0.95, ("line_up", 3): 0.95,
                     ("stack_high", 2): 0.95, ("sort_stack", 3): 0.95}
SIM_TIME_TARGETS_S = {("pick_sort", 3): 120.0}  # mean simulated seconds
TOWER_TARGET_BLOCKS = 12.0  # to_the_sky, mean over seeds
WORKCELL_FULL_RATE_TARGETS = {("sort_by_tag", 3): 0.95, ("stack_here", None): 0.95}  # on every workcell run
REALTIME_TARGET = 10.0  # per worker
LEVELLESS_JOBS = ("sort_by_tag", "clear_table", "stack_here")  # success rates on random scenes
_NUMBER = re.compile(r"-?\d+(?:\.\d+)?")
_COLOUR = re.compile(r"\b(" + "|".join(COLORS) + r")\b")


@dataclass
class Cell:
    """The runs of one (job, level), or why it did not run."""

    job: str
    level: int | None
    runs: list[dict] = field(default_factory=list)
    skipped: str = ""
    workcell: str = DEFAULT_WORKCELL
    started_utc: str = ""

    @property
    def name(self) -> str:
        name = self.job if self.level is None else f"{self.job} L{self.level}"
        return name if self.workcell == DEFAULT_WORKCELL else f"{name} @{self.workcell}"


def reason_key(text: str) -> str:
    """A failure reason with its numbers and colours blanked, so the same cause groups across seeds."""
    return _COLOUR.sub("<colour>", _NUMBER.sub("#", text))


def grouped_reasons(runs: list[dict]) -> list[tuple[int, str, list[int]]]:
    """(count, reason, seeds) for every job failure and every point the judge withheld in a run without full
    points, most frequent first."""
    counts: Counter[str] = Counter()
    seeds: dict[str, list[int]] = defaultdict(list)
    for run in runs:
        reasons = list(run["failures"])
        if not run.get("full"):
            reasons += [f"judge: {rule['rule']}: {rule['detail']}" for rule in run["breakdown"] if rule["points"] == 0]
        for reason in reasons:
            key = reason_key(reason)
            counts[key] += 1
            if run["seed"] not in seeds[key]:
                seeds[key].append(run["seed"])
    return [(count, key, seeds[key]) for key, count in counts.most_common()]


def tower_blocks(run: dict) -> int | None:
    """to_the_sky: blocks in the tallest column, from the judge's tower rule."""
    rules = [rule for rule in run["breakdown"] if rule["rule"] == "tower"]
    return len(rules[0]["object_ids"]) if rules else None


def interval(values) -> str:
    """A 95 % interval as "[low, high]" in per cent."""
    return "" if not values else f"[{100 * values[0]:.1f}, {100 * values[1]:.1f}]"


def mark(met: bool) -> str:
    return "met" if met else "MISSED"


def percent(value) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def seconds(value, digits: int = 1) -> str:
    return "-" if value is None else f"{value:.{digits}f} s"


def run_cell(cell: Cell, seeds: list[int], workers: int, ray_address: str | None, realism: str | None = None,
             arm_calibration: bool = True, pick_check: bool | None = None) -> None:
    reason = episode_unsupported(cell.job, cell.level, cell.workcell)
    if reason:
        cell.skipped = f"not run: {reason}"
        return
    cell.started_utc = now_utc()
    for run in evaluate(cell.job, cell.level, seeds, workers=workers, ray_address=ray_address, workcell=cell.workcell,
                        realism=realism, arm_calibration=arm_calibration, pick_check=pick_check):
        cell.runs.append(run)
        print(".", end="", flush=True)


def print_row(cell: Cell) -> None:
    if cell.skipped:
        print(f"{cell.name:<28} {cell.skipped}")
        return
    s = summarize(cell.runs)
    rtf = "-" if s["realtime_factor_per_worker"] is None else f"{s['realtime_factor_per_worker']:.1f}x"
    rtf_cpu = "-" if s["realtime_factor_per_cpu_s"] is None else f"{s['realtime_factor_per_cpu_s']:.1f}x"
    notes = []
    key = (cell.job, cell.level)
    targets = {**FULL_RATE_TARGETS, **WORKCELL_FULL_RATE_TARGETS}
    if key in targets and not (key in FULL_RATE_TARGETS and cell.workcell != DEFAULT_WORKCELL):
        notes.append(f"full >= {100 * targets[key]:.0f} %: {mark(s['full_rate'] >= targets[key])}")
    if key in SIM_TIME_TARGETS_S and s["mean_sim_time_s"] is not None:
        notes.append(f"sim <= {SIM_TIME_TARGETS_S[key]:.0f} s: {mark(s['mean_sim_time_s'] <= SIM_TIME_TARGETS_S[key])}")
    if cell.job == "to_the_sky":
        towers = [tower_blocks(run) for run in cell.runs]
        known = [t for t in towers if t is not None]
        if known:
            mean_tower = sum(known) / len(known)
            notes.append(f"tower mean {mean_tower:.1f} (min {min(known)}) blocks, >= {TOWER_TARGET_BLOCKS:.0f}: "
                         f"{mark(mean_tower >= TOWER_TARGET_BLOCKS)}")
    if s["crashed"]:
        notes.append(f"{s['crashed']} crashed")
    print(f"{cell.name:<28} {s['runs']:>4}  {percent(s['mean_points_fraction']):>8} {interval(s['mean_points_ci95']):>14}  "
          f"{percent(s['min_points_fraction']):>8}  {percent(s['full_rate']):>8} {interval(s['full_points_ci95']):>14}  "
          f"{seconds(s['mean_sim_time_s']):>8}  {seconds(s['mean_wall_time_s'], 2):>8}  "
          f"{rtf:>6}  {rtf_cpu:>7}  {'; '.join(notes)}")


def print_reasons(cells: list[Cell]) -> None:
    print("\nreasons (job failures, and the judge's zero-point rules in runs without full points):")
    any_reason = False
    for cell in cells:
        reasons = grouped_reasons(cell.runs)
        if not reasons:
            continue
        any_reason = True
        print(f"  {cell.name}:")
        for count, reason, seeds in reasons:
            print(f"    {count:>3}x  {reason}   (seeds {', '.join(map(str, seeds))})")
    if not any_reason:
        print("  none")


def print_targets(cells: dict[tuple[str, str, int | None], Cell], all_runs: list[dict], workcells: list[str]) -> None:
    print("\ntargets:")

    def cell_or_reason(key, workcell=DEFAULT_WORKCELL):
        cell = cells.get((workcell, *key))
        if cell is None:
            if key[0] not in JOBS:
                return None, "not in armlab.tasks.JOBS yet"
            return None, "not in this run (--workcells)" if workcell not in workcells else "not in this run (--jobs, --levels)"
        return (None, cell.skipped) if cell.skipped else (cell, "")

    for key, target in FULL_RATE_TARGETS.items():
        cell, why = cell_or_reason(key)
        label = f"{key[0]} L{key[1]} full points within the limit >= {100 * target:.0f} %"
        if cell is None:
            print(f"  {label:<66} {why}")
        else:
            s = summarize(cell.runs)
            rate = s["full_rate"]
            print(f"  {label:<66} {percent(rate):>8}  {mark(rate >= target)}   95 % interval {interval(s['full_points_ci95'])} "
                  f"over {s['runs']} seeds")
    for key, target_s in SIM_TIME_TARGETS_S.items():
        cell, why = cell_or_reason(key)
        label = f"{key[0]} L{key[1]} mean simulated time <= {target_s:.0f} s"
        if cell is None:
            print(f"  {label:<66} {why}")
        else:
            mean_s = summarize(cell.runs)["mean_sim_time_s"]
            print(f"  {label:<66} {seconds(mean_s):>8}  {mark(mean_s is not None and mean_s <= target_s)}")
    cell, why = cell_or_reason(("to_the_sky", 1))
    label = f"to_the_sky blocks in the tallest tower >= {TOWER_TARGET_BLOCKS:.0f} (mean)"
    if cell is None:
        print(f"  {label:<66} {why}")
    else:
        towers = [t for t in map(tower_blocks, cell.runs) if t is not None]
        mean_tower = sum(towers) / len(towers) if towers else None
        figure = "-" if mean_tower is None else f"{mean_tower:.1f}"
        print(f"  {label:<66} {figure:>8}  {mark(mean_tower is not None and mean_tower >= TOWER_TARGET_BLOCKS)}")
    summary = summarize(all_runs) if all_runs else {}
    rtf, rtf_cpu = summary.get("realtime_factor_per_worker"), summary.get("realtime_factor_per_cpu_s")
    label = f"eval real-time factor per worker >= {REALTIME_TARGET:.0f}x (all runs)"
    print(f"  {label:<66} {'-' if rtf is None else f'{rtf:.1f}x':>8}  {mark(rtf is not None and rtf >= REALTIME_TARGET)}"
          f"   (per CPU second: {'-' if rtf_cpu is None else f'{rtf_cpu:.1f}x'}, which other load does not lower)")
    for workcell in workcells:
        for job in LEVELLESS_JOBS:
            if job in JOBS and JOBS[job].levels:
                continue  # judged per level above (e.g. sort_by_tag L1-L3)
            cell, why = cell_or_reason((job, None), workcell)
            label = f"{job} success rate on random scenes (full points or no failure)" + (
                "" if workcell == DEFAULT_WORKCELL else f" @{workcell}")
            if cell is None:
                print(f"  {label:<66} {why}")
            else:
                print(f"  {label:<66} {percent(success_rate(cell.runs)):>8}")
    print("\nissue 12 (the UR3 write-up's jobs) on each workcell: full points rate, mean simulated time")
    for workcell in workcells:
        for key, target in WORKCELL_FULL_RATE_TARGETS.items():
            cell, why = cell_or_reason(key, workcell)
            label = f"{key[0]}{'' if key[1] is None else f' L{key[1]}'} @{workcell} full points >= {100 * target:.0f} %"
            if cell is None:
                print(f"  {label:<66} {why}")
            else:
                s = summarize(cell.runs)
                print(f"  {label:<66} {percent(s['full_rate']):>8}  {mark(s['full_rate'] >= target)}   "
                      f"95 % interval {interval(s['full_points_ci95'])}, mean sim {seconds(s['mean_sim_time_s'])} over "
                      f"{s['runs']} seeds")


def success_rate(runs: list[dict]) -> float | None:
    """A job without levels succeeds when it earns full points (if judged) or ends without failures."""
    if not runs:
        return None
    ok = [bool(run.get("full")) if run.get("max_points") else not run["failures"] for run in runs]
    return sum(ok) / len(ok)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default=DEFAULT_SEEDS, help=f"seeds for every (job, level) (default {DEFAULT_SEEDS})")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--ray", metavar="ADDRESS", help="run on a Ray cluster instead of local processes")
    parser.add_argument("--jobs", help="comma-separated job names (default: every job in armlab.tasks.JOBS)")
    parser.add_argument("--levels", help="comma-separated levels run for jobs that have them (default: all)")
    parser.add_argument("--realism", choices=("real", "camera", "ideal"), default=None,
                        help="real (the camera's and the arm's imperfections), camera (the camera's only) or ideal "
                             "(default: config/sim.yaml `realism`)")
    parser.add_argument("--no-arm-calibration", action="store_true",
                        help="on the real arm, run the jobs without calibrating the arm from the camera first (issue 19's "
                             "table beside the calibrated run)")
    parser.add_argument("--pick-check", choices=("on", "off"), default=None,
                        help="the closed loop before each pick's last descent (armlab.skills.pick_check; it runs on an arm "
                             "calibrated from the camera) on or off (default: StationConfig's pick_check)")
    parser.add_argument("--workcells", default=DEFAULT_WORKCELL,
                        help=f"comma-separated workcells (config/workcells; default {DEFAULT_WORKCELL}): each job runs on each")
    parser.add_argument("--json-out", metavar="FILE",
                        help="write every (job, level)'s runs, summary and record to FILE (for armlab eval --compare)")
    args = parser.parse_args()
    try:
        seeds = parse_seeds(args.seeds)
    except EvalError as error:
        print(f"competition: {error}", file=sys.stderr)
        return 2
    names = list(JOBS) if args.jobs is None else [name.strip() for name in args.jobs.split(",")]
    unknown = [name for name in names if name not in JOBS]
    if unknown:
        print(f"competition: unknown job(s) {', '.join(unknown)}; jobs: {', '.join(JOBS)}", file=sys.stderr)
        return 2
    workcells = [name.strip() for name in args.workcells.split(",")]
    unknown = [name for name in workcells if name not in known_workcells()]
    if unknown:
        print(f"competition: unknown workcell(s) {', '.join(unknown)}; workcells: {', '.join(known_workcells())}", file=sys.stderr)
        return 2
    try:
        levels = None if args.levels is None else {int(level) for level in args.levels.split(",")}
    except ValueError:
        print(f"competition: --levels takes comma-separated integers, not {args.levels!r}", file=sys.stderr)
        return 2
    if args.json_out and not os.path.isdir(os.path.dirname(os.path.abspath(args.json_out))):
        print(f"competition: --json-out {args.json_out}: no such folder", file=sys.stderr)
        return 2
    where = f"Ray cluster {args.ray}" if args.ray else f"{args.workers} worker process(es)"
    print(f"seeds ({len(seeds)}): {', '.join(map(str, seeds))}")
    print(f"jobs in armlab.tasks.JOBS: {', '.join(f'{n} L{min(s.levels)}-{max(s.levels)}' if s.levels else n for n, s in JOBS.items())}")
    print(f"workcells: {', '.join(workcells)}; realism: {args.realism or 'config/sim.yaml'}"
          + ("; arm calibration OFF" if args.no_arm_calibration else "")
          + (f"; pick check {args.pick_check}" if args.pick_check else ""))
    print(f"running on {where}; one dot per run", flush=True)

    cells: dict[tuple[str, str, int | None], Cell] = {}
    load_start = os.getloadavg()[0]
    started = time.monotonic()
    for workcell in workcells:
        for name in names:
            for level in [lv for lv in JOBS[name].levels if levels is None or lv in levels] or (None,):
                if level is None and JOBS[name].levels:
                    continue  # none of its levels asked for
                cell = cells[(workcell, name, level)] = Cell(name, level, workcell=workcell)
                print(f"{cell.name}: ", end="", flush=True)
                run_cell(cell, seeds, args.workers, args.ray, args.realism, not args.no_arm_calibration,
                         None if args.pick_check is None else args.pick_check == "on")
                print(f" {cell.skipped or 'done'}", flush=True)
    elapsed_s = time.monotonic() - started

    print(f"\n{'job':<28} {'runs':>4}  {'mean pts':>8} {'95 % interval':>14}  {'min pts':>8}  {'full':>8} "
          f"{'95 % interval':>14}  {'mean sim':>8}  "
          f"{'wall/run':>8}  {'rtf':>6}  {'rtf cpu':>7}  targets")
    for cell in cells.values():
        print_row(cell)
    print_reasons(list(cells.values()))
    all_runs = [run for cell in cells.values() for run in cell.runs]
    print_targets(cells, all_runs, workcells)
    print(f"\n{len(all_runs)} runs in {elapsed_s:.0f} s wall on {where}; load average (1 min) "
          f"{load_start:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, on {os.cpu_count()} CPUs")
    print("intervals: full points = Wilson score 95 %; mean points = percentile bootstrap 95 %, 2000 resamples, seed 0")
    if args.json_out:
        write_cells(args.json_out, [cell for cell in cells.values() if not cell.skipped], args.realism)
        print(f"runs, summaries and records written to {args.json_out} (armlab eval --compare reads it)")
    return 0


def write_cells(path: str, cells: list[Cell], realism: str | None) -> None:
    """{"cells": [{"runs", "summary", "record"}, ...]}: one `armlab eval --json` output per (job, level)."""
    out = [{"runs": [public_run(run) for run in cell.runs], "summary": summarize(cell.runs),
            "record": run_record(cell.job, cell.level, [run["seed"] for run in cell.runs], workcell=cell.workcell,
                                 realism_requested=realism, runs=cell.runs, started_utc=cell.started_utc)}
           for cell in cells]
    with open(path, "w") as file:
        json.dump({"cells": out}, file)


if __name__ == "__main__":
    sys.exit(main())
