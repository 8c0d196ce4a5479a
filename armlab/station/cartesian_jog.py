"""Hold-to-run Cartesian jog of the gate, and the stop of any hold-to-run jog (joint or Cartesian).

A command object core.Station owns (station.cartesian), beside the joint jog (manual.py); it has no state of its own
(the running jog is the station's `_jog`, shared with the joint jog and ended by e-stop and a lease release).
The gripper point moves along a world axis at a signed speed in m/s (scaled by the operator's speed_percent) keeping its pitch and yaw, planned by
armlab.motion.cartesian_jog on the line where the jog began. Like the joint jog it runs jog_hold_s past its last
heartbeat (heartbeat() in manual.py re-plans it) and then brakes by itself, so a released button, a hung page or a
dropped connection stops it with no timer involved. A jog of another axis (or a joint jog, or a move) still running
is first brought to rest, then the new line starts from there. Each plan is checked by the station's own trajectory check
sample by sample (joint limits, the board, the arm against itself): where the line cannot go on, it brakes before
that place and the event log says why once; a jog asked to start there is refused with the reason (422).
"""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.motion.blend import arm_limits
from armlab.motion.cartesian_jog import AXES, MOVES_M, jog_line, plan_cartesian_jog
from armlab.motion.errors import StepRefused
from armlab.motion.jog import plan_jog
from armlab.motion.safety import UnsafeTrajectory
from armlab.station.manual import checked_speed_percent
from armlab.station.planned_moves import joined

AT_REST_M_S = 1e-4  # the handover moves slower than this along the line: the jog starts from rest


class CartesianJog:
    """jog_cartesian (hold-to-run along x, y or z) and stop_jog (either kind of jog ramps down now). station: the
    core.Station that owns it."""

    def __init__(self, station) -> None:
        self._station = station

    def jog_cartesian(self, axis: str, velocity_m_s, source: str | None = None, speed_percent: float = 100.0) -> JointTrajectory:
        """Move the gripper point along world `axis` at velocity_m_s (signed, |v| <= jog_max_speed_m_s, scaled by
        speed_percent) for jog_hold_s, keeping its pitch and yaw, then stop by itself; sending it again (or
        heartbeat()) within jog_hold_s keeps it going on the same line; 0 ramps down to rest. InvalidInput for bad
        numbers or an unknown axis; StepRefused (422) with the reason when the line cannot go on from here."""
        self._station.require_arm("jog")
        config = self._station.motion_config
        if axis not in AXES:
            raise InvalidInput(f"axis must be one of {', '.join(AXES)}, got {axis!r}")
        velocity = _checked_velocity_m_s(velocity_m_s, config.jog_max_speed_m_s)
        velocity *= checked_speed_percent(speed_percent) / 100.0
        self._station.allowed_or_raise("jog", source)
        dt = 1.0 / config.sample_rate_hz
        outcome: dict = {}

        def plan(handover) -> JointTrajectory:
            with self._station._lock:
                running = self._station._jog
            if handover is None:
                q0, qdot0, hold_s = self._station.start_position(), None, config.jog_hold_s
            else:
                q0, qdot0 = handover.position_rad, handover.segment_velocity_rad_s
                hold_s = max(config.jog_hold_s - (handover.takes_over_s - self._station.clock_s()), dt)
            ours = running is not None and running["source"] == source and self._station.arm.is_moving()
            same_line = handover is not None and ours and running.get("axis") == axis
            # Another motion runs (or, taken over before this line's own motion began, is still braking): to rest first.
            braking = same_line and handover.takes_over_s < running["line_from_s"]
            brake, brake_from = None, None
            if handover is not None and not handover.at_rest and (braking or not same_line):
                brake_from = running["brake_from"] if braking else (running if ours and "axis" in running else None)
                brake = self._brake(handover, brake_from)
                q0, qdot0, hold_s = brake.positions_rad[-1], None, max(hold_s - brake.duration_s, dt)
                outcome.update(line_from_s=handover.takes_over_s + brake.duration_s,
                               brake_from=None if brake_from is None else {"axis": brake_from["axis"], "line": brake_from["line"]})
            line = running["line"] if same_line else jog_line(self._station.model, q0, axis)
            v0 = 0.0 if qdot0 is None else line.speed_m_s(self._station.model, q0, qdot0, dt)
            if abs(v0) < AT_REST_M_S:
                v0 = 0.0
            jog = plan_cartesian_jog(self._station.model, line, q0, v0, velocity, hold_s, config.jog_accel_m_s2,
                                     config.sample_rate_hz, self._first_unsafe)
            if velocity != 0.0 and v0 == 0.0 and jog.travel_m < MOVES_M and jog.stopped_by is not None:
                raise StepRefused(f"{_label(axis, velocity)} cannot move from here: {jog.stopped_by}", "boundary")
            outcome.update(line=line, stopped_by=jog.stopped_by,
                           reported=same_line and running.get("reported") is not None)
            return jog.trajectory if brake is None else joined([brake, jog.trajectory])

        trajectory, _ = self._station.gate.send_replacing(plan, lambda: self._station._transition("jog", source=source), "jog")
        reason = outcome["stopped_by"]
        with self._station._lock:
            self._station._jog = {"trajectory": trajectory, "start_s": self._station.clock_s(), "velocity": velocity, "source": source,
                         "axis": axis, "line": outcome["line"], "reported": reason,
                         "line_from_s": outcome.get("line_from_s", -math.inf), "brake_from": outcome.get("brake_from")}
        if reason is not None and not outcome["reported"]:
            self._station.events.add("warn", f"{_label(axis, velocity)} stops short: {reason}")
        return trajectory

    def stop_jog(self, source: str | None = None) -> bool:
        """The controller let go: its running hold-to-run jog (joint or Cartesian) ramps down to rest now instead of
        jog_hold_s later. False (nothing changes) when it has no jog running."""
        return self._station.manual._reissue_jog(source, stop=True)

    def _brake(self, handover, running: dict | None) -> JointTrajectory:
        """The motion running at `handover` brought to rest at once, before a jog of another kind or axis starts from
        there (the new line's plan from rest would not continue its velocity): along its own line when it is a
        Cartesian jog (`running`: its axis and line), else each joint at its acceleration limit (the joint jog's)."""
        config, model = self._station.motion_config, self._station.model
        dt = 1.0 / config.sample_rate_hz
        q0, qdot0 = handover.position_rad, handover.segment_velocity_rad_s
        if running is not None:
            line = running["line"]
            return plan_cartesian_jog(model, line, q0, line.speed_m_s(model, q0, qdot0, dt), 0.0, dt, config.jog_accel_m_s2, config.sample_rate_hz,
                                      self._first_unsafe).trajectory
        return plan_jog(q0, qdot0, np.zeros_like(qdot0), dt, model.lower_rad, model.upper_rad,
                        arm_limits(model).accel_rad_s2, config.sample_rate_hz)

    def _first_unsafe(self, trajectory: JointTrajectory) -> tuple[int, str] | None:
        """(index of the first sample the station's trajectory check refuses, the reason), or None when it passes
        whole: the shortest failing prefix, found by halving (a few checks, only when the whole fails)."""
        try:
            self._station.check_motion(trajectory)
            return None
        except UnsafeTrajectory as error:
            reason = str(error)
        passing, failing = 1, len(trajectory.times_s)  # a prefix of one sample has nothing to fail
        while failing - passing > 1:
            middle = (passing + failing) // 2
            try:
                self._station.check_motion(JointTrajectory(trajectory.times_s[:middle], trajectory.positions_rad[:middle]))
                passing = middle
            except UnsafeTrajectory as error:
                failing, reason = middle, str(error)
        return failing - 1, reason


def _checked_velocity_m_s(velocity_m_s, limit_m_s: float) -> float:
    """A finite signed speed in m/s within the jog's top speed, else InvalidInput."""
    if isinstance(velocity_m_s, bool) or not isinstance(velocity_m_s, (int, float)) or not math.isfinite(float(velocity_m_s)):
        raise InvalidInput(f"velocity_m_s must be a finite number of metres per second, got {velocity_m_s!r}")
    if abs(float(velocity_m_s)) > limit_m_s + 1e-12:
        raise InvalidInput(f"velocity_m_s {float(velocity_m_s):.3f} m/s is above the Cartesian jog's top speed {limit_m_s:.3f} m/s")
    return float(velocity_m_s)


def _label(axis: str, velocity_m_s: float) -> str:
    return f"{axis}{'+' if velocity_m_s >= 0 else '−'} jog"
