"""Closed loop at the block before a pick's last descent (issue 19 item 4, pick side): over the block, the arm
raises its wrist so the gripper's tag faces the overhead camera, the camera finds the tag (the arm calibration's
sighting, armlab.vision.gripper_marker, mapped along its colour ray), and the difference between where the tag is
seen and where the calibrated model puts it for the measured joints is the arm's error there. The descent goes to
the block's grasp point shifted by that error; the next look checks what remains and corrects again, at most
`max_corrections` times. A correction moves straight to the corrected hover's look (the wrist stays turned up; the
waist, shoulder and elbow as for the corrected descent), and the wrist turns down once, before the descent. Every
move (the look's wrist turn, each correction, the corrected descent) is planned, checked by the gate like any other
and kept clear of the obstacles; a correction beyond `max_correction_m` is refused with the reason (the pick
descends uncorrected), as is one the planner refuses.

Why the wrist only: pointing down, the tag faces sideways and the camera does not find it; turning only
wrist_angle (and wrist_rotate to 0, the tag's face up) leaves the waist, shoulder and elbow, and their error, as
they are for the descent (turning the whole arm to a pitched look measured an error that did not carry over:
armlab.tasks.place_check). Works the same on the real arm with its printed tag.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armlab.errors import PLAN_REFUSALS
from armlab.motion import GripperStep, TrajectoryStep, check_trajectory, plan_joint_move
from armlab.motion.cartesian import plan_vertical_segment
from armlab.motion.clearance import first_collision
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills.arm_camera import sight_marker_at_rest
from armlab.skills.manipulate import run_steps
from armlab.station.core import Station
from armlab.station.jobs import JobContext
from armlab.station.settle import SETTLE_MAX_RAD
from armlab.vision.gripper_marker import MarkerNotFound
from armlab.vision.pixel_world import depth_points_to_world
from armlab.workcell import load_workcell

DESCENT_STEP = "descend to grasp"  # the pick plan's last descent (armlab.skills.manipulate.plan_pick)
LOOK_TILT_RAD = 1.0  # wrist_angle raised this much from top-down for the look: the tag ~35 deg from facing up
DEADBAND_M = 0.0005  # what remains below this is not corrected (the sighting's own noise is ~0.2 mm)


@dataclass(frozen=True)
class PickCheckSettings:
    """StationConfig's pick_check, pick_corrections and pick_correction_max_m."""

    enabled: bool
    max_corrections: int = 2
    max_correction_m: float = 0.006


def run_pick(station: Station, ctx: JobContext, steps: list, settings: PickCheckSettings, boxes: list, name: str,
             log: Callable[[str, str], None], gripper_box=None) -> dict | None:
    """Run a pick plan's steps through the gate with the closed loop before its last descent (the plan's
    DESCENT_STEP; none, the loop off, or the camera or the arm not calibrated: the steps as planned; the loop trims
    what the arm calibration leaves). Returns the record (corrections and what remained, mm; None without a loop)
    after logging it. Not inside a job's gripper_box (pick_stack's bonus): the look's wrist turn takes the gripper
    point out of it (the bonus lost on 5 of 5 held-out pick_stack L3 seeds 30-34 with the loop)."""
    index = next((i for i, s in enumerate(steps) if isinstance(s, TrajectoryStep) and s.name == DESCENT_STEP), None)
    if (not settings.enabled or index is None or gripper_box is not None or station.calibration is None
            or getattr(station.model, "calibration", None) is None):
        run_steps(station, ctx, steps, progress=False)
        return None
    run_steps(station, ctx, arriving_to_look(station, steps[:index], steps[index].trajectory.positions_rad[0], boxes), progress=False)
    tail, record = corrected_tail(station, ctx, steps[index:], settings, boxes)
    record["block"] = name
    log("warn" if record.get("refused") else "info", f"pick check, {name}: {record['words']}")
    run_steps(station, ctx, tail, progress=False)
    return record


def arriving_to_look(station: Station, steps: list, q_hover, boxes: list) -> list:
    """steps, their last joint move (to q_hover over the block) ending at its look instead: the wrist turns up on the
    way (a 0.9 s wrist turn fewer); as planned when that move does not end at q_hover or the new one is refused."""
    last = max((i for i, s in enumerate(steps) if isinstance(s, TrajectoryStep)), default=None)
    if last is None or np.abs(steps[last].trajectory.positions_rad[-1] - q_hover).max() > 1e-9:
        return steps
    config = station.motion_config
    try:
        looking = plan_joint_move(steps[last].trajectory.positions_rad[0], look_joints(q_hover), station.model,
                                  config.move_time_s, config.accel_time_s, config.sample_rate_hz)
        check_trajectory(station.model, looking, clearance_m=config.board_clearance_m)
        station.check_motion(_checked(station, looking, boxes))
    except PLAN_REFUSALS:
        return steps
    return [*steps[:last], TrajectoryStep(f"{steps[last].name}, the wrist turned up to look", looking), *steps[last + 1:]]


@dataclass
class Loop:
    """What the loop over the block did: the correction applied (world, m: the target moves by minus it), the joints
    over the block it left the arm to descend from, each look's remaining error and each correction (mm), and why
    it stopped short (None: it did not)."""

    applied_m: np.ndarray
    q_near_rad: np.ndarray
    looks_mm: list[float]
    corrections_mm: list[list[float]]
    refused: str | None = None

    def record(self) -> dict:
        looks, count = self.looks_mm, len(self.corrections_mm)
        size_mm = round(float(np.linalg.norm(self.applied_m)) * 1000, 2)
        if not looks:
            words = f"{self.refused}; descending uncorrected"
        elif not count:
            words = f"seen {looks[0]:.1f} mm off: " + (f"{self.refused}; descending uncorrected" if self.refused
                                                       else f"within {DEADBAND_M * 1000:.1f} mm, not corrected")
        else:
            words = (f"seen {looks[0]:.1f} mm off, corrected by {size_mm:.1f} mm in {count} step(s), {looks[-1]:.1f} mm "
                     "remained at the last look" + (f" ({self.refused})" if self.refused else ""))
        return {"looks_mm": looks, "corrections_mm": self.corrections_mm, "correction_mm": size_mm, "refused": self.refused,
                "words": words}


def look_and_correct(station: Station, ctx: JobContext, q_hover, pitch_rad: float, yaw_rad: float, settings: PickCheckSettings,
                     boxes: list) -> Loop:
    """From q_hover (the arm there) over the block: look, and while what remains exceeds DEADBAND_M, move the hover
    by it (at most settings.max_corrections times, each within max_correction_m, each looked at again). The arm ends
    at the last look; Loop.q_near_rad is where to descend from."""
    model = station.model
    hover_m = model.fk(q_hover)[:3, 3]
    loop = Loop(np.zeros(3), np.asarray(q_hover, float), [], [])
    while True:
        seen = gripper_error(station, ctx, loop.q_near_rad, boxes)
        if isinstance(seen, str):
            loop.refused = loop.refused or f"no look ({seen})"
            return loop
        remains = seen - loop.applied_m
        loop.looks_mm.append(round(float(np.linalg.norm(remains)) * 1000, 2))
        if np.linalg.norm(remains) <= DEADBAND_M or len(loop.corrections_mm) >= settings.max_corrections:
            return loop
        wanted = loop.applied_m + remains
        if np.linalg.norm(wanted) > settings.max_correction_m:
            loop.refused = (f"a correction of {np.linalg.norm(wanted) * 1000:.1f} mm is more than the "
                            f"{settings.max_correction_m * 1000:.0f} mm allowed (not the arm's drift): refused")
            return loop
        try:  # straight to the corrected hover's look (the wrist stays turned up: two wrist turns fewer a correction)
            q_wanted = model.ik(hover_m - wanted, pitch=pitch_rad, yaw=yaw_rad, q_seed=q_hover)
            station.run_trajectory(ctx, _checked(station, station.plan_move(look_joints(q_wanted)), boxes))
        except PLAN_REFUSALS as error:
            loop.refused = f"the corrected hover is refused ({error})"
            return loop
        loop.applied_m, loop.q_near_rad = wanted, q_wanted
        loop.corrections_mm.append((1000 * wanted).round(2).tolist())


def corrected_tail(station: Station, ctx: JobContext, tail: list, settings: PickCheckSettings, boxes: list) -> tuple[list, dict]:
    """(the steps from the hover over the block on, corrected by look_and_correct; the record). The arm is left where
    the returned steps start."""
    model = station.model
    descent = tail[0].trajectory
    q_hover = descent.positions_rad[0]
    hover_m, grasp_m = model.fk(q_hover)[:3, 3], model.fk(descent.positions_rad[-1])[:3, 3]
    fingers = model.fk(descent.positions_rad[-1])[:3, 1]
    pitch, yaw = model.pitch_of(q_hover), float(np.arctan2(fingers[1], fingers[0]))
    loop = look_and_correct(station, ctx, q_hover, pitch, yaw, settings, boxes)
    steps = None
    if loop.corrections_mm:
        applied = loop.applied_m
        try:
            steps = [TrajectoryStep("over the block, corrected", station.plan_move(loop.q_near_rad)),
                     *_descent_from(station, loop.q_near_rad, grasp_m - applied, hover_m[2] - applied[2], pitch, yaw, tail, boxes)]
        except PLAN_REFUSALS as error:
            loop = Loop(np.zeros(3), np.asarray(q_hover, float), loop.looks_mm, [], f"the corrected descent is refused ({error})")
    if steps is None:  # the plan's own descent, from its hover (the arm may be at a look)
        away = np.abs(station.start_position() - q_hover).max() > 1e-6
        steps = [TrajectoryStep("back over the block", station.plan_move(q_hover)), *tail] if away else list(tail)
    return steps, loop.record()


def gripper_error(station: Station, ctx: JobContext, q_near, boxes: list) -> np.ndarray | str:
    """Turn the wrist up over q_near (checked, clear of boxes), find the gripper's tag: where it is seen minus where
    the calibrated model puts it for the measured joints (world, m); or why there is no look."""
    marker = load_workcell(station.config.workcell).gripper.marker
    if marker is None:
        return "the workcell has no gripper tag"
    q_look = look_joints(q_near)
    try:
        # not there yet (a correction goes straight there, its command then settled by at most SETTLE_MAX_RAD)
        if np.abs(station.start_position() - q_look).max() > SETTLE_MAX_RAD:
            station.run_trajectory(ctx, _checked(station, station.plan_move(q_look), boxes))
    except PLAN_REFUSALS as error:
        return f"the look's wrist turn is refused: {error}"
    intrinsics = station.intrinsics.current()
    try:
        sighting = sight_marker_at_rest(station, ctx, marker.id, intrinsics.K, np.asarray(intrinsics.dist, float))
    except MarkerNotFound as error:
        return str(error)
    seen = depth_points_to_world(station.calibration, sighting.point_camera_m)[0]
    T = getattr(station.model, "fk_measured", station.model.fk)(station.joints_rad())
    return seen - (T[:3, :3] @ np.asarray(marker.position_m, float) + T[:3, 3])


def look_joints(q_near) -> np.ndarray:
    """The look over q_near: its wrist turned up LOOK_TILT_RAD, wrist_rotate 0 (the tag's face up)."""
    q_look = np.array(q_near, float)
    q_look[3] -= LOOK_TILT_RAD
    q_look[4] = 0.0
    return q_look


def _descent_from(station: Station, q_from, grasp_m, near_z_m: float, pitch: float, yaw: float, tail: list, boxes: list) -> list:
    """The descent to grasp_m from q_from (over it), the plan's grasp, the rise back to near_z_m and a joint move to
    where the plan's tail ends; each checked (limits, board, obstacles). PLAN_REFUSALS when one is refused."""
    model, config = station.model, station.motion_config
    vertical = dict(pitch_rad=pitch, yaw_rad=yaw, speed_m_s=config.vertical_speed_m_s, accel_m_s2=config.vertical_accel_m_s2,
                    rate_hz=config.sample_rate_hz)
    down = plan_vertical_segment(model, q_from, float(grasp_m[2]), **vertical)
    up = plan_vertical_segment(model, down.positions_rad[-1], near_z_m, **vertical)
    grasp = next(s for s in tail if isinstance(s, GripperStep))
    end = [s for s in tail if isinstance(s, TrajectoryStep)][-1].trajectory.positions_rad[-1]
    back = plan_joint_move(up.positions_rad[-1], end, model, config.move_time_s, config.accel_time_s, config.sample_rate_hz)
    for trajectory in (up, back):  # the descent itself goes between the neighbours, as the plan's does
        check_trajectory(model, trajectory, clearance_m=config.board_clearance_m)
        _checked(station, trajectory, boxes)
    check_trajectory(model, down, clearance_m=config.board_clearance_m)
    return [TrajectoryStep(DESCENT_STEP, down), grasp, TrajectoryStep("lift", up), TrajectoryStep("back to transfer height", back)]


def _checked(station: Station, trajectory, boxes: list):
    """trajectory, once it keeps clear of the obstacle boxes (UnsafeTrajectory naming what it would hit)."""
    hit = first_collision(station.model, trajectory, boxes)
    if hit:
        raise UnsafeTrajectory(f"it would hit {hit}")
    return trajectory


def pick_summary(records: list[dict]) -> dict:
    """For the job's result: every pick's loop, and the first looks' and the corrections' mean and max (mm)."""
    first = [r["looks_mm"][0] for r in records if r["looks_mm"]]
    corrected = [r["correction_mm"] for r in records if r["corrections_mm"]]
    figures = {}
    for key, values in (("seen", first), ("correction", corrected)):
        figures[f"{key}_mean_mm"] = round(float(np.mean(values)), 2) if values else None
        figures[f"{key}_max_mm"] = round(float(np.max(values)), 2) if values else None
    return {"picks": len(records), "looked": len(first), "corrected": len(corrected), **figures, "records": list(records)}
