"""Manipulation skills: plan a pick or a place (checked before anything moves), then run its steps
through the gate (armlab.station), which refuses them once the job is cancelled or e-stopped."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from armlab.errors import PLAN_REFUSALS
from armlab.kinematics import Unreachable
from armlab.motion import GripperStep, TrajectoryStep, check_trajectory, plan_joint_move
from armlab.motion import plan_pick as motion_plan_pick
from armlab.motion import plan_place as motion_plan_place
from armlab.motion.cartesian import plan_vertical_segment
from armlab.motion.clearance import first_collision, lowest_corners_m
from armlab.motion.gripper_box import joint_moves_inside
from armlab.motion.pick_place import solve_approach
from armlab.motion.safety import UnsafeTrajectory
from armlab.station.arm_info import station_end_effector
from armlab.station.body_check import palm_corners_m
from armlab.station.core import Station
from armlab.station.jobs import JobContext


def plan_pick_steps(station: Station, top_center_m, yaw_rad: float | None, q_start_rad=None, wrist_offset_rad: float = 0.0) -> list:
    """armlab.motion's pick plan from the current joints (open, above, straight down, grasp, straight up).
    wrist_offset_rad: IK seeded with the last joint turned this much (π/2: the fingers across the other faces).

    Unreachable / UnsafeTrajectory / InvalidInput (PLAN_REFUSALS) before anything moves.
    """
    q_start = station.start_position() if q_start_rad is None else np.asarray(q_start_rad, float)
    return motion_plan_pick(station.model, q_start, np.asarray(top_center_m, float), 0.0 if yaw_rad is None else yaw_rad, station.motion_config,
                            tool=station_end_effector(station), q_seed_rad=_wrist_turned(q_start, wrist_offset_rad))


def plan_place_steps(station: Station, surface_m, yaw_rad: float | None, held_height_m: float, q_start_rad=None,
                     wrist_offset_rad: float = 0.0) -> list:
    """armlab.motion's place plan: the held block's bottom centre onto surface_m, then release and retreat."""
    q_start = station.start_position() if q_start_rad is None else np.asarray(q_start_rad, float)
    yaw = 0.0 if yaw_rad is None else yaw_rad
    return motion_plan_place(station.model, q_start, np.asarray(surface_m, float), yaw, station.motion_config, held_height_m,
                             tool=station_end_effector(station), q_seed_rad=_wrist_turned(q_start, wrist_offset_rad))


def _wrist_turned(q_rad: np.ndarray, offset_rad: float) -> np.ndarray | None:
    """q with its last joint (the wrist's roll) turned by offset_rad, as an IK seed (None for no turn)."""
    if offset_rad == 0.0:
        return None
    seed = np.array(q_rad, dtype=float)
    seed[-1] += offset_rad
    return seed


def run_steps(station: Station, ctx: JobContext, steps: Sequence, replan: Callable[[], list] | None = None,
              progress: bool = True) -> None:
    """Execute motion steps (TrajectoryStep / GripperStep) through the gate, reporting progress.

    If the arm is no longer where the plan starts (it moved since planning), `replan()` plans again.
    """
    first = next((step for step in steps if isinstance(step, TrajectoryStep)), None)
    if replan is not None and first is not None and np.abs(first.trajectory.positions_rad[0] - station.start_position()).max() > 0.01:
        steps = replan()
    for index, step in enumerate(steps):
        if progress:
            ctx.progress(index / len(steps), step.name)
        if isinstance(step, TrajectoryStep):
            station.run_trajectory(ctx, step.trajectory)
        else:
            station.run_gripper(ctx, step.action)
    if progress:
        ctx.progress(1.0, "done")


# Pick and place with a safe transfer height ------------------------------------------------------

TRANSFER_CLEARANCE_M = 0.05  # the held block's bottom (or the fingers) this far above the tallest obstacle
TALL_OVER_TARGET_M = 0.16  # obstacles this much above the target (taller than a pile of four) are checked on the way down too
MAX_PLACE_TILT_RAD = np.radians(5.0)  # by default a block is released at most this far from top-down
SHORT_APPROACH_FRACTIONS = (0.75, 0.5)  # of approach_height_m: last-resort straight descents (a tall column far out)
# A grasp whose descent would put the open fingers' box (or the palm) into the board - a low block reached only at a
# pitch short of top-down, the box's far corners dipping - is raised by the dip (and this margin), at most by
# MAX_GRASP_RAISE_M in all: the gate refused such picks (the real arm, calibrated, reaches less far: pick_sort L3
# seed 3 gave up on two small blocks, "the fingers would go 2.8 mm into the board").
GRASP_RAISE_MARGIN_M, MAX_GRASP_RAISE_M = 0.001, 0.006


def _finger_seed(station: Station, q_start, point_m, pitch_rad: float, yaw_rad: float, finger_axis_rad: float):
    """q_start with wrist_rotate chosen so IK closes the fingers along world angle finger_axis_rad
    (mod pi) rather than the perpendicular equivalent (top-down only)."""
    q = station.model.ik(point_m, pitch=pitch_rad, yaw=yaw_rad, q_seed=q_start)
    fingers = station.model.fk(q)[:3, 1]
    want = np.array([np.cos(finger_axis_rad), np.sin(finger_axis_rad), 0.0])
    if abs(float(fingers @ want)) >= 0.7:
        return q_start
    seed = np.asarray(q_start, float).copy()
    seed[-1] = q[-1] + (np.pi / 2 if q[-1] < 0 else -np.pi / 2)
    return seed


def _facing_seed(model, q, point_m) -> np.ndarray:
    """q with the first (base) joint turned so the tool's azimuth about the base axis points at point_m.
    A numerical IK (6-DoF arms) seeded from a pose facing elsewhere (e.g. a look pose folded beside the
    base) otherwise lands on another branch (the shoulder flipped over the back) that cannot go straight down."""
    q = np.asarray(q, float).copy()
    base = model.joint_frames(q)[0][:2, 3]
    tool = model.fk(q)[:2, 3] - base
    target = np.asarray(point_m, float)[:2] - base
    if np.linalg.norm(tool) < 0.02 or np.linalg.norm(target) < 0.02:
        return q
    turn = math.atan2(target[1], target[0]) - math.atan2(tool[1], tool[0])
    turn = (turn + math.pi) % (2 * math.pi) - math.pi
    lower, upper = model.lower_rad[0], model.upper_rad[0]
    for candidate in (q[0] + turn, q[0] + turn - 2 * math.pi, q[0] + turn + 2 * math.pi):
        if lower <= candidate <= upper:
            q[0] = candidate
            break
    return q


def _transfer_plan(station: Station, q_start, point_m, yaw_rad: float | None, boxes: list, held_edge_m: float | None,
                   action: str, words: tuple[str, str, str], max_transfer_z_m: float = 0.42,
                   finger_axis_rad: float | None = None, min_pitch_rad: float = 0.0, gripper_box=None) -> list:
    """Steps: rise straight up to a transfer height (if low), joint move over point_m at that height,
    down to approach_height_m above point_m, straight down at the steepest pitch that reaches both,
    gripper `action`, straight up and back to the transfer height. The transfer height rises until
    the transfers clear the obstacle boxes; the last approach keeps its own (top-down) pitch however
    high the transfer. Every trajectory is checked against limits and the table, and, given a
    gripper_box (armlab.motion.gripper_box), its sampled gripper path against that box (joint moves
    that bulge out are split along the straight line). Unreachable / UnsafeTrajectory before anything moves.
    A suction cup comes straight down only (no tilted approach: it seals flat on a face), with no finger
    seed and no finger tips in the clearance check."""
    config = station.motion_config
    model = station.model
    tool = station_end_effector(station)
    lowest_pitch = tool.lowest_pitch_rad(config)
    point_m = np.asarray(point_m, float)
    carried = 0.0 if held_edge_m is None else held_edge_m
    vertical = dict(speed_m_s=config.vertical_speed_m_s, accel_m_s2=config.vertical_accel_m_s2, rate_hz=config.sample_rate_hz)

    def joint_move(q_a, q_b):
        return plan_joint_move(q_a, q_b, model, config.move_time_s, config.accel_time_s, config.sample_rate_hz)

    def joint_moves(q_a, q_b, name):  # [TrajectoryStep]: one joint move, or several kept inside the gripper box
        return [TrajectoryStep(name, move) for move in joint_moves_inside(model, q_a, q_b, gripper_box, joint_move)]

    q_start = np.asarray(q_start, float)
    seed = q_start if tool.has_heading else _facing_seed(model, q_start, point_m)  # a round cup: any turn, so facing the point
    if finger_axis_rad is not None and yaw_rad is not None and tool.has_heading:
        seed = _finger_seed(station, q_start, point_m, config.top_down_pitch_rad, yaw_rad, finger_axis_rad)
    # Carrying a block, approach from higher by its edge (so the block itself clears its neighbours)
    # where that is reachable at the pitch wanted; else from the usual approach height; else (a column's
    # top near the edge of reach, where the point is reachable top-down but not the one above it) from lower.
    approaches = list(dict.fromkeys((config.approach_height_m + carried, config.approach_height_m,
                                     *(config.approach_height_m * f for f in SHORT_APPROACH_FRACTIONS))))
    for index, approach_m in enumerate(approaches):
        near_m = point_m + np.array([0.0, 0.0, min(approach_m, max(0.0, max_transfer_z_m - point_m[2]))])
        try:
            pitch, (_q_point, q_near) = solve_approach(model, seed, [point_m, near_m], yaw_rad, config.top_down_pitch_rad, lowest_pitch)
        except Unreachable:
            if index == len(approaches) - 1:
                raise
            continue
        if pitch >= min_pitch_rad - 1e-9:
            break
    else:
        raise Unreachable(f"({point_m[0] * 1000:.0f}, {point_m[1] * 1000:.0f}, {point_m[2] * 1000:.0f}) mm is reachable only at "
                          f"{np.degrees(pitch):.0f}° pitch (at least {np.degrees(min_pitch_rad):.0f}° needed)", "out of reach")
    descend = plan_vertical_segment(model, q_near, float(point_m[2]), pitch_rad=pitch, yaw_rad=yaw_rad, **vertical)
    ascend = plan_vertical_segment(model, descend.positions_rad[-1], float(near_m[2]), pitch_rad=pitch, yaw_rad=yaw_rad, **vertical)
    final = [TrajectoryStep(words[1], descend), GripperStep(action, action), TrajectoryStep(words[2], ascend)]
    # The straight descent and rise skip the neighbours the fingers pass beside, but not a tall column:
    # reaching far past one, the stretched arm comes down onto its top.
    tall = [box for box in boxes if box.top_z_m > point_m[2] + TALL_OVER_TARGET_M]
    down = next((c for c in (first_collision(model, t, tall, held_edge_m=held_edge_m)
                             for t in (descend, ascend)) if c), None)
    if down is not None:
        raise UnsafeTrajectory(f"no safe way down to ({point_m[0] * 1000:.0f}, {point_m[1] * 1000:.0f}) mm: {down}")

    start_m = model.fk(q_start)[:3, 3]
    tallest = max([box.top_z_m for box in boxes] + [0.0])
    # After a short approach the arm goes back up at least to the usual approach height (a joint move, at
    # whatever pitch reaches it), not just the few cm of the short one: there the way to park is clear.
    usual_near_z = point_m[2] + min(config.approach_height_m, max(0.0, max_transfer_z_m - point_m[2]))
    z_first = min(max(near_m[2], usual_near_z, tallest + carried + TRANSFER_CLEARANCE_M), max_transfer_z_m)
    # From over the tallest obstacle upward; when none of those works (over a tall column the transfer
    # is too high to reach a block near the base), lower ones, which must then pass beside it.
    heights = [*np.arange(z_first, max_transfer_z_m + 1e-9, 0.04), *np.arange(near_m[2], z_first - 0.02, 0.04)]
    last_problem = "no transfer height tried"
    for z_transfer in map(float, heights):
        try:
            steps, checked = [], []
            q_from = q_start
            if start_m[2] < z_transfer - 0.01:
                try:  # straight up first, clear of what is below; near the base it may not reach
                    rise = plan_vertical_segment(model, q_start, z_transfer, **vertical)
                    steps.append(TrajectoryStep("rise to transfer height", rise))
                    checked.append(rise)
                    q_from = rise.positions_rad[-1]
                except PLAN_REFUSALS:
                    pass
            if z_transfer > near_m[2] + 0.005:  # over the target high, then down to the approach point
                q_high = model.ik([point_m[0], point_m[1], z_transfer], yaw=yaw_rad, q_seed=q_near)
                moves = joint_moves(q_from, q_high, words[0]) + joint_moves(q_high, q_near, "lower to approach")
                back = joint_moves(ascend.positions_rad[-1], q_high, "back to transfer height")
            else:
                moves, back = joint_moves(q_from, q_near, words[0]), []
            steps += moves
            checked += [step.trajectory for step in moves + back]
        except PLAN_REFUSALS as error:
            last_problem = str(error)
            continue
        steps += final + back
        for step in steps:
            if isinstance(step, TrajectoryStep):
                check_trajectory(model, step.trajectory, clearance_m=config.board_clearance_m)
        outside = None if gripper_box is None else next(
            (p for p in (gripper_box.first_exit(model, s.trajectory) for s in steps if isinstance(s, TrajectoryStep)) if p), None)
        if outside is not None:
            raise UnsafeTrajectory(f"no transfer to ({point_m[0] * 1000:.0f}, {point_m[1] * 1000:.0f}) mm inside the gripper box: {outside}")
        collision = next((c for c in (first_collision(model, t, boxes, held_edge_m=held_edge_m)
                                      for t in checked) if c), None)
        if collision is None:
            return steps
        last_problem = collision
    raise UnsafeTrajectory(f"no safe transfer to ({point_m[0] * 1000:.0f}, {point_m[1] * 1000:.0f}) mm: {last_problem}")


def plan_pick(station: Station, top_center_m, yaw_rad: float | None, edge_m: float, boxes: list, q_start=None,
              max_transfer_z_m: float = 0.42, finger_axis_rad: float | None = None, gripper_box=None) -> list:
    """Plan picking the block whose top-face centre is top_center_m: open, transfer above it, descend
    to the end effector's held_below_top_m(edge) below its top (a suction cup: onto it), grasp, rise. boxes: other objects; gripper_box: a
    GripperBox the gripper point keeps inside (None: no such limit)."""
    config = station.motion_config
    top = np.asarray(top_center_m, float)
    tool = station_end_effector(station)
    grasp_m = top - np.array([0.0, 0.0, tool.held_below_top_m(config, edge_m)])
    grasp_m[2] = max(grasp_m[2], config.board_clearance_m, tool.lowest_grasp_m(config))
    q_start = station.start_position() if q_start is None else q_start
    raised_m = 0.0
    while True:
        steps = _transfer_plan(station, q_start, grasp_m, yaw_rad, boxes, None, "grasp", ("move above block", "descend to grasp", "lift"),
                               max_transfer_z_m, finger_axis_rad, gripper_box=gripper_box)
        dip_m = _parts_below_board_m(station, steps)
        if dip_m <= 0.0 or raised_m + dip_m + GRASP_RAISE_MARGIN_M > MAX_GRASP_RAISE_M:
            break  # clear, or too far to raise: the gate refuses it with its reason
        grasp_m[2] += dip_m + GRASP_RAISE_MARGIN_M
        raised_m += dip_m + GRASP_RAISE_MARGIN_M
    return [GripperStep(tool.release_before_pick, "release"), *steps]


def _parts_below_board_m(station: Station, steps: list) -> float:
    """How far (m, 0 when clear) the open fingers' box or the palm (the gate's body check) comes below the board
    during the plan's descent to grasp (the "descend to grasp" step; the station's model)."""
    tool = station_end_effector(station)  # the boxes Station.check_body checks (finger_box, palm_corners_m)
    corners = [tool.body_box(station.motion_config, station.model.config).corners_m()]
    if tool.has_palm and (palm := palm_corners_m(station.model.config.name)) is not None:
        corners.append(palm)
    descents = [s.trajectory.positions_rad for s in steps if isinstance(s, TrajectoryStep) and s.name == "descend to grasp"]
    lowest = min((float(lowest_corners_m(station.model, q, c)[0].min()) for q in descents for c in corners), default=0.0)
    return max(0.0, -lowest)


def plan_place(station: Station, surface_m, yaw_rad: float | None, edge_m: float, boxes: list, q_start=None,
               max_transfer_z_m: float = 0.42, finger_axis_rad: float | None = None,
               max_tilt_rad: float = MAX_PLACE_TILT_RAD, gripper_box=None) -> list:
    """Plan setting the held block (edge edge_m, grasped as plan_pick does) with its bottom centre on
    surface_m, releasing place_clearance_m above it, then rising. finger_axis_rad: the world direction
    the fingers open along (e.g. across a line of blocks, so they do not push the neighbours)."""
    config = station.motion_config
    surface = np.asarray(surface_m, float)
    held_below_top = station_end_effector(station).held_below_top_m(config, edge_m)
    release_m = surface + np.array([0.0, 0.0, edge_m - held_below_top + config.place_clearance_m])
    q_start = station.start_position() if q_start is None else q_start
    return _transfer_plan(station, q_start, release_m, yaw_rad, boxes, edge_m, "release",
                          ("move above place", "descend to place", "retreat"), max_transfer_z_m, finger_axis_rad,
                          min_pitch_rad=config.top_down_pitch_rad - max_tilt_rad, gripper_box=gripper_box)


def plan_side_place(station: Station, surface_m, edge_m: float, boxes: list, q_start=None, max_transfer_z_m: float = 0.55) -> list:
    """Plan setting the held block (grasped top-down as plan_pick does) on surface_m with the gripper
    horizontal (pitch 0), for surfaces too high for a top-down place (tall towers). The wrist turns
    to a multiple of 90° so the block's faces stay level; its centre lies (edge/2 - grasp depth)
    beyond the gripper point along the horizontal approach axis."""
    tool = station_end_effector(station)
    if not tool.holds_by_sides:
        raise Unreachable(f"a side place needs fingers: a {tool.name} gripper holds the block by its top face, "
                          "which would turn sideways", "out of reach")
    config = station.motion_config
    model = station.model
    surface = np.asarray(surface_m, float)
    base_xy = np.asarray(model.joint_frames(np.zeros(model.dof))[0][:2, 3])  # the waist axis
    outward = (surface[:2] - base_xy) / max(np.linalg.norm(surface[:2] - base_xy), 1e-9)
    beyond = edge_m / 2.0 - config.grasp_depth_for(edge_m)
    release_m = np.array([*(surface[:2] - outward * beyond), surface[2] + edge_m / 2.0 + config.place_clearance_m])
    near_m = release_m + np.array([0.0, 0.0, config.approach_height_m])
    q_start = station.start_position() if q_start is None else np.asarray(q_start, float)
    seed = q_start.copy()
    seed[-1] = np.round(seed[-1] / (np.pi / 2)) * (np.pi / 2)
    vertical = dict(speed_m_s=config.vertical_speed_m_s, accel_m_s2=config.vertical_accel_m_s2, rate_hz=config.sample_rate_hz)
    if near_m[2] > max_transfer_z_m:
        raise Unreachable(f"a side place at {release_m[2] * 1000:.0f} mm needs the gripper above the {max_transfer_z_m * 1000:.0f} mm limit",
                          "out of reach")
    q_near = model.ik(near_m, pitch=0.0, yaw=None, q_seed=seed)
    descend = plan_vertical_segment(model, q_near, float(release_m[2]), pitch_rad=0.0, yaw_rad=None, **vertical)
    ascend = plan_vertical_segment(model, descend.positions_rad[-1], float(near_m[2]), pitch_rad=0.0, yaw_rad=None, **vertical)
    move = plan_joint_move(q_start, q_near, model, config.move_time_s, config.accel_time_s, config.sample_rate_hz)
    steps = [TrajectoryStep("move beside the tower", move), TrajectoryStep("descend to place", descend),
             GripperStep("release", "release"), TrajectoryStep("retreat", ascend)]
    for step in steps:
        if isinstance(step, TrajectoryStep):
            check_trajectory(model, step.trajectory, clearance_m=config.board_clearance_m)
    collision = first_collision(model, move, boxes, held_edge_m=edge_m)
    if collision is not None:
        raise UnsafeTrajectory(f"no safe way beside the tower: {collision}")
    return steps
