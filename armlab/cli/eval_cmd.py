"""`armlab eval`: run an autonomous job headless over many seeds (serially, over a process pool or a Ray
cluster) and print each run's judged score and a summary with 95 % intervals; `--json` for machines, `--out`
to keep the results with their record (commit, config hash, seeds, realism), `--truth-out` for each run's
final ground truth, `--until-ci` to add seeds until the full-points interval is narrow enough, and
`--compare A.json B.json` to say whether two evaluations differ beyond chance."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

PROG = "armlab eval"
# The help's figures; armlab.tasks.evaluate (imported only when the command runs) holds the values used.
MAX_SEEDS_HELP, UNTIL_CI_MAX_SEEDS_HELP, UNTIL_CI_BATCH_SEEDS_HELP = 10_000, 1000, 20


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "eval", help="run a job headless over seeds and score each run with the judge",
        description="Run an autonomous job headless in the simulation's fast mode, once per seed, and score "
                    "every run with the competition judge. Results are identical however the seeds are spread.")
    parser.add_argument("event", nargs="?", help="job name, e.g. pick_sort (see armlab.tasks.JOBS)")
    parser.add_argument("--level", help="the job's level (required for jobs that have levels)")
    parser.add_argument("--workcell", default=None,
                        help="workcell (config/workcells/<name>.yaml: arm, gripper, board, places); default rx200_armlab")
    parser.add_argument("--seeds", help="seeds: 1,2,3 or 1-20 or a mix (0-9,42); at most 10000 (with --until-ci: the first batch)")
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
    parser.add_argument("--record", type=Path, metavar="DIR",
                        help="record each run (calibration and job: joints, gripper, transforms, camera, detections, events) "
                             "to an MCAP file in DIR (open it in Foxglove)")
    parser.add_argument("--json", action="store_true", help='print {"runs": [...], "summary": {...}, "record": {...}} only')
    parser.add_argument("--out", type=Path, metavar="FILE",
                        help="also write the --json output (runs, summary with intervals, record) to FILE")
    parser.add_argument("--until-ci", type=ci_width, metavar="WIDTH",
                        help="after --seeds, add seeds in batches until the full-points rate's Wilson 95 %% interval is at "
                             "most WIDTH wide (a fraction in (0, 1], e.g. 0.1), or --max-seeds have run")
    parser.add_argument("--max-seeds", type=positive_int, metavar="N",
                        help=f"with --until-ci: run at most N seeds in all (default {UNTIL_CI_MAX_SEEDS_HELP})")
    parser.add_argument("--batch-seeds", type=positive_int, metavar="N",
                        help=f"with --until-ci: seeds added per batch, the next ones after the largest run (default {UNTIL_CI_BATCH_SEEDS_HELP})")
    parser.add_argument("--compare", nargs=2, type=Path, metavar=("A.json", "B.json"),
                        help="compare two saved evaluations (--json or --out files) per job and level: do they differ "
                             "beyond chance? Runs nothing; exits 0 whatever the answer")
    parser.set_defaults(func=run_eval, parser=parser)


def ci_width(text: str) -> float:
    """--until-ci's width: a fraction in (0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"the interval width must be a number in (0, 1], not {text!r}") from None
    if not 0.0 < value <= 1.0:  # also refuses nan
        raise argparse.ArgumentTypeError(f"the interval width must be a fraction in (0, 1] (0.1 = 10 percentage points), "
                                         f"not {text}")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, not {text!r}") from None
    if not 1 <= value <= MAX_SEEDS_HELP:
        raise argparse.ArgumentTypeError(f"expected an integer in 1..{MAX_SEEDS_HELP}, not {text}")
    return value


def check_arguments(args: argparse.Namespace) -> None:
    """argparse errors (usage, exit 2) for options that do not go together."""
    parser = args.parser
    if args.compare:
        given = [name for name, value in (("a job", args.event), ("--seeds", args.seeds), ("--until-ci", args.until_ci),
                                          ("--out", args.out), ("--truth-out", args.truth_out),
                                          ("--record", args.record)) if value is not None]
        if given:
            parser.error(f"--compare runs nothing: leave out {', '.join(given)}")
        return
    if args.event is None or args.seeds is None:
        parser.error("give a job and --seeds (or --compare A.json B.json)")
    if args.until_ci is None:
        extra = [name for name, value in (("--max-seeds", args.max_seeds), ("--batch-seeds", args.batch_seeds)) if value is not None]
        if extra:
            parser.error(f"{' and '.join(extra)} only with --until-ci")


def _int_option(name: str, text: str | None) -> int | None:
    if text is None:
        return None
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"{name} must be an integer, not {text!r}") from None


def run_eval(args: argparse.Namespace) -> int:
    check_arguments(args)
    if args.compare:
        return run_compare(args)
    from armlab.tasks.evaluate import (
        UNTIL_CI_BATCH_SEEDS,
        UNTIL_CI_MAX_SEEDS,
        EvalError,
        UntilCi,
        check_request,
        evaluate,
        parse_seeds,
        public_run,
        seed_text,
        summarize,
    )
    from armlab.tasks.run_record import now_utc, run_record

    started_utc = now_utc()
    until = None
    try:
        level = check_request(args.event, _int_option("--level", args.level), args.workcell)
        seeds = parse_seeds(args.seeds)
        workers = _int_option("--workers", args.workers)

        def run_seeds(batch: list[int]):
            return evaluate(args.event, level, batch, workers=workers, ray_address=args.ray,
                            keep_truth=args.truth_out is not None, workcell=args.workcell, realism=args.realism,
                            arm_calibration=not args.no_arm_calibration,
                            record_dir=None if args.record is None else str(args.record.resolve()))

        if args.until_ci is not None:
            until = UntilCi(run_seeds, seeds, args.until_ci, max_seeds=args.max_seeds or UNTIL_CI_MAX_SEEDS,
                            batch_seeds=args.batch_seeds or UNTIL_CI_BATCH_SEEDS,
                            on_batch=None if args.json else print_batch)
            runs_iter = until.runs()
        else:
            runs_iter = run_seeds(seeds)
        if args.record is not None:
            if args.record.exists() and not args.record.is_dir():
                raise EvalError(f"--record {args.record} exists and is not a directory")
            args.record.mkdir(parents=True, exist_ok=True)
        if args.truth_out is not None:
            if args.truth_out.exists() and not args.truth_out.is_dir():
                raise EvalError(f"--truth-out {args.truth_out} exists and is not a directory")
            args.truth_out.mkdir(parents=True, exist_ok=True)
        if args.out is not None:
            if args.out.is_dir():
                raise EvalError(f"--out {args.out} is a directory; give a file")
            args.out.parent.mkdir(parents=True, exist_ok=True)
    except (EvalError, ValueError, OSError) as error:
        print(f"{PROG}: {error}", file=sys.stderr)
        return 2
    if not args.json:
        backend = f"Ray cluster {args.ray}" if args.ray else f"{workers} worker process(es)" if workers > 1 else "this process"
        more = "" if until is None else (f", then {until.batch_seeds} more at a time until the full-points interval is at most "
                                         f"{100 * until.width:.1f} percentage points wide (at most {until.max_seeds} seeds)")
        print(f"{args.event}" + (f" L{level}" if level is not None else "") +
              (f" on workcell {args.workcell}" if args.workcell else "") +
              (f" ({args.realism} simulation)" if args.realism else "") +
              f": {len(seeds)} seed(s) {seed_text(seeds)}{more} on {backend}", flush=True)
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
    if until is not None:
        summary["until_ci"] = until.status()
    record = run_record(args.event, level, [run["seed"] for run in runs], workcell=args.workcell,
                        realism_requested=args.realism, runs=runs, arm_calibration=not args.no_arm_calibration,
                        started_utc=started_utc)
    output = {"runs": [public_run(run) for run in runs], "summary": summary, "record": record}
    if args.out is not None:
        try:
            partial = args.out.with_name(args.out.name + ".partial")
            partial.write_text(json.dumps(output) + "\n")
            partial.replace(args.out)
        except OSError as error:
            print(f"{PROG}: cannot write --out {args.out}: {error}", file=sys.stderr)
            return 2
    if args.json:
        print(json.dumps(output))
    else:
        print_summary(summary, record)
        if args.out is not None:
            print(f"results and record written to {args.out}")
    return 1 if summary["crashed"] else 0


def run_compare(args: argparse.Namespace) -> int:
    """--compare A B: a verdict per job and level in both files; 0 whatever it says, 2 for an unusable file."""
    from armlab.tasks.compare import CompareError, compare_cells, comparison_lines, load_cells

    path_a, path_b = args.compare
    try:
        cells_a, cells_b = load_cells(path_a), load_cells(path_b)
    except CompareError as error:
        print(f"{PROG}: --compare: {error}", file=sys.stderr)
        return 2
    result = compare_cells(cells_a, cells_b)
    if not result["comparisons"]:
        print(f"{PROG}: --compare: {path_a} and {path_b} have no job and level in common "
              f"(A: {', '.join(result['only_in_a'])}; B: {', '.join(result['only_in_b'])})", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result))
    else:
        print("\n".join(comparison_lines(result, path_a, path_b, cells_a, cells_b)))
    return 0


def print_batch(status: dict) -> None:
    """--until-ci after each batch: the interval so far and what happens next."""
    low, high = status["full_points_ci95"]
    line = (f"after {status['seeds_run']} seed(s): full points {status['full_points_runs']}/{status['seeds_run']}, "
            f"95 % interval [{100 * low:.1f}, {100 * high:.1f}] % is {100 * status['width']:.1f} points wide "
            f"(wanted <= {100 * status['width_wanted']:.1f})")
    stopped = status["stopped_by"]
    if stopped == "width":
        line += ": narrow enough, done"
    elif stopped == "max_seeds":
        line += f": STOPPED by the bound --max-seeds {status['max_seeds']} before the interval was narrow enough"
    elif stopped == "seed_range":
        line += ": STOPPED: no seeds left below 2^32"
    else:
        line += ": adding seeds"
    print(line, flush=True)


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
    if run.get("recording"):
        print(f"    recording: {run['recording']}")
    sys.stdout.flush()


def print_summary(summary: dict, record: dict | None = None) -> None:
    def figure(value, unit="", scale=1.0, digits=1):
        return "-" if value is None else f"{value * scale:.{digits}f}{unit}"

    def interval(values) -> str:
        return "" if not values else f" (95 % interval {100 * values[0]:.1f}-{100 * values[1]:.1f} %)"

    print(f"summary over {summary['runs']} run(s)" + (f", {summary['crashed']} crashed" if summary["crashed"] else "") + ":")
    print(f"  points: mean {figure(summary['mean_points_fraction'], ' %', 100)} of the maximum"
          f"{interval(summary['mean_points_ci95'])}, min {figure(summary['min_points_fraction'], ' %', 100)}")
    print(f"  full points within the time limit: {summary['full_points_runs']}/{summary['runs']} = "
          f"{figure(summary['full_points_rate'], ' %', 100)} of runs{interval(summary['full_points_ci95'])}")
    print(f"  intervals: full points {summary['intervals']['full_points_ci95']}; mean points "
          f"{summary['intervals']['mean_points_ci95']}")
    until = summary.get("until_ci")
    if until is not None:
        why = {"width": "the full-points interval is narrow enough",
               "max_seeds": f"STOPPED BY THE BOUND (--max-seeds {until['max_seeds']}) with the interval wider than wanted",
               "seed_range": "no seeds left"}[until["stopped_by"]]
        print(f"  --until-ci {until['width_wanted']}: {until['seeds_run']} seeds in {until['batches']} batch(es); "
              f"interval {100 * until['width']:.1f} points wide; {why}")
    print(f"  simulated time: mean {figure(summary['mean_sim_time_s'], ' s')}; wall time: mean "
          f"{figure(summary['mean_wall_time_s'], ' s', digits=2)} per run; real-time factor per worker "
          f"{figure(summary['realtime_factor_per_worker'], 'x')} ({figure(summary['realtime_factor_per_cpu_s'], 'x')} "
          f"per CPU second); elapsed {summary['elapsed_wall_s']:.1f} s")
    if record is not None:
        git = record.get("git") or {}
        commit = (git["commit"][:10] + (" + uncommitted changes" if git.get("dirty") else "")) if git.get("commit") else "unknown"
        print(f"  record: commit {commit}, config {record['config_sha256'][:12]} ({record['config_files']} files in "
              f"{record['config_dir']}), realism {record['realism'] or '-'}, workcell {record['workcell']}")
