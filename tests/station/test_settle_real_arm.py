"""A job's step leaves the real arm where it was sent (issue 19, arm-calibration accuracy max <= 5 mm). The real
RX200's waist is held by its P-only servo against the link's friction alone (gravity does not load it): after a
move it still swings, or stands short of its goal, by up to ~0.6 deg when the step returns (rig 0, camera and arm
calibrated: bench/arm_accuracy.py's worst point, (-301, 42, 150) mm after (-304, 127, 150) mm, 6.4 mm off by the
truth). Before the position is used (here a release; a grasp, a sighting) the station now waits for those joints to
stand still and corrects them from their readings; measured against MuJoCo's truth the moment the release returns."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.station.settle import SETTLE_DEADBAND_RAD
from armlab.store import Store
from armlab.workcell import load_workcell_arm
from real_arm_station import calibrated_real_station

pytestmark = pytest.mark.slow

# (from, to) gripper points, m, top-down: the bench's worst (a 16 deg waist turn), a long swing across the board
# (2.6 rad) and one back the other way.
MOVES = (((-0.304, 0.127, 0.15), (-0.301, 0.042, 0.15)),
         ((0.30, 0.10, 0.15), (-0.301, 0.042, 0.15)),
         ((-0.25, -0.10, 0.12), (0.28, 0.12, 0.12)))
COUNT_RAD = 2 * np.pi / 4096  # one encoder count: the readings' resolution
WITHIN_M = 0.003  # the calibrated arm's error there approached slowly from nearby: 1.1-1.5 mm (bench/arm_accuracy.py)


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    with calibrated_real_station(0, {"objects": []}, tmp_path_factory.mktemp("settle")) as calibrated:
        yield calibrated


def test_a_step_returns_with_the_gripper_where_it_was_sent(station):
    misses = []

    def run(ctx):
        model = station.model
        for a, b in MOVES:
            station.run_trajectory(ctx, station.plan_move(model.ik(np.array(a), pitch=np.pi / 2, yaw=0.0, q_seed=station.joints_rad())))
            station.run_trajectory(ctx, station.plan_move(model.ik(np.array(b), pitch=np.pi / 2, yaw=0.0, q_seed=station.joints_rad())))
            station.run_gripper(ctx, "release")  # where the position is used (the fingers are open: nothing else moves)
            misses.append(float(np.linalg.norm(station.sim.gripper_point_m() - np.array(b))))

    job = station.start_job("auto", "settle", run)
    assert job.wait(600), "the job did not end"
    assert job.state == "succeeded", job.message
    assert max(misses) <= WITHIN_M, [round(1000 * m, 2) for m in misses]


def test_uncalibrated_the_correction_moves_only_the_joints_it_corrects(tmp_path):
    """Uncalibrated, the station knows no steady error: the shoulder and elbow read ~2 deg below their command under
    the arm's weight. A correction planned from the readings (not from the command holding the arm) sent the
    drooped readings as the new command: the arm sagged further (a 25 mm outlier in rig 1's arm calibration)."""
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=1, realism="real")) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(), config=StationConfig(),
                          store=Store(tmp_path / "s.sqlite3"), sim=cell, synchronous=True)
        station.start()
        ends = []
        try:
            def run(ctx):
                model = station.model
                for a, b in MOVES:
                    for point in (a, b):
                        q = model.ik(np.array(point), pitch=np.pi / 2, yaw=0.0, q_seed=station.joints_rad())
                        station.run_trajectory(ctx, station.plan_move(q))
                        station.run_gripper(ctx, "release")
                        ends.append((q, station.commanded_joints_rad(), station.joints_rad()))

            job = station.start_job("auto", "settle", run)
            assert job.wait(600) and job.state == "succeeded", job.message
        finally:
            station.close()
    for q, command, reading in ends:
        assert np.abs(command[1:3] - q[1:3]).max() < 1e-9, (command - q).round(4)  # shoulder, elbow (loaded): as sent
        assert abs(reading[0] - q[0]) <= SETTLE_DEADBAND_RAD + COUNT_RAD, reading[0] - q[0]  # the waist where it was sent
    assert any(abs(command[0] - q[0]) > 1e-9 for q, command, _ in ends)  # at least one waist was corrected
