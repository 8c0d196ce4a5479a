"""`armlab eval`: run an autonomous job headless over many seeds (serially, over a process pool or a Ray
cluster) and print each run's judged score and a summary; `--json` for machines, `--truth-out` for
each run's final ground truth."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

PROG = "armlab eval"


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "eval", help="run a job headless over seeds and score each run with the judge",
        description="Run an autonomous job headless in the simulation's fast mode, once per seed, and score "
                    "every run with the competition judge. Results are identical however the seeds are spread.")
    parser.add_argument("event", help="job name, e.g. pick_sort (see armlab.tasks.JOBS)")
    parser.add_argument("--level", help="the job's level (required for jobs that have levels)")
    parser.add_argument("--workcell", default=None,
                        help="workcell (config/workcells/<name>.yaml: arm, gripper, board, places); default rx200_armlab")
    parser.add_argument("--seeds", required=True, help="seeds: 1,2,3 or 1-20 or a mix (0-9,42); at most 10000")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", default="1", help="processes running seeds in parallel (default 1: this process)")
    where.add_argument("--ray", metavar="ADDRESS", help="run the seeds as tasks on a Ray cluster: auto or host:port "
                                                      "(needs the cluster extra: pip install 'armlab[cluster]')")
    parser.add_argument("--realism", choices=("real", "camera", "ideal"), default=None,
                        help="real: the simulated camera and arm with a real one's imperfections (the RX200's droop, backlash, "
                             "encoder counts, rig offsets); camera: the real camera with the exact arm; ideal: exact. Default: config/sim.yaml `realism`")
    parser.add_argument("--no-arm-calibration", action="store_true",
                        help="with --realism real: skip calibrating the arm from the camera before the job's clock starts")
    parser.add_argument("--truth-out", type=Path, metavar="DIR",
                        help="write each run's final ground truth (+ gripper_path_m) to DIR/<seed>.json")
    parser.add_argument("--json", action="store_true", help='print {"runs": [...], "summary": {...}} only')
    parser.set_defaults(func=run_eval)


def _int_option(name: str, text: str | None) -> int | None:
    if text is None:
        return None
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"{name} must be an integer, not {text!r}") from None


def run_eval(args: argparse.Namespace) -> int:
    from armlab.tasks.evaluate import (
        EvalError,
        check_request,
        evaluate,
        parse_seeds,
        public_run,
        summarize,
    )

    try:
        level = check_request(args.event, _int_option("--level", args.level), args.workcell)
        seeds = parse_seeds(args.seeds)
        workers = _int_option("--workers", args.workers)
        runs_iter = evaluate(args.event, level, seeds, workers=workers, ray_address=args.ray,
                             keep_truth=args.truth_out is not None, workcell=args.workcell, realism=args.realism,
                             arm_calibration=not args.no_arm_calibration)
        if args.truth_out is not None:
            if args.truth_out.exists() and not args.truth_out.is_dir():
                raise EvalError(f"--truth-out {args.truth_out} exists and is not a directory")
            args.truth_out.mkdir(parents=True, exist_ok=True)
    except (EvalError, ValueError, OSError) as error:
        print(f"{PROG}: {error}", file=sys.stderr)
        return 2
    if not args.json:
        backend = f"Ray cluster {args.ray}" if args.ray else f"{workers} worker process(es)" if workers > 1 else "this process"
        print(f"{args.event}" + (f" L{level}" if level is not None else "") +
              (f" on workcell {args.workcell}" if args.workcell else "") +
              (f" ({args.realism} simulation)" if args.realism else "") + f": {len(seeds)} seed(s) {_seed_text(seeds)} on {backend}", flush=True)
    started = time.monotonic()
    runs = []
    try:
        for run in runs_iter:
            truth = run.pop("truth", None)
            if args.truth_out is not None and truth is not None:
                (args.truth_out / f"{run['seed']}.json").write_text(json.dumps(truth))
            runs.append(run)
            if not args.json:
                print_run(run)
    except EvalError as error:  # e.g. Ray missing, found only when the first run is asked for
        print(f"{PROG}: {error}", file=sys.stderr)
        return 2
    except ConnectionError as error:
        print(f"{PROG}: cannot reach the Ray cluster at {args.ray}: {error}", file=sys.stderr)
        return 1
    summary = summarize(runs)
    summary["elapsed_wall_s"] = round(time.monotonic() - started, 3)
    if args.json:
        print(json.dumps({"runs": [public_run(run) for run in runs], "summary": summary}))
    else:
        print_summary(summary)
    return 1 if summary["crashed"] else 0


def _seed_text(seeds: list[int]) -> str:
    """Seeds as ranges: [0, 1, 2, 5] -> "0-2,5"."""
    parts, start = [], 0
    for i in range(1, len(seeds) + 1):
        if i == len(seeds) or seeds[i] != seeds[i - 1] + 1:
            first, last = seeds[start], seeds[i - 1]
            parts.append(str(first) if first == last else f"{first}-{last}")
            start = i
    return ",".join(parts)


def print_run(run: dict) -> None:
    """One run: points, maximum, simulated and wall time, the judge's breakdown and the failures."""
    if run.get("crashed"):
        print(f"seed {run['seed']}: CRASHED after {run['wall_time_s']:.2f} s wall: {run['failures'][-1]}", flush=True)
        return
    verdict = "full points" if run.get("full") else ("within the limit" if run.get("within_limit") else "OVER the time limit")
    rtf = run["sim_time_s"] / run["wall_time_s"] if run["wall_time_s"] > 0 else float("inf")
    print(f"seed {run['seed']}: {run['points']}/{run['max_points']} points ({verdict}), "
          f"sim {run['sim_time_s']:.1f} s, wall {run['wall_time_s']:.2f} s ({rtf:.1f}x real time)")
    for rule in run["breakdown"]:
        ids = ",".join(rule.get("object_ids") or [])
        print(f"    {rule['rule']:<11} {rule['points']:>+5}  {ids + '  ' if ids else ''}{rule['detail']}")
    for failure in run["failures"]:
        print(f"    failure: {failure}")
    sys.stdout.flush()


def print_summary(summary: dict) -> None:
    def figure(value, unit="", scale=1.0, digits=1):
        return "-" if value is None else f"{value * scale:.{digits}f}{unit}"

    print(f"summary over {summary['runs']} run(s)" + (f", {summary['crashed']} crashed" if summary["crashed"] else "") + ":")
    print(f"  points: mean {figure(summary['mean_points_fraction'], ' %', 100)} of the maximum, "
          f"min {figure(summary['min_points_fraction'], ' %', 100)}")
    print(f"  full points within the time limit: {figure(summary['full_rate'], ' %', 100)} of runs")
    print(f"  simulated time: mean {figure(summary['mean_sim_time_s'], ' s')}; wall time: mean "
          f"{figure(summary['mean_wall_time_s'], ' s', digits=2)} per run; real-time factor per worker "
          f"{figure(summary['realtime_factor_per_worker'], 'x')} ({figure(summary['realtime_factor_per_cpu_s'], 'x')} "
          f"per CPU second); elapsed {summary['elapsed_wall_s']:.1f} s")
