"""The closed loop every autonomous job shares: park where the arm hides nothing → look → ask the job's
policy for the next move → plan (checked against limits, table and known objects) → pick → place →
look again. A failed move is retried up to a bound, then given up with a reason; the job goes on.

A job is a policy: a function from what is seen (a Scene view of detections) to candidate moves in
order of preference (policy.py: Move, Plan, Policy and the helpers policies share). The runner owns the arm
through the gate (armlab.station) via armlab.skills; where it parks the arm to look: look_poses.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from armlab import skills
from armlab.errors import PLAN_REFUSALS
from armlab.motion import TrajectoryStep, plan_joint_move
from armlab.motion.cartesian import plan_vertical_segment
from armlab.motion.clearance import OBJECT_BOX_RADIUS_M, box_around, first_collision
from armlab.motion.gripper_box import joint_moves_inside
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills import side_grasp
from armlab.skills.manipulate import plan_pick, plan_place, plan_side_place, run_steps
from armlab.skills.pick_check import PickCheckSettings, pick_summary, run_pick
from armlab.station.core import Station
from armlab.station.held import HeldBlock
from armlab.station.jobs import JobContext
from armlab.station.telemetry import block_to_dict
from armlab.tasks.look_poses import look_pose, park_pose
from armlab.tasks.place_check import PlaceCheck, first_passing_target
from armlab.tasks.policy import Move, NoFreeSpot, Policy, blocks_seen, confirm_finish, finger_axis_away, near
from armlab.tasks.seen import Seen, StandingObject
from armlab.vision.block import Block
from armlab.vision.geometry import project_points

MAX_ATTEMPTS_PER_MOVE = 3
MAX_LOOKS = 200  # a job that has looked this often without finishing stops (no endless loops)
MAX_CONFIRM_LOOKS = 2  # looks again, at most this often a run, when it would finish seeing fewer blocks than before
PARK_CLEARANCE_M = 0.0  # the sleep pose is low beside the base: its body may pass right by the boxes around blocks
PARK_RISE_Z_M = 0.32  # how high the gripper rises before parking when the straight way is blocked
PARK_FRONT_VIA_M = (0.0, 0.16, 0.16)  # else through here, in front of the base, clear of it and of the board
REACH_REGION_M = ((-0.34, 0.34), (-0.15, 0.34))  # every board spot free_spot can offer (its reach band cuts it)


@dataclass
class Progress:
    done: int = 0
    left: int = 0
    step: str = ""
    attempts: int = 0
    failures: list[str] = field(default_factory=list)
    moves: int = 0
    next_block: Block | None = None
    next_block_id: int | None = None  # its index among the look's detections (the wire's "id")
    next_target_m: list[float] | None = None

    def to_dict(self) -> dict:
        """The job's extra.task (server/auto_models.py TaskProgress): next_block as a detection's wire dict."""
        next_block = None if self.next_block is None else block_to_dict(self.next_block_id, self.next_block)
        return {"done": self.done, "left": self.left, "step": self.step, "attempts": self.attempts,
                "failures": list(self.failures), "moves": self.moves, "next_block": next_block,
                "next_target_m": self.next_target_m}


def pick_end_joints(steps: list) -> np.ndarray:
    """The joints a plan's last trajectory ends at."""
    return [step for step in steps if isinstance(step, TrajectoryStep)][-1].q_end_rad


class TaskRunner:
    """Runs a policy to completion through the gate; see the module docstring."""

    def __init__(self, station: Station, ctx: JobContext, name: str) -> None:
        self.station = station
        self.ctx = ctx
        self.name = name
        self.progress = Progress()
        self._attempts: dict[tuple, int] = {}
        self._given_up: set[tuple] = set()
        self.edges_m = {size: float(getattr(station.perception_config.blocks, f"{size}_size_m")) for size in ("large", "small")}
        self.max_transfer_z_m = 0.42  # a job may lower it (pick_stack keeps the gripper under 300 mm)
        self.last_objects: list[Seen] = []  # the newest look's objects (obstacles while parking)
        self.detections: list[Block] = []  # the newest look's detections, in order (a block's index is its wire id)
        self.reserved_m: list[tuple[float, float]] = []  # spots a job keeps free (column bases, line slots)
        self.look_pose_rad = look_pose(station)  # where the arm waits while the camera looks (a job may change it)
        self.keep_occluded = False  # a job that must find every block acts also on those the parked arm partly hides
        self.gripper_box = None  # a GripperBox every planned motion keeps the gripper point inside (pick_stack)
        self.time_limit_s: float | None = None  # the event's limit (station clock): no new move starts after it
        config = station.config
        self.place_check = PlaceCheck(config.place_check, config.place_corrections, config.place_correction_max_m,
                                      lambda level, words: station.events.add(level, f"{name}: {words}"))
        self.pick_check = PickCheckSettings(config.pick_check, config.pick_corrections, config.pick_correction_max_m)
        self.pick_records: list[dict] = []  # the closed loop before each pick's last descent (job result pick_check)

    # Reporting -------------------------------------------------------------------------------------

    def report(self, step: str) -> None:
        self.progress.step = step
        total = self.progress.done + self.progress.left
        self.ctx.progress(self.progress.done / total if total else 0.0, step)
        self.ctx.job.update_extra(task=self.progress.to_dict())

    def note_once(self, reason: str) -> None:
        """A failure reported once however often the policy meets it (e.g. a block it must leave)."""
        if reason not in self.progress.failures:
            self.fail(reason)

    def fail(self, reason: str) -> None:
        self.progress.failures.append(reason)
        self.station.events.add("warn", f"{self.name}: {reason}")

    # Arm -------------------------------------------------------------------------------------------

    def park(self) -> None:
        """Move to the park pose (park_pose: the arm hides no block from the camera) by a path that keeps
        clear of the objects seen last (straight there, else up first, else up and over the base)."""
        model = self.station.model
        q_park = self.look_pose_rad
        self.progress.next_block = self.progress.next_block_id = self.progress.next_target_m = None  # no move planned until the next look
        q_now = self.station.joints_rad()
        if np.abs(q_now - q_park).max() <= 0.02:
            return
        self.report("parking to look")
        boxes = self.boxes(self.last_objects)
        config = self.station.motion_config
        routes = [[]]
        try:
            rise_z_m = PARK_RISE_Z_M if self.gripper_box is None else min(PARK_RISE_Z_M, self.gripper_box.max_m[2])
            rise = plan_vertical_segment(model, q_now, max(rise_z_m, model.fk(q_now)[2, 3]), speed_m_s=config.vertical_speed_m_s,
                                         accel_m_s2=config.vertical_accel_m_s2, rate_hz=config.sample_rate_hz)
            routes.append([rise.positions_rad[-1]])
            routes.append([rise.positions_rad[-1], model.ik([0.0, 0.12, rise_z_m], q_seed=q_park)])
        except PLAN_REFUSALS:
            pass
        try:  # out in front first: from the sleep pose, the drooping real arm's straight way passes by its base
            routes.append([model.ik(PARK_FRONT_VIA_M, pitch=None, yaw=None, q_seed=q_park)])
        except PLAN_REFUSALS:
            pass

        def joint_move(q_a, q_b):
            return plan_joint_move(q_a, q_b, model, None, None, config.sample_rate_hz)

        for via in routes:
            legs, q_from = [], q_now
            try:
                for q_to in [*via, q_park]:
                    legs += joint_moves_inside(model, q_from, q_to, self.gripper_box, joint_move)
                    q_from = q_to
                for leg in legs:  # the gate's own body check (the arm's base, the board): the calibrated arm,
                    self.station.check_body(leg)  # drooping, passes nearer its base than the nominal one
            except PLAN_REFUSALS:  # an IK point a hair outside a limit, or a leg through the arm's base: the next route
                continue
            if all(first_collision(model, leg, boxes, margin_m=PARK_CLEARANCE_M) is None for leg in legs):
                for leg in legs:
                    self.station.run_trajectory(self.ctx, leg)
                return
        self.fail("no collision-free way to the park pose; parking straight")
        self.station.move_in_job(self.ctx, q_park)

    def look(self) -> list[Seen]:
        """Detections of a fresh frame taken with the arm parked (occluded ones left out, unless the job
        keeps the blocks among them: keep_occluded), and the columns it missed (unseen_columns)."""
        self.park()
        self.report("looking")
        self.detections = skills.look(self.station, self.ctx)
        objects: list[Seen] = [o for o in self.detections if not o.occluded or (self.keep_occluded and o.is_cube)]
        self.last_objects = objects + self.unseen_columns(objects)
        return self.last_objects

    def unseen_columns(self, objects: list[Seen]) -> list[StandingObject]:
        """Obstacles the detector missed at the job's reserved spots (e.g. a column too tall for it):
        wherever depth measures something standing there and no detection is near, an object of
        that height that no policy picks (is_cube False, no colour)."""
        found = []
        for xy in self.reserved_m:
            if any(near(o.position_m, xy, 0.03) for o in objects):
                continue
            height = self.height_at(xy)
            if height > 0.005:
                found.append(StandingObject.at(xy, height))
        return found

    def boxes(self, objects: list[Seen], *exclude: Seen) -> list:
        """Obstacle boxes around every detected object except `exclude`."""
        skip = {id(o) for o in exclude}
        return [box_around(f"{o.color} {o.size or 'object'} at ({o.position_m[0] * 1000:.0f}, "
                           f"{o.position_m[1] * 1000:.0f}) mm", o.position_m, OBJECT_BOX_RADIUS_M, o.position_m[2])
                for o in objects if id(o) not in skip]

    def edge_of(self, block: Seen) -> float:
        return self.edges_m.get(block.size or "large", self.edges_m["large"])

    def detection_id(self, block: Block) -> int | None:
        """The block's index among the newest look's detections (its wire id), None for a block not among them
        (a Block equals only itself)."""
        return self.detections.index(block) if block in self.detections else None

    def execute(self, move: Move, objects: list[Seen]) -> bool:
        """Pick move.block and place it at move.to_m; True if the block was held and released there.

        Both the pick and the place are planned (and checked) before the arm moves, the place from
        where the pick ends, so a block is never picked up that cannot be put where it should go."""
        block = move.block
        edge = self.edge_of(block)
        intended = np.asarray(move.to_m, float)
        to = self.place_check.target_for(intended)  # shifted by what the last looks saw remain there
        name = f"{block.color} {block.size} block"
        below = [o for o in objects if o is not block and near(o.position_m, to, 0.02) and abs(o.position_m[2] - to[2]) < 0.01]
        place_boxes = self.boxes(objects, block, *below)
        yaw = block.yaw_rad if move.yaw_rad is None else move.yaw_rad
        axis = move.finger_axis_rad
        if axis is None:
            axis = finger_axis_away(to, yaw or 0.0, [o for o in objects if o is not block and o not in below], block)
        self.progress.next_block, self.progress.next_block_id = block, self.detection_id(block)
        self.progress.next_target_m = [float(v) for v in to]
        grasp = None  # how a side-grasped block sits in the gripper (move.grasp_pitches_rad)
        if skills.is_stale(self.station, block):
            self.fail(f"the {name} was seen before the arm last moved over it: looking again")
            return False

        def plan_the_place(q_start=None) -> list:
            if move.grasp_pitches_rad:
                return side_grasp.plan_side_place(self.station, to, edge, grasp, place_boxes, q_start=q_start,
                                                  then_rad=park_pose(self.station.model))
            try:
                return plan_place(self.station, to, yaw, edge, place_boxes, q_start=q_start, max_transfer_z_m=self.max_transfer_z_m,
                                  finger_axis_rad=axis, max_tilt_rad=move.max_tilt_rad, gripper_box=self.gripper_box)
            except PLAN_REFUSALS:
                if not move.side_ok:
                    raise
                return plan_side_place(self.station, to, edge, place_boxes, q_start=q_start)

        try:
            if move.grasp_pitches_rad:
                pick, grasp = side_grasp.plan_side_pick_place(self.station, block.position_m, to, edge, self.boxes(objects, block),
                                                              place_boxes, move.grasp_pitches_rad, then_rad=park_pose(self.station.model))
            else:
                pick = plan_pick(self.station, block.position_m, block.yaw_rad, edge, self.boxes(objects, block),
                                 max_transfer_z_m=self.max_transfer_z_m, gripper_box=self.gripper_box,
                                 finger_axis_rad=finger_axis_away(block.position_m, block.yaw_rad or 0.0, objects, block))
        except PLAN_REFUSALS as error:
            self.fail(f"cannot pick the {name} at ({block.position_m[0] * 1000:.0f}, {block.position_m[1] * 1000:.0f}) mm: {error}")
            return False

        def plan_at(target) -> list:  # plan_the_place from the pick's end, for this target
            nonlocal to
            to = target
            return plan_the_place(pick_end_joints(pick))

        try:
            to = first_passing_target(plan_at, to, intended, self.fail)
        except PLAN_REFUSALS as error:
            self.fail(f"cannot place the {name} at ({to[0] * 1000:.0f}, {to[1] * 1000:.0f}, {to[2] * 1000:.0f}) mm: {error}")
            return False
        self.report(f"picking the {name}: {move.why}")
        if not self.run_or_fail(pick, f"picking the {name}", self.boxes(objects, block)):
            return False
        if not self.station.gripper.read_state().holding:
            self.fail(f"missed the {name} (nothing in the gripper)")
            return False
        self.station.set_held_block(HeldBlock(edge_m=edge, color=block.color, size=block.size))
        try:
            place = plan_the_place()
        except PLAN_REFUSALS as error:
            self.fail(f"cannot place the {name} at ({to[0] * 1000:.0f}, {to[1] * 1000:.0f}, {to[2] * 1000:.0f}) mm: {error}")
            self.put_down_held(objects)
            return False
        self.report(f"placing the {name}: {move.why}")
        if not self.run_or_fail(place, f"placing the {name}"):
            return False
        self.station.set_held_block(None)
        self.place_check.placed(intended, to, edge, name)
        self.progress.moves += 1
        placed = replace(block, position_m=np.array([float(to[0]), float(to[1]), float(to[2] + edge)]))
        self.last_objects = [o for o in self.last_objects if o is not block] + [placed]
        if move.on_placed is not None:
            move.on_placed(edge)
        return True

    def run_or_fail(self, steps: list, what: str, pick_boxes: list | None = None) -> bool:
        """Run planned steps (a pick's, given its obstacle boxes: with the closed loop before its last descent,
        armlab.skills.pick_check); a step the gate refuses (the arm is not where the plan starts, e.g. it
        was stopped by a contact) fails the move with the reason, puts down what is held, and the
        job goes on from a fresh look."""
        try:
            if pick_boxes is None:
                run_steps(self.station, self.ctx, steps, progress=False)
            else:
                log = lambda level, words: self.station.events.add(level, f"{self.name}: {words}")  # noqa: E731
                record = run_pick(self.station, self.ctx, steps, self.pick_check, pick_boxes, what, log, self.gripper_box)
                if record is not None:
                    self.pick_records.append(record)
        except UnsafeTrajectory as error:
            self.fail(f"{what}: the gate refused a step ({error})")
            if self.station.gripper.read_state().holding:
                self.put_down_held(self.last_objects)
            return False
        return True

    def put_down_held(self, objects: list[Seen] | None = None) -> str:
        """Set a held block down on a free spot of the board (after a failure or a cancel)."""
        held = self.station.held_block
        self.station.wait_gripper()  # a cancel during a grasp: let the fingers settle before asking
        if not self.station.gripper.read_state().holding:
            self.station.set_held_block(None)
            return "nothing in the gripper"
        edge = float(held.edge_m if held is not None else self.edges_m["large"])
        spot = self.free_spot(objects or [], edge)
        place = plan_place(self.station, (spot[0], spot[1], 0.0), 0.0, edge, self.boxes(objects or []),
                           max_transfer_z_m=self.max_transfer_z_m, gripper_box=self.gripper_box)
        run_steps(self.station, self.ctx, place, progress=False)
        self.station.set_held_block(None)
        return f"put the held block down at ({spot[0] * 1000:.0f}, {spot[1] * 1000:.0f}) mm"

    # Space -----------------------------------------------------------------------------------------

    def free_spot(self, objects: list[Seen], edge_m: float, region=None, avoid_m: list | None = None,
                  allowed: Callable[[tuple[float, float]], bool] | None = None) -> tuple[float, float]:
        """A reachable board spot in `region` ((x_min, x_max), (y_min, y_max); default y > 0.06) at least
        one block plus a finger gap from every object and `avoid_m` point (and where allowed(x, y), if given),
        the one farthest from them whose block the arm, waiting at look_pose_rad, leaves in the camera's view
        (a block beside the parked gripper reads occluded, and a job leaves occluded blocks where they are)."""
        (x_min, x_max), (y_min, y_max) = region or ((-0.30, 0.30), (0.08, 0.32))
        taken = [o.position_m[:2] for o in objects] + [p[:2] for p in (avoid_m or [])] + list(self.reserved_m)
        gap = edge_m / 2 + 0.019 + 0.03
        scored = []
        for x in np.arange(x_min, x_max + 1e-9, 0.02):
            for y in np.arange(y_min, y_max + 1e-9, 0.02):
                r = math.hypot(x, y)
                if not 0.14 <= r <= 0.34 or any(math.dist((x, y), tag) < 0.045 for tag in self.tag_centres()):
                    continue
                if allowed is not None and not allowed((float(x), float(y))):
                    continue
                clearance = min((math.dist((x, y), t) for t in taken), default=1.0)
                if clearance >= gap:
                    scored.append((-clearance, float(x), float(y)))
        scored.sort()  # stable: among equals the first in the scan, as before
        for _, x, y in scored:
            if not skills.arm_hides_block(self.station, self.look_pose_rad, (x, y), edge_m):
                return (x, y)
        raise NoFreeSpot("no free spot on the board to put a block aside" + (" that the parked arm leaves in view" if scored else ""))

    def free_spot_in_reach(self, objects: list[Seen], edge_m: float, region=None,
                           rules: tuple[Callable[[tuple[float, float]], bool] | None, ...] = (None,)) -> tuple[float, float]:
        """free_spot in `region`, else anywhere in the arm's reach (REACH_REGION_M), for each allowed-rule of `rules`
        in turn (None: anywhere); NoFreeSpot with the last search's reason when none has a spot."""
        error = NoFreeSpot("no free spot on the board to put a block aside")
        for rule in rules:
            for where in (region, REACH_REGION_M):
                try:
                    return self.free_spot(objects, edge_m, region=where, allowed=rule)
                except NoFreeSpot as refused:
                    error = refused
        raise error

    def height_at(self, xy_m) -> float:
        """Measured height of what stands at (x, y) in the newest look's depth image (0 = board)."""
        return skills.surface_height_m(self.station, xy_m)

    def clear_of_park(self, xy_m, clearance_m: float = 0.09) -> bool:
        """True if a tall column at (x, y) keeps clear of the arm's way into its park pose (the vertical
        plane through the base axis and the parked gripper, out to 0.22 m)."""
        park_xy = self.station.model.fk(self.look_pose_rad)[:2, 3]  # the way down to it
        direction = park_xy / max(np.linalg.norm(park_xy), 1e-9)
        along = float(np.clip(np.dot(xy_m, direction), 0.0, 0.22))
        return float(np.linalg.norm(np.asarray(xy_m) - along * direction)) >= clearance_m

    def in_view(self, xy_m, height_m: float, margin_px: float = 40.0) -> bool:
        """True if a column at (x, y) up to height_m stays inside the camera image (so it can be measured)."""
        calibration = self.station.calibration
        points = np.array([[xy_m[0], xy_m[1], z] for z in (0.0, height_m)])
        pixels = project_points(calibration.T_world_camera, calibration.K, calibration.dist, points)
        return bool(np.all((pixels >= margin_px) & (pixels <= np.array([calibration.width, calibration.height]) - margin_px)))

    def can_place_on(self, surface_m, edge_m: float) -> bool:
        """True if a block of edge_m can be set down top-down on surface_m from here (obstacles aside)."""
        try:
            plan_place(self.station, surface_m, 0.0, edge_m, [], max_transfer_z_m=self.max_transfer_z_m, gripper_box=self.gripper_box)
        except PLAN_REFUSALS:
            return False
        return True

    def feed_spot(self) -> tuple[float, float] | None:
        """The simulated feeder's spot (to keep clear), when the scene has a feeder."""
        sim = self.station.sim
        feeder = sim.truth().get("feeder") if sim is not None else None
        return None if not feeder else tuple(map(float, feeder["spot_m"]))

    def tag_centres(self) -> list[tuple[float, float]]:
        return [tuple(map(float, xy)) for xy in self.station.perception_config.tags.board_tags.values()]

    # The loop --------------------------------------------------------------------------------------

    def out_of_time(self, started_s: float) -> bool:
        """True (and said once) when the job has used its event's time limit: a job ends within its event's
        limit (a stack_high run once went on for 3,108 s simulated), with the blocks placed so far."""
        if self.time_limit_s is None or self.station.clock_s() - started_s < self.time_limit_s:
            return False
        self.fail(f"stopped at the event's time limit ({self.time_limit_s:.0f} s): {self.progress.left} block(s) left")
        return True

    def run(self, policy: Policy) -> dict:
        """Look, move, repeat until the policy is finished or has nothing left it can try."""
        seen_before, confirm_looks = None, 0
        started_s = self.station.clock_s()
        for _ in range(MAX_LOOKS):
            if self.out_of_time(started_s):
                break
            objects = self.look()
            self.place_check.check(objects)
            plan = policy(objects, self._given_up)
            self.progress.done, self.progress.left = plan.done, plan.left
            seen_now = blocks_seen(objects)
            if confirm_looks < MAX_CONFIRM_LOOKS and confirm_finish(plan, seen_now, seen_before):
                confirm_looks += 1
                self.station.events.add("info", f"{self.name}: {seen_now} block(s) seen, {seen_before} before: looking again")
                continue
            seen_before = seen_now
            moves = [m for m in plan.moves if m.key() not in self._given_up]
            if plan.finished or not moves:
                if not plan.finished:
                    self.fail(f"{plan.left} block(s) left that no move can reach")
                break
            move = moves[0]
            key = move.key()
            self._attempts[key] = self._attempts.get(key, 0) + 1
            self.progress.attempts += 1
            if not self.execute(move, objects) and self._attempts[key] >= MAX_ATTEMPTS_PER_MOVE:
                self._given_up.add(key)
                self.fail(f"gave up on the {move.block.color} {move.block.size} block after "
                          f"{MAX_ATTEMPTS_PER_MOVE} attempts")
        if self.place_check.pending:  # the last place's check: one more look
            self.place_check.check(self.look())
        self.park()
        self.report("finished")
        return {**self.progress.to_dict(), "place_check": self.place_check.summary(), "pick_check": pick_summary(self.pick_records)}
