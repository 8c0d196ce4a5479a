"""The autonomous jobs by name, their levels and parameters, and how to start one on the station."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from armlab.errors import InvalidInput
from armlab.motion.end_effector import END_EFFECTORS, end_effector
from armlab.scene import as_workcell
from armlab.station.core import NotCalibrated, Station
from armlab.station.jobs import Job, JobContext
from armlab.tasks import (
    clear_table,
    line_up,
    pick_sort,
    pick_stack,
    sort_by_tag,
    sort_stack,
    stack_here,
    stack_high,
    to_the_sky,
)
from armlab.tasks.job_params import JobParams, NoParams, StackHereParams, validated_params
from armlab.tasks.judge import EVENT_LIMITS_S
from armlab.tasks.judge import GRIPPER_BOX_M as box
from armlab.tasks.policy import Plan
from armlab.tasks.runner import TaskRunner
from armlab.workcell import Workcell


class JobUnsupported(InvalidInput):
    """A job the station's workcell cannot run (its gripper type or geometry): refused before anything moves."""


def _tags_in_gripper_box(workcell: Workcell) -> str | None:
    """pick_stack's columns stand on the two board tags nearest the base, with the gripper kept inside
    the judge's fixed box (§7, the RX200 board's): both tags must lie inside it."""
    tags = sorted(workcell.board_tags.centres_m.values(), key=lambda xy: (math.hypot(*xy), xy[0]))[:2]
    outside = [xy for xy in tags if not (abs(xy[0]) <= box["x_abs_max"] and box["y_min"] <= xy[1] <= box["y_max"])]
    if not outside:
        return None
    return (f"board tags inside the judge's gripper box (|x| <= {box['x_abs_max'] * 1000:.0f} mm, y {box['y_min'] * 1000:.0f}.."
            f"{box['y_max'] * 1000:.0f} mm) to stack on; tag(s) at {', '.join(f'({x * 1000:.0f}, {y * 1000:.0f}) mm' for x, y in outside)} are not")


LINE_REACH_M = (0.14, 0.35)  # line_up's slot radius band (armlab.tasks.line_up.choose_layout)


def _reaches_line_band(workcell: Workcell) -> str | None:
    """line_up lays its lines out within 0.14-0.35 m of the base axis (the RX200's top-down reach): the
    workcell's top-down reach (scene.reach_m) must cover that band."""
    low, high = workcell.scene.reach_m
    if low <= LINE_REACH_M[0] and high >= LINE_REACH_M[1]:
        return None
    return (f"a top-down reach covering {LINE_REACH_M[0] * 1000:.0f}-{LINE_REACH_M[1] * 1000:.0f} mm from the base "
            f"(its line layouts, laid out for the RX200); this workcell's reach is {low * 1000:.0f}-{high * 1000:.0f} mm")


@dataclass(frozen=True)
class JobSpec:
    """An autonomous job: its levels (() = none), and its policy for a level and parameters."""

    name: str
    levels: tuple[int, ...]
    make_policy: Callable[[int | None, dict, TaskRunner], Callable[[list[dict], set], Plan]]
    summary: str
    params_model: type[JobParams] = NoParams  # its parameters (armlab.tasks.job_params)
    # What the job needs of the workcell (config/workcells/<name>.yaml): an end effector that holds blocks by
    # their sides (and why), and a check of the workcell's geometry (None = any; else a function returning what
    # is missing, or None when the workcell has it).
    side_grasps_why: str | None = None
    workcell_check: Callable[[Workcell], str | None] | None = None


JOBS: dict[str, JobSpec] = {
    spec.name: spec
    for spec in (
        JobSpec("pick_sort", (1, 2, 3), pick_sort.make_policy,
                "every block to y < 0: small at x < 0, large at x > 0"),
        JobSpec("pick_stack", (1, 2, 3), pick_stack.make_policy,
                "every block into columns of three or more on the calibration tags",
                workcell_check=_tags_in_gripper_box),
        JobSpec("line_up", (1, 2, 3), line_up.make_policy,
                "per size, the six blocks in a straight rainbow line", workcell_check=_reaches_line_band),
        JobSpec("stack_high", (1, 2), stack_high.make_policy,
                "per size, one column of the six blocks in rainbow order, red at the bottom"),
        JobSpec("to_the_sky", (1,), to_the_sky.make_policy,
                "one tower of large blocks, as tall as the arm can build (fed by the feeder)",
                side_grasps_why="side grasps for the tower's upper blocks"),
        JobSpec("sort_stack", (1, 2, 3), sort_stack.make_policy,
                "every block to its side of y < 0, stacked in rainbow order per side"),
        JobSpec("sort_by_tag", (1, 2, 3), sort_by_tag.make_policy,
                "every ArUco-topped block to the place its id names, stacked when ids repeat"),
        JobSpec("clear_table", (1, 2, 3), clear_table.make_policy,
                "every object on the board, any colour or shape, into the bin"),
        JobSpec("stack_here", (), stack_here.make_policy,
                "all blocks (or one colour / size) stacked at a point, large ones first",
                params_model=StackHereParams),
    )
}


def checked_request(job: str, level, params) -> tuple[JobSpec, int | None, dict]:
    """Validate a job request: ValueError naming the problem (unknown job, level, parameter)."""
    if not isinstance(job, str) or job not in JOBS:
        raise InvalidInput(f"unknown job {job!r}; jobs: {', '.join(JOBS)}")
    spec = JOBS[job]
    if spec.levels:
        if level is None:
            level = spec.levels[-1]
        if isinstance(level, bool) or not isinstance(level, int) or level not in spec.levels:
            raise InvalidInput(f"job '{job}' has levels {', '.join(map(str, spec.levels))}, not {level!r}")
    elif level is not None:
        raise InvalidInput(f"job '{job}' has no levels; leave 'level' out")
    return spec, level, validated_params(job, spec.params_model, params)


def unsupported_reason(job: str, workcell: Workcell | str | None = None) -> str | None:
    """What the workcell (a Workcell, a name, None = the default) lacks for the job, or None when the job
    can run there. Unknown jobs are checked_request's (None here)."""
    spec = JOBS.get(job)
    if spec is None:
        return None
    cell = as_workcell(workcell)
    tool = end_effector(cell.gripper.type)
    if spec.side_grasps_why is not None and not tool.holds_by_sides:
        holders = " or ".join(other.name for other in END_EFFECTORS.values() if other.holds_by_sides)
        return f"a gripper that holds blocks by their sides: {holders} ({spec.side_grasps_why}); this workcell's is {tool.name}"
    return spec.workcell_check(cell) if spec.workcell_check is not None else None


def check_supported(job: str, workcell: Workcell | str | None = None) -> None:
    """JobUnsupported (an InvalidInput) naming the job, the workcell and what it lacks, unless the job runs there."""
    reason = unsupported_reason(job, workcell)
    if reason:
        raise JobUnsupported(f"job '{job}' is not available on workcell '{as_workcell(workcell).name}': it needs {reason}")


def start_auto(station: Station, job: str, level: int | None = None, params: dict | None = None, source: str | None = None) -> Job:
    """Start an autonomous job in the auto_sort state (CommandRefused unless idle; ValueError for a bad
    request; NotCalibrated without a camera calibration). Nothing moves before the checks pass."""
    station.allowed_or_raise("auto")
    spec, level, params = checked_request(job, level, params)
    check_supported(job, getattr(station.config, "workcell", None))
    if station.calibration is None:
        raise NotCalibrated(f"job '{job}'")
    station.require_trusted_calibration(f"job '{job}'")
    runners: dict[str, TaskRunner] = {}

    def run(ctx: JobContext) -> dict:
        runner = runners["runner"] = TaskRunner(station, ctx, job)
        runner.time_limit_s = EVENT_LIMITS_S.get(job)
        return runner.run(spec.make_policy(level, params, runner))

    def cleanup(ctx: JobContext) -> str:
        runner = runners.get("runner")
        if runner is None:
            return ""
        runner.ctx = ctx
        return runner.put_down_held()

    detail = job if level is None else f"{job} L{level}"
    return station.start_job("auto", job, run, detail=detail, source=source, cleanup=cleanup)
