"""Side and inclined grasps (issue 8, to_the_sky): pick a block from the board with the fingers closing
horizontally at a pitch shallower than top-down, and set it on a tall tower at the same pitch.

A held block turns with the gripper, so its tilt when released is (place pitch − grasp pitch) about the
finger axis: a block picked top-down and set down with the gripper horizontal lies on its side. Here
the pitch is chosen once for both ends (the steepest one at which the pick and the place are both
reachable), so the block stands as it stood on the board. The fingers close along the horizontal
tangent (wrist_rotate 0), so a block is taken across two faces only when its yaw lines up with its
bearing from the base (mod 90°); `aligned` says whether it does.

High on a tower there is no room above the release point: the held block slides in over the tower top
(from the base side or across it), and after releasing the open fingers slide back along themselves;
it gets there rising far from the tower and turning in about the waist, and leaves turning away about
the waist before the arm folds to park (folding straight down swings the elbow into a tall tower).
Every trajectory is checked against joint limits and the table (check_trajectory), the arm's links
against the obstacle boxes (first_collision), the gripper's wide palm and open fingers against them,
and the held block's corners against them and the tower under it. Unreachable / UnsafeTrajectory
before anything moves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from armlab.devices.arm_body import load_finger_gripper_outline
from armlab.errors import PLAN_REFUSALS
from armlab.kinematics import Unreachable
from armlab.motion import GripperStep, TrajectoryStep, check_trajectory, plan_joint_move
from armlab.motion.cartesian import plan_vertical_segment
from armlab.motion.clearance import CLEARANCE_M, box_around, first_collision
from armlab.motion.line import plan_line_segment
from armlab.motion.safety import UnsafeTrajectory
from armlab.station.arm_info import station_end_effector
from armlab.station.core import Station
from armlab.vision.block import Block

PITCH_STEP_RAD = math.radians(5.0)
MIN_PITCH_RAD = 0.0  # never grasp from the board pointing upward (the wrist would be below the fingers)
ALIGN_TOLERANCE_RAD = math.radians(8.0)  # a block this far off its bearing (mod 90°) still closes across faces
TABLE_MARGIN_M = 0.004  # the gripper's lowest part keeps this far above the board when grasping
SLIDE_IN_M = 0.05  # high places: the held block starts this far toward the base from its release point ...
SLIDE_RISE_M = 0.01  # ... and this much higher, then slides in over the tower top
FINGERS_OFF_M = 0.035  # after releasing, the open fingers slide back along themselves this far (off the block) ...
RETREAT_M = 0.07  # ... then down and toward the base to this far from the release point (the park checks the tower)
RETREAT_DROP_M = 0.02
BLOCK_MARGIN_M = 0.002  # the held block's corners keep this far from obstacles and the tower under it
PARK_MARGIN_M = 0.0  # as the runner's park: the folded arm passes closer to objects than transfers do
TOWER_BOX_HALF_M = 0.032  # the new tower's box when leaving it (as the runner's boxes around objects)
EXIT_TURNS_RAD = tuple(np.radians((30.0, 45.0, 60.0, 90.0)))  # waist turns away from a tower before parking


@dataclass(frozen=True)
class SideGrasp:
    """How a block sits in the gripper: the grasp pitch, the block centre in the gripper frame (m) and
    the block's axes in the gripper frame (columns), from the grasp pose."""

    pitch_rad: float
    centre_in_gripper_m: np.ndarray
    axes_in_gripper: np.ndarray


def bearing_rad(xy_m) -> float:
    """Direction of (x, y) from the base axis (world, rad)."""
    return math.atan2(float(xy_m[1]), float(xy_m[0]))


def aligned(block: Block, tolerance_rad: float = ALIGN_TOLERANCE_RAD) -> bool:
    """True if the block's faces line up with its bearing from the base (mod 90°), so fingers closing
    along the horizontal tangent close across two faces."""
    off = math.remainder(float(block.yaw_rad) - bearing_rad(block.position_m), math.pi / 2)
    return abs(off) <= tolerance_rad


def gripper_rotation(model, pitch_rad: float, bearing: float) -> np.ndarray:
    """World rotation of the gripper frame (x approach, y finger axis) at pitch_rad below horizontal,
    facing `bearing`, wrist_rotate 0 (fingers closing horizontally)."""
    q = np.zeros(model.dof)
    q[0] = bearing - math.pi / 2  # waist 0 faces +y
    q[3] = pitch_rad
    return np.asarray(model.fk(q), float)[:3, :3]


@lru_cache(maxsize=4)
def gripper_outline(arm: str):
    """The arm's finger gripper: palm and fingers around the finger plane (FingerGripperOutline of the arm's body,
    armlab.devices.arm_body: the parts the simulation builds)."""
    return load_finger_gripper_outline(arm)


def lowest_below_gripper_point_m(arm: str, pitch_rad: float) -> float:
    """How far below the gripper point the arm's gripper's lowest part (palm or finger) reaches at this pitch."""
    s, c = math.sin(pitch_rad), math.cos(pitch_rad)
    outline = gripper_outline(arm)
    palm = outline.palm_half_height_m * c - outline.palm_front_behind_m * s
    finger = outline.finger_half_height_m * c + outline.finger_tip_beyond_m * s
    return max(palm, finger)


def grasp_point(station: Station, top_center_m, edge_m: float, pitch_rad: float) -> np.ndarray:
    """Gripper point closing on the block whose top-face centre is top_center_m at pitch_rad: as far
    from the block centre along the approach as a top-down grasp holds it (config.grasp_depth_for),
    raised where the gripper's lowest part would come within TABLE_MARGIN_M of the board."""
    config = station.motion_config
    top = np.asarray(top_center_m, float)
    centre = top - np.array([0.0, 0.0, edge_m / 2.0])
    approach = gripper_rotation(station.model, pitch_rad, bearing_rad(top))[:, 0]
    point = centre - approach * (edge_m / 2.0 - config.grasp_depth_for(edge_m))
    floor = top[2] - edge_m + lowest_below_gripper_point_m(station.model.name, pitch_rad) + TABLE_MARGIN_M
    point[2] = max(point[2], floor, config.board_clearance_m)
    return point


def held_block_corners(model, positions_rad: np.ndarray, grasp: SideGrasp, edge_m: float) -> np.ndarray:
    """World corners (N, 8, 3) of the held block at each joint vector."""
    frames = np.asarray(model.fk(np.asarray(positions_rad, float)))
    if frames.ndim == 2:
        frames = frames[None]
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float) * edge_m / 2.0
    local = grasp.centre_in_gripper_m[None, :] + signs @ grasp.axes_in_gripper.T  # (8, 3) gripper frame
    return frames[:, None, :3, 3] + np.einsum("nij,kj->nki", frames[:, :3, :3], local)


def _corner_hit(points: np.ndarray, boxes: list, margin_m: float, skip: np.ndarray | None = None) -> str | None:
    """A sentence if any point comes within margin_m of a box (boxes the `skip` points already touch,
    e.g. where a motion starts, are left out, as first_collision does)."""
    def inside(p, box):
        dx = np.abs(p[..., 0] - box.center_xy_m[0]) - box.half_xy_m[0]
        dy = np.abs(p[..., 1] - box.center_xy_m[1]) - box.half_xy_m[1]
        return (dx < margin_m) & (dy < margin_m) & (p[..., 2] - box.top_z_m < margin_m)

    for box in boxes:
        if skip is not None and inside(skip, box).any():
            continue
        if inside(points, box).any():
            what = "the held block" if skip is None else "the gripper"
            return f"{what} passes within {margin_m * 1000:.0f} mm of {box.name} (top {box.top_z_m * 1000:.0f} mm)"
    return None


def gripper_points(model, positions_rad: np.ndarray) -> np.ndarray:
    """World points (N, 6, 3) at the open fingers' outer faces (tips and roots) and the palm's ends, which
    reach far to the sides of the link points armlab.motion.clearance samples along the arm's axis."""
    frames = np.asarray(model.fk(np.asarray(positions_rad, float)))
    if frames.ndim == 2:
        frames = frames[None]
    outline = gripper_outline(model.name)
    local = np.array([[x, side * outline.open_outer_m, 0.0]
                      for x in (outline.finger_tip_beyond_m, -outline.palm_front_behind_m, -outline.palm_back_behind_m)
                      for side in (-1.0, 1.0)])
    return frames[:, None, :3, 3] + np.einsum("nij,kj->nki", frames[:, :3, :3], local)


def _check(station: Station, trajectories: list, boxes: list, grasp: SideGrasp | None, edge_m: float,
           block_boxes: list | None = None, margin_m: float = CLEARANCE_M) -> None:
    """Limits and table for every trajectory; links and the gripper's sides against boxes; the held
    block against block_boxes."""
    model = station.model
    for trajectory in trajectories:
        check_trajectory(model, trajectory, clearance_m=station.motion_config.board_clearance_m)
        collision = first_collision(model, trajectory, boxes, margin_m=margin_m)
        positions = trajectory.positions_rad[:: max(1, len(trajectory.positions_rad) // 40)]
        if collision is None:
            sides = gripper_points(model, positions)
            collision = _corner_hit(sides[1:], boxes, gripper_outline(model.name).finger_half_height_m, skip=sides[0])
        if collision is None and grasp is not None:
            collision = _corner_hit(held_block_corners(model, positions, grasp, edge_m), block_boxes or boxes, BLOCK_MARGIN_M)
        if collision is not None:
            raise UnsafeTrajectory(collision)


def _vertical(station: Station, q_start, z_m: float, pitch_rad: float):
    c = station.motion_config
    return plan_vertical_segment(station.model, q_start, z_m, pitch_rad=pitch_rad, yaw_rad=None, speed_m_s=c.vertical_speed_m_s,
                                 accel_m_s2=c.vertical_accel_m_s2, rate_hz=c.sample_rate_hz)


def _line(station: Station, q_start, goal_m, pitch_rad: float):
    c = station.motion_config
    return plan_line_segment(station.model, q_start, goal_m, pitch_rad, None, speed_m_s=c.vertical_speed_m_s,
                             accel_m_s2=c.vertical_accel_m_s2, rate_hz=c.sample_rate_hz)


def _joint_move(station: Station, q_a, q_b):
    c = station.motion_config
    return plan_joint_move(np.asarray(q_a, float), np.asarray(q_b, float), station.model, c.move_time_s, c.accel_time_s,
                           c.sample_rate_hz)


def _seed(q_rad) -> np.ndarray:
    seed = np.asarray(q_rad, float).copy()
    seed[-1] = 0.0  # wrist_rotate 0: the fingers close along the horizontal tangent
    return seed


def plan_side_pick(station: Station, top_center_m, edge_m: float, boxes: list, pitch_rad: float,
                   q_start=None) -> tuple[list, SideGrasp]:
    """Steps to pick the block whose top-face centre is top_center_m at pitch_rad with the fingers
    closing horizontally: open, move above the grasp point, straight down, grasp, straight up
    (approach_height_m). boxes: the other objects. Also how the block will sit in the gripper."""
    model = station.model
    config = station.motion_config
    q_start = station.start_position() if q_start is None else np.asarray(q_start, float)
    point = grasp_point(station, top_center_m, edge_m, pitch_rad)
    above = point + np.array([0.0, 0.0, config.approach_height_m])
    q_above = model.ik(above, pitch=pitch_rad, yaw=None, q_seed=_seed(q_start))
    descend = _vertical(station, q_above, float(point[2]), pitch_rad)
    lift = _vertical(station, descend.positions_rad[-1], float(above[2]), pitch_rad)
    move = _joint_move(station, q_start, q_above)
    _check(station, [move, descend, lift], boxes, None, edge_m)
    top = np.asarray(top_center_m, float)
    centre = top - np.array([0.0, 0.0, edge_m / 2.0])
    grip = np.asarray(model.fk(descend.positions_rad[-1]), float)
    heading = bearing_rad(top)
    block_axes = np.array([[math.cos(heading), -math.sin(heading), 0.0], [math.sin(heading), math.cos(heading), 0.0], [0.0, 0.0, 1.0]])
    grasp = SideGrasp(pitch_rad, grip[:3, :3].T @ (centre - grip[:3, 3]), grip[:3, :3].T @ block_axes)
    steps = [GripperStep("open before pick", "release"), TrajectoryStep("move above block", move),
             TrajectoryStep("descend to grasp", descend), GripperStep("grasp", "grasp"), TrajectoryStep("lift", lift)]
    return steps, grasp


def release_point(station: Station, surface_m, edge_m: float, grasp: SideGrasp, pitch_rad: float) -> np.ndarray:
    """Gripper point that puts the held block's bottom centre place_clearance_m above surface_m."""
    surface = np.asarray(surface_m, float)
    centre = surface + np.array([0.0, 0.0, edge_m / 2.0 + station.motion_config.place_clearance_m])
    rotation = gripper_rotation(station.model, pitch_rad, bearing_rad(surface))
    return centre - rotation @ grasp.centre_in_gripper_m


def block_tilt_rad(model, q_rad, grasp: SideGrasp) -> float:
    """Angle between the held block's body z and world z at joints q (what the judge calls upright)."""
    rotation = np.asarray(model.fk(np.asarray(q_rad, float)), float)[:3, :3] @ grasp.axes_in_gripper
    return float(math.acos(max(-1.0, min(1.0, rotation[2, 2]))))


def _place_approaches(station: Station, release_m: np.ndarray) -> list[tuple[np.ndarray, list[np.ndarray]]]:
    """(way in, way out) of a place: straight down from above and back up; else sliding in over the
    tower top from the base side or across it (the fingers stay above the held block's bottom), and
    out along the fingers (they straddle the block just released), then down and in to RETREAT_M."""
    inward = -release_m[:2] / max(np.linalg.norm(release_m[:2]), 1e-9)
    across = np.array([-inward[1], inward[0]])
    above = release_m + np.array([0.0, 0.0, station.motion_config.approach_height_m])
    clear = release_m + np.array([*(inward * FINGERS_OFF_M), 0.0])
    out = [clear, release_m + np.array([*(inward * RETREAT_M), -RETREAT_DROP_M])]
    return [(above, [above])] + [(release_m + np.array([*(side * SLIDE_IN_M), SLIDE_RISE_M]), out)
                                 for side in (inward, across, -across)]


def _exit(station: Station, q_from, then_rad: np.ndarray, boxes: list) -> list:
    """Legs from q_from to a pose from which a straight joint move to then_rad (the park pose) clears
    every box and the new tower (none if the straight move already does). Folding the arm straight
    down from beside a tall tower swings the elbow into it, so first the waist alone turns away (every
    arm point keeps its distance from the base axis, so the arm slides along the tower, not into it)."""
    toward = 1.0 if then_rad[0] >= q_from[0] else -1.0
    candidates = [None] + [q_from + np.array([sign * turn, 0.0, 0.0, 0.0, 0.0]) for turn in EXIT_TURNS_RAD for sign in (toward, -toward)]
    problem = ""
    for q_via in candidates:
        try:
            legs = [] if q_via is None else [_joint_move(station, q_from, q_via)]
            _check(station, legs, boxes, None, 0.0, margin_m=PARK_MARGIN_M)
            _check(station, [_joint_move(station, q_from if q_via is None else q_via, then_rad)], boxes, None, 0.0,
                   margin_m=PARK_MARGIN_M)
        except PLAN_REFUSALS as error:
            problem = str(error)
            continue
        return legs
    raise UnsafeTrajectory(f"no way from the tower to the park pose that clears it ({problem})")


def plan_side_place(station: Station, surface_m, edge_m: float, grasp: SideGrasp, boxes: list, q_start=None,
                    pitch_rad: float | None = None, then_rad=None) -> list:
    """Steps to set the block held as `grasp` says with its bottom centre on surface_m (a tower top or
    the board), at the grasp's pitch (or pitch_rad): joint move to the way in, straight to the release
    point, release, straight out. boxes: obstacles other than what stands at surface_m; the column
    under surface_m is added (the links keep clear of all but its top block, the held block of all).
    then_rad: where the arm goes next (the park pose): the plan ends where a joint move there is clear."""
    model = station.model
    pitch = grasp.pitch_rad if pitch_rad is None else pitch_rad
    q_start = station.start_position() if q_start is None else np.asarray(q_start, float)
    surface = np.asarray(surface_m, float)
    release = release_point(station, surface, edge_m, grasp, pitch)
    support = []
    if surface[2] > 0.005:
        support = [box_around("the tower under the place", surface[:2], edge_m / 2.0 + 0.004, surface[2])]
    links_support = [box_around("the tower below its top block", surface[:2], edge_m / 2.0 + 0.004, surface[2] - edge_m)] \
        if surface[2] - edge_m > 0.005 else []
    problem = "no way in"
    start_z = float(np.asarray(model.fk(q_start), float)[2, 3])
    for way_in, way_out in _place_approaches(station, release):
        try:
            q_in = model.ik(way_in, pitch=pitch, yaw=None, q_seed=_seed(q_start))
            slide = _line(station, q_in, release, pitch)
            back = []
            for point in way_out:
                back.append(_line(station, (back[-1] if back else slide).positions_rad[-1], point, pitch))
            _check(station, [slide], boxes + links_support, grasp, edge_m, boxes + support)
            _check(station, back, boxes + links_support, None, edge_m)
        except PLAN_REFUSALS as error:  # UnsafeTrajectory is a PlanRefused
            problem = str(error)
            continue
        # Over to the way in: straight there; else straight up first; else to the way in's arm shape turned
        # away about the waist (rising far from the tower), then the waist alone turns in above its top.
        toward_start = 1.0 if q_start[0] >= q_in[0] else -1.0
        routes = [[], *([("rise", z)] for z in np.arange(max(start_z, way_in[2]), way_in[2] + 0.2, 0.05)),
                  *([("via", q_in + np.array([toward_start * turn, 0.0, 0.0, 0.0, 0.0]))] for turn in EXIT_TURNS_RAD)]
        for route in routes:
            try:
                transfer, names = [], []
                q_from = q_start
                for kind, value in route:
                    if kind == "rise":
                        transfer.append(_vertical(station, q_from, float(value), model.pitch_of(q_from)))
                        names.append("rise to transfer height")
                    else:
                        transfer.append(_joint_move(station, q_from, value))
                        names.append("move up beside the tower")
                    q_from = transfer[-1].positions_rad[-1]
                transfer.append(_joint_move(station, q_from, q_in))
                names.append("move beside the place")
                _check(station, transfer, boxes + support, grasp, edge_m, boxes + support)
            except PLAN_REFUSALS as error:
                problem = str(error)
                continue
            exit_legs = [] if then_rad is None else _exit(station, back[-1].positions_rad[-1], np.asarray(then_rad, float),
                                                          boxes + [box_around("the tower", surface[:2], TOWER_BOX_HALF_M, surface[2] + edge_m)])
            return [*(TrajectoryStep(name, t) for name, t in zip(names, transfer)),
                    TrajectoryStep("slide to place", slide), GripperStep("release", "release"),
                    *(TrajectoryStep("retreat", t) for t in back), *(TrajectoryStep("clear of the tower", t) for t in exit_legs)]
    raise Unreachable(f"no side place at ({surface[0] * 1000:.0f}, {surface[1] * 1000:.0f}, {surface[2] * 1000:.0f}) mm "
                      f"at {math.degrees(pitch):.0f}° pitch: {problem}", "out of reach")


def plan_side_pick_place(station: Station, top_center_m, surface_m, edge_m: float, pick_boxes: list, place_boxes: list,
                         pitches_rad, q_start=None, then_rad=None) -> tuple[list, SideGrasp]:
    """The pick steps and grasp for the first of pitches_rad at which both the pick (from q_start) and
    the place after it (plan_side_place from the pick's end) plan and pass every check. Fingers only:
    another gripper type is refused (Unreachable) before anything is planned."""
    tool = station_end_effector(station)
    if not tool.holds_by_sides:
        raise Unreachable(f"a side grasp needs fingers closing on the block's sides: this station's gripper is a "
                          f"{tool.name} gripper", "out of reach")
    problems = []
    for pitch in pitches_rad:
        try:
            pick, grasp = plan_side_pick(station, top_center_m, edge_m, pick_boxes, pitch, q_start=q_start)
            end = [step for step in pick if isinstance(step, TrajectoryStep)][-1].q_end_rad
            plan_side_place(station, surface_m, edge_m, grasp, place_boxes, q_start=end, then_rad=then_rad)
        except PLAN_REFUSALS as error:
            problems.append(f"{math.degrees(pitch):.0f}°: {error}")
            continue
        return pick, grasp
    raise Unreachable("no pitch both picks and places the block: " + "; ".join(problems[-2:]), "out of reach")


def reachable_pitches(station: Station, top_center_m, surface_m, edge_m: float) -> list[float]:
    """Pitches (steepest first, 5° steps from top-down to MIN_PITCH_RAD) at which both the grasp of the
    block at top_center_m and its release on surface_m are within the arm's reach (IK only: no obstacles)."""
    model = station.model
    found = []
    pitch = math.pi / 2
    while pitch >= MIN_PITCH_RAD - 1e-9:
        try:
            point = grasp_point(station, top_center_m, edge_m, pitch)
            for target in (point, point + np.array([0.0, 0.0, station.motion_config.approach_height_m])):
                model.ik(target, pitch=pitch, yaw=None, q_seed=_seed(model.home_rad))
            fake = SideGrasp(pitch, *nominal_hold(station, top_center_m, edge_m, pitch))
            release = release_point(station, surface_m, edge_m, fake, pitch)
            model.ik(release, pitch=pitch, yaw=None, q_seed=_seed(model.home_rad))
            if not any(_reaches(model, way_in, pitch) and all(_reaches(model, p, pitch) for p in way_out)
                       for way_in, way_out in _place_approaches(station, release)):
                raise Unreachable("no way in", "out of reach")
            found.append(pitch)
        except Unreachable:
            pass
        pitch -= PITCH_STEP_RAD
    return found


def _reaches(model, point_m, pitch_rad: float) -> bool:
    try:
        model.ik(point_m, pitch=pitch_rad, yaw=None, q_seed=_seed(model.home_rad))
    except Unreachable:
        return False
    return True


def nominal_hold(station: Station, top_center_m, edge_m: float, pitch_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(block centre, block axes) in the gripper frame for a grasp at pitch_rad, without solving IK."""
    top = np.asarray(top_center_m, float)
    heading = bearing_rad(top)
    rotation = gripper_rotation(station.model, pitch_rad, heading)
    point = grasp_point(station, top, edge_m, pitch_rad)
    centre = top - np.array([0.0, 0.0, edge_m / 2.0])
    axes = np.array([[math.cos(heading), -math.sin(heading), 0.0], [math.sin(heading), math.cos(heading), 0.0], [0.0, 0.0, 1.0]])
    return rotation.T @ (centre - point), rotation.T @ axes
