"""The station's global speed override: one percentage (10-100 %) for every motion the station plans, jobs, manual
moves and repeats alike, shown in the status (`speed_percent`).

A mixin of core.Station; the override itself and the pacing are the motion gate's (motion.py: every motion is planned
at full speed and paced when it is sent, armlab.motion.time_warp: the same path, time-scaled; velocity × s,
acceleration × s²). A repeat plans its own runs at the override (its RunControl holds the same number: a change goes
to it, and it re-plans the rest of its run, skills/repeat.py). Any other motion running when the override changes has
its remainder re-timed along the same path from a handover of the running command (continuous position and velocity,
a ramp sized to the acceleration limits, checked like every motion); when that cannot be sent, the motion runs on at
its speed and the new one applies from the next motion (the event log says so). Jogs keep their own speed (their
velocity is the operator's).
"""

from __future__ import annotations

from armlab.station.job_control import RunControl, checked_speed_percent


class SpeedOverride:
    """set_speed: the operator's command changing the gate's override."""

    def set_speed(self, speed_percent, source: str | None = None) -> float:
        """Set the override (InvalidInput outside 10-100 % or not a finite number: nothing changes). A running repeat
        takes it (its own check may refuse it: InvalidInput, nothing changes); any other motion in progress is re-timed
        from now on. Returns the override now in force."""
        speed = checked_speed_percent(speed_percent)
        self.require_control("set_speed", source)
        refused = None
        with self.gate.speed_change():
            job = self.current_job()
            control = getattr(job, "control", None) if job is not None and not job.done else None
            if isinstance(control, RunControl) and control.speed_percent != speed:
                control.set_speed(speed)  # InvalidInput: the repeat's reason, nothing changes
            old = self.gate.set_speed_percent(speed)
            if not isinstance(control, RunControl) and speed != old:
                refused = self.gate.retime_running(speed)
        if refused is not None:
            self.events.add("warn", f"speed {speed:g} % applies from the next motion: the one in progress runs on ({refused})")
        if speed != old:
            self.events.add("info", f"speed override set to {speed:g} %")
        return speed
