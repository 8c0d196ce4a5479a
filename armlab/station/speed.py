"""The station's global speed override: one percentage (10-100 %) for every motion the station plans, jobs, manual
moves and repeats alike, shown in the status (`speed_percent`).

A mixin of core.Station. Motions are planned at full speed and paced when they are sent (armlab.motion.time_warp:
the same path, time-scaled; velocity × s, acceleration × s²). A repeat plans its own runs at the override (its
RunControl holds the same number: a change goes to it, and it re-plans the rest of its run, skills/repeat.py).
Any other motion running when the override changes has its remainder re-timed along the same path from a
handover of the running command (continuous position and velocity, a ramp sized to the acceleration limits,
checked like every motion); when that cannot be sent, the motion runs on at its speed and the new one applies
from the next motion (the event log says so). Jogs keep their own speed (their velocity is the operator's).
"""

from __future__ import annotations

from armlab.devices.arm import JointTrajectory
from armlab.errors import PLAN_REFUSALS, ArmMoving, CommandRefused, InvalidInput
from armlab.motion.handover import Handover
from armlab.motion.planning_limits import planning_accel_rad_s2
from armlab.motion.time_warp import paced, retimed
from armlab.station.job_control import RunControl, checked_speed_percent
from armlab.station.motion import HandoverLate


class SpeedOverride:
    """speed_percent, set_speed, and the pacing of newly planned motions (`_paced`); its state is declared in
    Station.__init__ (core.py)."""

    @property
    def speed_percent(self) -> float:
        return self._speed_percent

    def _paced(self, trajectory: JointTrajectory, percent: float, from_rest: bool | None = None) -> JointTrajectory:
        """A newly planned motion at `percent` (armlab.motion.time_warp.paced); from_rest None: it starts from rest
        unless a commanded motion is still running."""
        if from_rest is None:
            with self._lock:
                running = self._commanded
            from_rest = running is None or self.clock_s() - running[1] >= running[0].duration_s
        return paced(trajectory, percent / 100.0, planning_accel_rad_s2(self.model), from_rest, self.motion_config.sample_rate_hz)

    def _pace_next_send(self, percent: float) -> None:
        """Under the lock, just before _command_arm: the motion about to be sent was paced at `percent` (a later
        change re-times it); HandoverLate (plan again) when the override has changed since it was planned."""
        if percent != self._speed_percent:
            raise HandoverLate(f"the speed override changed to {self._speed_percent:g} % while this motion was planned")
        self._pace_next = percent

    def set_speed(self, speed_percent, source: str | None = None) -> float:
        """Set the override (InvalidInput outside 10-100 % or not a finite number: nothing changes). A running repeat
        takes it (its own check may refuse it: InvalidInput, nothing changes); any other motion in progress is re-timed
        from now on. Returns the override now in force."""
        speed = checked_speed_percent(speed_percent)
        self.require_control("set_speed", source)
        with self._speed_lock:
            job = self.current_job()
            control = getattr(job, "control", None) if job is not None and not job.done else None
            if isinstance(control, RunControl) and control.speed_percent != speed:
                control.set_speed(speed)  # InvalidInput: the repeat's reason, nothing changes
            with self._lock:
                old, self._speed_percent = self._speed_percent, speed
            if not isinstance(control, RunControl) and speed != old:
                self._retime_running(speed)
        if speed != old:
            self.events.add("info", f"speed override set to {speed:g} %")
        return speed

    def _retime_running(self, speed: float) -> None:
        """Re-time the remainder of the motion in progress to `speed` (when it is one this override paced)."""
        with self._lock:
            running, paced_motion = self._commanded, self._paced_motion
        if running is None or paced_motion is None or running[0] is not paced_motion[0] or paced_motion[1] == speed:
            return
        if self.clock_s() - running[1] >= running[0].duration_s:
            return  # it has ended
        ratio = speed / paced_motion[1]

        def plan(handover: Handover | None) -> JointTrajectory:
            with self._lock:
                current = self._commanded
            if handover is None or current is None or current[2] != handover.source_id:
                raise InvalidInput("the motion ended or was replaced meanwhile")
            trajectory, t0 = current[0], current[1]
            return retimed(trajectory, handover.takes_over_s - t0, 1.0, ratio, planning_accel_rad_s2(self.model),
                           self.motion_config.sample_rate_hz)

        try:
            self._send_replacing(plan, lambda: self._pace_next_send(speed), "set_speed")
        except (*PLAN_REFUSALS, ArmMoving, CommandRefused) as error:
            self.events.add("warn", f"speed {speed:g} % applies from the next motion: the one in progress runs on ({error})")
