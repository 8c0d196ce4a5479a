"""Steps start where the arm is (issue 19: "the gate refusing a plan that starts 0.05+ rad from the measured
joints"). A pick's steps are planned in a chain, each from the previous one's commanded end; on the real arm
(realism real, rig seed 5, camera and arm calibrated) the P-only servos hold the arm 0.04-0.05 rad below that
command at far reach (shoulder, elbow), and the gate compared the next step's start with the readings: a block
400 mm out could not be picked ("the trajectory starts 0.052 rad from where elbow is"). The start is now checked
against the command that holds the arm where it reads (the readings less the calibrated servos' steady error); a
real jump is still refused."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.motion import TrajectoryStep, plan_joint_move
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills.manipulate import plan_pick
from armlab.station.core import Station
from real_arm_station import calibrated_real_station

pytestmark = pytest.mark.slow

EDGE_M = 0.038
FAR_M = (0.05, 0.40)
SCENE = {"objects": [{"id": "far", "type": "block", "color": "red", "size": "large", "position_m": [*FAR_M, EDGE_M / 2], "yaw_rad": 0.0}]}


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    with calibrated_real_station(5, SCENE, tmp_path_factory.mktemp("startcheck")) as calibrated:
        yield calibrated


def in_job(station: Station, run) -> object:
    job = station.start_job("auto", "start check", run)
    assert job.wait(600), "the job did not end"
    return job


def test_a_far_pick_planned_as_a_chain_runs_through_the_gate_and_holds_the_block(station):
    gaps = []

    def run(ctx):
        truth = station.sim.truth()["objects"][0]["position_m"]
        for step in plan_pick(station, [truth[0], truth[1], truth[2] + EDGE_M / 2], 0.0, EDGE_M, []):
            if isinstance(step, TrajectoryStep):
                gaps.append(float(np.abs(step.trajectory.positions_rad[0] - station.joints_rad()).max()))
                station.run_trajectory(ctx, step.trajectory)
            else:
                station.run_gripper(ctx, step.action)

    job = in_job(station, run)
    assert job.state == "succeeded", job.message
    # the servos' steady error, the size of what the old check refused (0.052 rad, over the 0.05 tolerance, until the
    # settling of session 13 changed the arm calibration's moves: 0.048 since)
    assert max(gaps) > 0.9 * station.motion_config.start_tolerance_rad
    assert station.gripper.read_state().holding


def test_a_step_starting_off_where_the_arm_is_is_still_refused(station):
    refused = []

    def run(ctx):
        held = station.start_position()
        command = station.model.command_holding(station.joints_rad())
        assert np.abs(held - command).max() < 0.5 * station.motion_config.start_tolerance_rad  # at rest, holding
        droop = station.joints_rad() - held  # where the readings sit from the command (+0.04-0.05 rad on the elbow)
        for joint in (2, 1, 0):
            start = held.copy()
            start[joint] -= 0.06 if droop[joint] >= 0 else -0.06  # 0.06 rad from the command, away from the readings
            try:
                station.run_trajectory(ctx, plan_joint_move(start, held, station.model))
            except UnsafeTrajectory as error:
                refused.append(str(error))

    job = in_job(station, run)
    assert job.state == "succeeded", job.message
    assert len(refused) == 3 and all("the arm would jump" in words for words in refused), refused


def test_after_a_long_fast_swing_a_step_returns_with_the_arm_where_its_command_holds_it(station):
    """The trajectory is done at its end time while the P-only waist still trails it (0.02-0.03 rad after this
    swing, more loaded): the next step would start that far from the arm."""
    gaps = []

    def run(ctx):
        model = station.model
        for a, b in (((-0.25, -0.1, 0.12), (0.3, 0.15, 0.12)), ((0.3, 0.15, 0.12), (-0.25, -0.1, 0.12))):
            station.run_trajectory(ctx, station.plan_move(model.ik(np.array(a), pitch=np.pi / 2, q_seed=station.joints_rad())))
            q = model.ik(np.array(b), pitch=np.pi / 2, q_seed=station.joints_rad())
            station.run_trajectory(ctx, station.plan_move(q))
            gaps.append(np.abs(model.command_holding(station.joints_rad()) - q))

    job = in_job(station, run)
    assert job.state == "succeeded", job.message
    assert max(float(g.max()) for g in gaps) <= 0.5 * station.motion_config.start_tolerance_rad, gaps
