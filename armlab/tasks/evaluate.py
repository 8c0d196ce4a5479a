"""Fan-out of headless episodes over seeds: serially, over a process pool, or over a Ray cluster.

Pure orchestration around `armlab.tasks.episode.run_episode`: every seed runs the same function with
the same arguments wherever it runs, so the results equal a serial run's apart from wall time. Runs
come back in seed order. A run that raises is recorded as crashed (no points) instead of ending the
evaluation, so one bad seed among thousands still leaves the other results.
"""

from __future__ import annotations

import os
import re
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Sequence

from armlab.errors import ConfigError, InvalidInput
from armlab.tasks.episode import episode_scene, run_episode
from armlab.tasks.judge import EVENT_LIMITS_S
from armlab.tasks.registry import JOBS, JobUnsupported, check_supported, checked_request
from armlab.tasks.run_record import seed_text  # noqa: F401 - armlab eval's import
from armlab.tasks.scorers import SCORED_JOBS
from armlab.tasks.stats import BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, bootstrap_mean_interval, wilson_interval
from armlab.workcell import load_workcell

MAX_SEEDS = 10_000  # per evaluation; a larger sweep is several evaluations
MAX_SEED = 2**32 - 1  # seeds are unsigned 32-bit, like most simulators' seeds
MAX_WORKERS = 256
UNTIL_CI_MAX_SEEDS = 1000  # --until-ci's default bound on the seeds run
UNTIL_CI_BATCH_SEEDS = 20  # --until-ci's default seeds added per batch
RUN_KEYS = ("event", "level", "seed", "points", "max_points", "sim_time_s", "wall_time_s", "breakdown", "failures")
_SEED_ITEM = re.compile(r"(\d+)(?:-(\d+))?")


class EvalError(InvalidInput):
    """A bad evaluation request (event, level, seeds, workers); the message says what is wrong."""


def parse_seeds(text: str) -> list[int]:
    """Seeds from "1,2,3", "1-20" or a mix ("0-4,9"): sorted, distinct, non-negative, at most MAX_SEEDS.
    EvalError for anything else (empty items, backwards ranges, signs, letters, repeats)."""
    if not isinstance(text, str) or not text.strip():
        raise EvalError("empty seed list; give seeds like 1,2,3 or 1-20")
    seeds: list[int] = []
    count = 0
    for item in text.split(","):
        item = item.strip()
        match = _SEED_ITEM.fullmatch(item)
        if match is None:
            what = "an empty item" if not item else f"{item!r}"
            raise EvalError(f"bad seed list {text!r}: {what} is not a seed (N) or a range (N-M) of non-negative integers")
        first = int(match.group(1))
        last = first if match.group(2) is None else int(match.group(2))
        if last < first:
            raise EvalError(f"bad seed list {text!r}: range {item} runs backwards")
        if last > MAX_SEED:
            raise EvalError(f"bad seed list {text!r}: seeds go up to {MAX_SEED}, not {last}")
        count += last - first + 1
        if count > MAX_SEEDS:
            raise EvalError(f"bad seed list {text!r}: more than {MAX_SEEDS} seeds in one evaluation")
        seeds.extend(range(first, last + 1))
    seeds.sort()
    repeated = next((a for a, b in zip(seeds, seeds[1:]) if a == b), None)
    if repeated is not None:
        raise EvalError(f"bad seed list {text!r}: seed {repeated} given more than once")
    return seeds


def check_request(event: str, level: int | None, workcell: str | None = None) -> int | None:
    """The level to run `event` at; EvalError for an unknown job or workcell, a missing or out-of-range
    level, or a job the headless episode cannot run yet (no scene generator or judge for it)."""
    if event in JOBS and JOBS[event].levels and level is None:
        levels = ", ".join(map(str, JOBS[event].levels))
        raise EvalError(f"job '{event}' has levels {levels}; give --level")
    try:
        _, level, _ = checked_request(event, level, None)
    except ValueError as error:
        raise EvalError(str(error)) from None
    if workcell is not None:
        try:
            load_workcell(workcell).check_arm_fits()
        except ConfigError as error:
            raise EvalError(str(error)) from None

    try:
        check_supported(event, workcell)
    except JobUnsupported as error:
        raise EvalError(str(error)) from None
    reason = episode_unsupported(event, level, workcell)
    if reason:
        raise EvalError(f"job '{event}' cannot be evaluated headless yet: {reason}")
    return level


def episode_unsupported(event: str, level: int | None, workcell: str | None = None) -> str | None:
    """Why a headless episode of (event, level) cannot run yet, or None when it can: the episode needs a
    scene generator for the pair and a judge for the event. Cheap (generates one scene, judges nothing)."""
    try:
        episode_scene(event, level, 0, workcell)
    except (ValueError, TypeError) as error:
        return f"no scene generator ({error})"
    if event not in EVENT_LIMITS_S and event not in SCORED_JOBS:
        return "neither the judge nor armlab.tasks.scorers scores it"
    return None


def run_one(event: str, level: int | None, seed: int, keep_truth: bool = False, workcell: str | None = None,
            realism: str | None = None, arm_calibration: bool = True, record_dir: str | None = None,
            pick_check: bool | None = None) -> dict:
    """One episode, in whichever process runs it; an exception becomes a crashed run with no points."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    started, cpu_started = time.monotonic(), time.process_time()
    try:
        result = run_episode(event, level, seed, keep_truth=keep_truth, workcell=workcell, realism=realism,
                             arm_calibration=arm_calibration, record_dir=record_dir, pick_check=pick_check)
        # CPU seconds of this process (all its threads): a speed figure that other load on the machine
        # does not inflate, unlike wall time.
        result["cpu_time_s"] = round(time.process_time() - cpu_started, 3)
        return result
    except Exception as error:  # noqa: BLE001 - any failure of one seed is that seed's result
        where = traceback.extract_tb(error.__traceback__)[-1]
        return {
            "event": event, "level": level, "seed": int(seed), "workcell": workcell, "points": 0, "max_points": None,
            "within_limit": False, "full": False, "sim_time_s": None,
            "wall_time_s": round(time.monotonic() - started, 3), "breakdown": [],
            "failures": [f"crashed: {type(error).__name__}: {error} ({os.path.basename(where.filename)}:{where.lineno})"],
            "crashed": True,
        }


def evaluate(event: str, level: int | None, seeds: Sequence[int], *, workers: int = 1,
             ray_address: str | None = None, keep_truth: bool = False, workcell: str | None = None,
             realism: str | None = None, arm_calibration: bool = True, record_dir: str | None = None,
             pick_check: bool | None = None) -> Iterator[dict]:
    """Run every seed and yield the results in seed order as they become available. workers = 1 runs in
    this process; more use a spawn-context process pool (MuJoCo's GL context and threads do not survive
    fork); ray_address ("auto" or host:port) runs each seed as a Ray task on that cluster instead.
    workcell: config/workcells/<name>.yaml to run on (None = the default, the RX200); realism: real or
    ideal simulation (None: the simulation config's); arm_calibration: calibrate the real arm from the camera before
    the job's clock starts (False: run it uncalibrated); record_dir: record each run to an MCAP file there (on the
    machine that runs it); pick_check: the closed loop before each pick's last descent on or off (None: StationConfig's)."""
    seeds = sorted(int(s) for s in seeds)
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= MAX_WORKERS:
        raise EvalError(f"workers must be an integer in 1..{MAX_WORKERS}, not {workers!r}")
    if ray_address is not None:
        return _over_ray(event, level, seeds, ray_address, keep_truth, workcell, realism, arm_calibration, record_dir, pick_check)
    if workers == 1 or len(seeds) <= 1:
        return (run_one(event, level, seed, keep_truth, workcell, realism, arm_calibration, record_dir, pick_check) for seed in seeds)
    return _over_processes(event, level, seeds, min(workers, len(seeds)), keep_truth, workcell, realism, arm_calibration, record_dir,
                           pick_check)


def _over_processes(event, level, seeds, workers, keep_truth, workcell=None, realism=None, arm_calibration=True,
                    record_dir=None, pick_check=None) -> Iterator[dict]:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    executor = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [executor.submit(run_one, event, level, seed, keep_truth, workcell, realism, arm_calibration, record_dir, pick_check)
                   for seed in seeds]
        for future in futures:
            yield future.result()
    finally:
        executor.shutdown(wait=True, cancel_futures=True)


def _over_ray(event, level, seeds, address, keep_truth, workcell=None, realism=None, arm_calibration=True,
              record_dir=None, pick_check=None) -> Iterator[dict]:
    try:
        import ray
    except ImportError:
        raise EvalError("--ray needs Ray: pip install 'armlab[cluster]'") from None
    connected_here = not ray.is_initialized()
    if connected_here:
        # Worker output stays on the workers: --json prints only the results on stdout.
        ray.init(address=address, log_to_driver=False, logging_level="warning")
    try:
        task = ray.remote(num_cpus=1, max_retries=0)(run_one)
        refs = [task.remote(event, level, seed, keep_truth, workcell, realism, arm_calibration, record_dir, pick_check)
                for seed in seeds]
        for ref in refs:
            yield ray.get(ref)
    finally:
        if connected_here:
            ray.shutdown()


class UntilCi:
    """Seeds in batches until the full-points rate's Wilson 95 % interval is at most `width` wide, or `max_seeds`
    seeds have run. `run_seeds(seeds)` runs a batch and yields its runs (armlab eval: `evaluate` with the
    request's arguments; tests: a fake). The first batch is `first_seeds`; each further batch is the next
    `batch_seeds` consecutive seeds after the largest run so far (fewer to stay within max_seeds).

    `runs()` yields every run as it arrives; `on_batch(status)` is called after each batch with `status()`.
    After the runs: `stopped_by` is "width" (the interval is narrow enough), "max_seeds" (the bound stopped
    it first) or "seed_range" (no seeds left below MAX_SEED)."""

    def __init__(self, run_seeds: Callable[[list[int]], Iterable[dict]], first_seeds: Sequence[int], width: float,
                 max_seeds: int = UNTIL_CI_MAX_SEEDS, batch_seeds: int = UNTIL_CI_BATCH_SEEDS,
                 on_batch: Callable[[dict], None] | None = None) -> None:
        if isinstance(width, bool) or not isinstance(width, int | float) or not 0.0 < width <= 1.0:
            raise EvalError(f"--until-ci: the interval width must be a fraction in (0, 1], not {width!r}")
        for name, value in (("--max-seeds", max_seeds), ("--batch-seeds", batch_seeds)):
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_SEEDS:
                raise EvalError(f"{name} must be an integer in 1..{MAX_SEEDS}, not {value!r}")
        first = sorted(int(seed) for seed in first_seeds)
        if not first:
            raise EvalError("--until-ci needs a first batch of seeds (--seeds)")
        if len(first) > max_seeds:
            raise EvalError(f"--seeds gives {len(first)} seeds, more than --max-seeds {max_seeds}")
        self.run_seeds, self.first_seeds, self.width = run_seeds, first, float(width)
        self.max_seeds, self.batch_seeds, self.on_batch = max_seeds, batch_seeds, on_batch
        self.seeds: list[int] = []
        self.full_runs = 0
        self.batches = 0
        self.stopped_by: str | None = None

    def interval(self) -> tuple[float, float]:
        return wilson_interval(self.full_runs, len(self.seeds))

    def status(self) -> dict:
        """Where the search stands: seeds run, full-points runs, the interval and its width, why it stopped."""
        low, high = self.interval()
        return {"width_wanted": self.width, "width": round(high - low, 6), "full_points_ci95": [round(low, 6), round(high, 6)],
                "seeds_run": len(self.seeds), "full_points_runs": self.full_runs, "batches": self.batches,
                "max_seeds": self.max_seeds, "batch_seeds": self.batch_seeds, "stopped_by": self.stopped_by}

    def runs(self) -> Iterator[dict]:
        batch = self.first_seeds
        while True:
            for run in self.run_seeds(batch):
                self.full_runs += bool(run.get("full"))
                self.seeds.append(int(run["seed"]))
                yield run
            self.batches += 1
            low, high = self.interval()
            if high - low <= self.width:
                self.stopped_by = "width"
            elif len(self.seeds) >= self.max_seeds:
                self.stopped_by = "max_seeds"
            else:
                start = max(self.seeds) + 1
                count = min(self.batch_seeds, self.max_seeds - len(self.seeds), MAX_SEED + 1 - start)
                if count <= 0:
                    self.stopped_by = "seed_range"
                batch = list(range(start, start + max(count, 0)))
            if self.on_batch is not None:
                self.on_batch(self.status())
            if self.stopped_by is not None:
                return


def public_run(run: dict) -> dict:
    """A run as `armlab eval --json` prints it (RUN_KEYS only; truth and the judge's extras left out)."""
    return {key: run.get(key) for key in RUN_KEYS}


def points_fraction(run: dict) -> float:
    """Points as a fraction of the maximum; a crashed run scores 0."""
    return run["points"] / run["max_points"] if run.get("max_points") else 0.0


def summarize(runs: Sequence[dict]) -> dict:
    """Figures over runs: mean and minimum points fraction, full-points rate within the time limit, mean
    simulated and wall time per run, and the real-time factor per worker (simulated / wall seconds) and
    per CPU second (simulated / CPU seconds of the worker, which a loaded machine does not inflate).

    Error bars (armlab.tasks.stats): `full_points_ci95`, the Wilson 95 % score interval of the full-points
    rate (`full_points_runs` of `runs`), and `mean_points_ci95`, the percentile bootstrap 95 % interval of
    the mean points fraction (BOOTSTRAP_RESAMPLES resamples seeded with BOOTSTRAP_SEED: the same runs give
    the same interval). A crashed run counts as a run without full points and with 0 points. `full_rate`
    is `full_points_rate` under its older name."""
    ran = [run for run in runs if not run.get("crashed")]
    fractions = [points_fraction(run) for run in runs]
    full_runs = sum(bool(run.get("full")) for run in runs)
    sim_s = sum(run["sim_time_s"] for run in ran)
    wall_s = sum(run["wall_time_s"] for run in ran)
    cpu_s = sum(run.get("cpu_time_s", 0.0) for run in ran)

    def mean(values) -> float | None:
        values = list(values)
        return round(sum(values) / len(values), 4) if values else None

    def rounded(interval) -> list[float]:  # 6 digits: a printed per cent with one decimal is not rounded twice
        return [round(interval[0], 6), round(interval[1], 6)]

    full_rate = round(full_runs / len(runs), 4) if runs else None
    return {
        "runs": len(runs),
        "crashed": len(runs) - len(ran),
        "mean_points_fraction": mean(fractions),
        "mean_points_ci95": rounded(bootstrap_mean_interval(fractions)) if fractions else None,
        "min_points_fraction": round(min(fractions), 4) if fractions else None,
        "full_points_runs": full_runs,
        "full_points_rate": full_rate,
        "full_points_ci95": rounded(wilson_interval(full_runs, len(runs))) if runs else None,
        "full_rate": full_rate,
        "mean_points": mean(run["points"] for run in runs),
        "mean_sim_time_s": mean(run["sim_time_s"] for run in ran),
        "mean_wall_time_s": mean(run["wall_time_s"] for run in ran),
        "realtime_factor_per_worker": round(sim_s / wall_s, 2) if wall_s > 0 else None,
        "realtime_factor_per_cpu_s": round(sim_s / cpu_s, 2) if cpu_s > 0 else None,
        "intervals": {"full_points_ci95": "Wilson score, z = 1.96",
                      "mean_points_ci95": f"percentile bootstrap, {BOOTSTRAP_RESAMPLES} resamples, seed {BOOTSTRAP_SEED}"},
    }
