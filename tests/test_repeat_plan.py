"""Planning a repeat (armlab.skills.repeat_plan) against a stand-in station whose motion check is scripted:
stops where something happens, blending elsewhere, the ease-in by way of home when the straight way is
refused, and the failing segment named."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills.repeat_plan import RepeatSettings, plan_cycle, plan_ease_in
from armlab.station.checks import checked_joints
from armlab.station.motion_check import MotionCheck
from armlab.store import Program, Waypoint

ARM = load_arm("rx200")
LOW = np.array([0.9, 0.3, 0.2, 1.0, 0.0])
SIDE = np.array([-0.9, 0.3, 0.2, 1.0, 0.0])


class FakeStation:
    """What the planner uses of a Station: model, sim (none: no ticks), checked_joints, check_motion, check_poses."""

    def __init__(self, refuse=lambda trajectory: None) -> None:
        self.model, self.sim, self.refuse = ARM, None, refuse

    def checked_joints(self, q):
        return checked_joints(ARM, q)

    def check_motion(self, trajectory) -> None:
        reason = self.refuse(trajectory)
        if reason:
            raise UnsafeTrajectory(reason)

    check_pose = MotionCheck.check_pose  # the station's own: a standing arm through check_motion
    check_poses = MotionCheck.check_poses  # the station's own: naming the waypoint


def _through_front_low(trajectory) -> str | None:
    """Refuse a path that sweeps the waist across 0 while the shoulder is down (a scripted obstacle)."""
    q = trajectory.positions_rad
    crossing = (np.abs(q[:, 0]) < 0.05) & (q[:, 1] > 0.1)
    return "the gripper point at z = -3.0 mm is below the board" if crossing.any() else None


def test_the_ease_in_goes_by_way_of_home_when_the_straight_way_is_refused():
    station = FakeStation(_through_front_low)
    points, run, labels = plan_ease_in(station, LOW, SIDE, 100.0, RepeatSettings())
    assert len(points) == 3 and np.allclose(points[1], ARM.home_rad) and labels[1] == 10**9
    assert np.allclose(run.trajectory.positions_rad[-1], SIDE) and len(run.arrival_s) == 3
    direct, _, _ = plan_ease_in(FakeStation(), LOW, SIDE, 100.0, RepeatSettings())
    assert len(direct) == 2  # nothing refused: straight


def test_the_ease_in_refusal_names_the_straight_way_when_home_does_not_help_either():
    station = FakeStation(lambda trajectory: "the elbow origin is below the board")
    with pytest.raises(UnsafeTrajectory, match="segment from the current pose to waypoint 1"):
        plan_ease_in(station, LOW, SIDE, 100.0, RepeatSettings())


def test_stops_at_gripper_steps_and_dwells_and_blends_between():
    a, b, c, d = (np.array(v) for v in ([0.0, -0.3, 0.3, 0.9, 0.0], [0.4, 0.0, 0.3, 1.0, 0.0], [0.8, 0.2, 0.1, 1.1, 0.3],
                                        [0.4, -0.2, 0.0, 1.2, 0.3]))
    program = Program(1, "p", 0.0, (
        Waypoint(tuple(a), "release"), Waypoint(tuple(b), "release"), Waypoint(tuple(c), "release"),
        Waypoint(tuple(c), "grasp"), Waypoint(tuple(d), "grasp", 0.4),
    ))
    plan = plan_cycle(FakeStation(), program, 100.0)
    kinds = [(step.kind, step.waypoint) for step in plan.steps]
    assert kinds == [("move", 2), ("gripper", 3), ("move", 4), ("dwell", 4), ("move", 0), ("gripper", 0)]
    assert plan.steps[0].points == (0, 1, 2) and plan.steps[0].run.blended  # through waypoint 2 without stopping
    assert plan.steps[-1].closing and plan.steps[-2].closing
    assert plan.cycle_s == pytest.approx(sum(step.duration_s for step in plan.steps))
    assert plan.last_cycle_s == pytest.approx(plan.cycle_s - plan.steps[-1].duration_s - plan.steps[-2].duration_s)


def test_a_refused_blend_falls_back_to_stops_and_a_refused_segment_is_named():
    program = Program(1, "p", 0.0, tuple(Waypoint(tuple(q), "release") for q in (LOW, [0.5, 0.3, 0.2, 1.0, 0.0], SIDE)))
    blends_refused = FakeStation(lambda t: "too close" if len(t.times_s) > 2 and _moving_at_a_waypoint(t) else None)
    plan = plan_cycle(blends_refused, program, 100.0)
    assert not plan.steps[0].run.blended
    with pytest.raises(UnsafeTrajectory, match="segment from waypoint 2 to waypoint 3"):
        plan_cycle(FakeStation(_through_front_low), program, 100.0)
    with pytest.raises(ValueError, match="waypoint 2: joint 'shoulder'"):
        plan_cycle(FakeStation(), Program(1, "p", 0.0, (Waypoint(tuple(LOW), "release"), Waypoint((0, 2.5, 0, 0, 0), "release"))), 100.0)


def _moving_at_a_waypoint(trajectory) -> bool:
    """True when the path passes waypoint 2 ([0.5, ...]) while moving (a blend)."""
    q = trajectory.positions_rad
    near = np.flatnonzero(np.abs(q[:, 0] - 0.5) < 1e-9)
    return any(0 < i < len(q) - 1 and abs(q[i + 1, 0] - q[i - 1, 0]) > 1e-4 for i in near)


def test_the_ease_in_is_at_the_safe_speed_whatever_the_override():
    from armlab.motion.safety import finite_difference_rates

    settings = RepeatSettings()
    for speed in (100.0, 60.0):
        _, run, _ = plan_ease_in(FakeStation(), LOW, SIDE, speed, settings)
        velocity, accel = finite_difference_rates(run.trajectory)
        assert np.all(np.abs(velocity).max(axis=0) <= np.asarray(ARM.velocity_limit_rad_s) * settings.ease_in_speed_fraction + 1e-9)
        assert np.all(np.abs(accel).max(axis=0) <= np.asarray(ARM.accel_limit_rad_s2) * settings.ease_in_speed_fraction**2 + 1e-9)
    _, slow, _ = plan_ease_in(FakeStation(), LOW, SIDE, 10.0, settings)  # slower still when the override is lower
    assert slow.duration_s > run.duration_s
