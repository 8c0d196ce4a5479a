"""Issue 18 item 2: speed changes during a repeat never fail the job. Programs near the shoulder and elbow limits
(before the fix every one of these failed: 'elbow = 1.6695 rad ... outside its limits', 'shoulder = -1.8879 rad'),
repeated with the speed changed at random moments: each change re-plans the rest of the run from the motion in
progress, within the joint and acceleration limits, or is refused and the running plan goes on. Measured on the
simulation's clock at every control tick (fast, synchronous sim)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab import skills
from armlab.kinematics import load_arm
from armlab.motion.measure import motion_figures
from armlab.store import Waypoint
from station_helpers import live

ARM = load_arm("rx200")
NEAR_LIMITS = [  # drawn with shoulder and elbow within 0.15 rad of their limits (bench/motion_continuity.py's generator)
    [(0.675, -1.872, 1.585, 1.044, 1.403), (1.154, -1.763, -0.264, 0.584, -0.194), (-1.83, -1.742, 1.509, 0.926, -0.498),
     (0.694, -1.778, 0.298, 0.45, -1.481)],
    [(-0.322, 0.468, -1.754, 1.129, -1.452), (-1.324, 0.424, -1.8, 0.873, -0.075), (-1.732, 0.013, -0.433, -0.981, 0.826),
     (1.168, -1.787, 1.494, -0.083, 1.199)],
    [(1.673, 0.476, 0.363, -0.908, -0.449), (1.437, -1.849, 0.248, 1.276, -0.694), (0.088, 0.09, -1.849, 0.287, -1.861),
     (0.293, -0.112, -1.773, -0.878, -0.0)],
]



@pytest.mark.parametrize("index", range(len(NEAR_LIMITS)))
def test_random_speed_changes_near_the_limits_never_fail_the_job(fast, index):
    station, cell = fast
    rng = np.random.default_rng(index)
    program = station.store.save_program(f"near the limits {index}", [Waypoint(q, "release") for q in NEAR_LIMITS[index]])
    cell.start_joint_recording()
    job = skills.repeat(station, program.id, cycles=2, speed_percent=100)
    changes = 0
    while not job.done and changes < 12:
        at = cell.sim_time_s + rng.uniform(0.1, 0.8)
        live.wait_for(lambda: cell.sim_time_s >= at or job.done, 60, 0.0005)
        if not job.done:
            try:
                station.set_job_speed(float(rng.integers(10, 101)))
            except ValueError as error:  # refused with the reason: the job goes on
                assert "refused, the job goes on" in str(error)
            changes += 1
    assert job.wait(300) and job.state == "succeeded", job.message
    trace = cell.stop_joint_recording()
    lower, upper = np.asarray(ARM.lower_rad), np.asarray(ARM.upper_rad)
    assert np.all(trace["reference_rad"] >= lower - 1e-9) and np.all(trace["reference_rad"] <= upper + 1e-9)
    command, _ = motion_figures(trace).ratio(ARM.accel_limit_rad_s2)
    assert command <= 1.01, f"the command accelerates at {command:.2f}x the limit"
    assert changes >= 6
