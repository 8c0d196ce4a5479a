"""The real arm in the simulation (`realism: real`, issue 19 item 1): each imperfection measured against MuJoCo's
ground truth with the figures of the real RX200 — the droop at 300 mm reach (23 +- 5 mm, one team's measurement),
part of it in the joint readings and part not; 0.25 deg of backlash; readings in whole encoder counts (4096 per
turn) published at 100 Hz; per-rig joint offsets (+-2 deg), link lengths (+-1 mm) and base pose (+-5 mm, +-1 deg)
drawn from the seed. `ideal` stays exact."""

import math

import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from tests.devices.sim.sim_helpers import level_ik, move, planar_fk

COUNT_RAD = 2.0 * math.pi / 4096  # one encoder count of the X-series servos
BACKLASH_RAD = math.radians(0.25)


def real_cell(seed: int = 0, rig: bool = False) -> SimWorkcell:
    return SimWorkcell(SimWorkcellConfig(seed=seed, realism="real", arm_rig_error=rig, camera_pose_error=False))


def hold(cell: SimWorkcell, q, settle_s: float = 1.5) -> None:
    move(cell, q, duration_s=1.5)
    cell.step(settle_s)


def azimuth_rad(point) -> float:
    """The gripper point's heading about the base (base frame x = world +y, base y = world -x)."""
    return math.atan2(-point[0], point[1])


@pytest.fixture(scope="module")
def sagging():
    """The nominal rig (no offsets) holding the gripper level at 300 mm reach, three heights: the gripper point's
    truth, the readings, and the commanded height."""
    rows = []
    with real_cell() as cell:
        for height_m in (0.05, 0.10, 0.15):
            q = level_ik(0.30, height_m)
            hold(cell, q)
            rows.append((height_m, cell.gripper_point_m(), cell.arm.read_joint_state().position_rad))
    return rows


def test_the_uncorrected_gripper_sags_like_the_real_rx200_at_300_mm_reach(sagging):
    for height_m, point, _ in sagging:
        sag_mm = 1000.0 * (height_m - point[2])
        assert 18.0 <= sag_mm <= 28.0, f"at 300 mm reach, {height_m} m high: sags {sag_mm:.1f} mm, the real arm 23 +- 5"
        assert abs(point[0]) < 1e-4  # straight ahead: the droop stays in the arm's plane


def test_part_of_the_droop_shows_in_the_readings_and_part_does_not(sagging):
    for height_m, point, reading in sagging:
        _, seen_height_m = planar_fk(reading)
        shown_mm, total_mm = 1000.0 * (height_m - seen_height_m), 1000.0 * (height_m - point[2])
        assert 0.3 * total_mm < shown_mm < 0.9 * total_mm, (
            f"{height_m} m: the readings show {shown_mm:.1f} of {total_mm:.1f} mm: both the servos' steady error and "
            "the gears' play and compliance must take part")


@pytest.mark.parametrize("duration_s", [1.5, 3.0])
def test_backlash_shows_as_a_direction_dependent_position_error(duration_s):
    """The waist (no gravity on it) comes to the same goal from below and from above: where the link truly points
    (the gripper point's heading) against what its encoder reads differs by the gear play between the two."""
    with real_cell() as cell:
        q = level_ik(0.30, 0.10)
        unseen = []
        for side in (-0.3, 0.3):
            move(cell, q + np.array([side, 0, 0, 0, 0]), duration_s=duration_s)
            move(cell, q, duration_s=duration_s)
            cell.step(1.0)
            reading = cell.arm.read_joint_state().position_rad[0]
            assert abs(reading) <= 3 * COUNT_RAD  # the motor stops within a few counts of its goal (bearing friction)
            unseen.append(azimuth_rad(cell.gripper_point_m()) - reading)
    play = unseen[1] - unseen[0]  # from below the link trails low, from above high
    assert 0.8 * BACKLASH_RAD < play < 1.3 * BACKLASH_RAD, f"{math.degrees(play):.3f} deg between the approaches, not 0.25"


def test_readings_are_whole_encoder_counts_published_at_100_hz():
    with real_cell() as cell:
        q0 = cell.arm.read_joint_state().position_rad
        cell.arm.command_trajectory(move_trajectory(q0, level_ik(0.25, 0.1), 1.0))
        changes, last = [], cell.arm.read_joint_state().position_rad
        for _step in range(1, 600):
            cell.step(0.002)
            reading = cell.arm.read_joint_state().position_rad
            counts = reading / COUNT_RAD
            assert np.allclose(counts, np.round(counts), atol=1e-9), counts
            if not np.array_equal(reading, last):
                changes.append(cell.sim_time_s)
            last = reading
        truth = cell.arm_positions()
    assert len(changes) > 50  # it moved, and the readings followed
    periods = np.round(np.array(changes) / 0.01, 6)
    assert np.allclose(periods, np.round(periods)), "readings changed between the 10 ms publications"
    assert np.all(np.abs(reading - truth) <= 0.5 * COUNT_RAD + 1e-12)  # at rest the reading is the truth, rounded


def move_trajectory(q0, q1, duration_s):
    from armlab.devices.arm import JointTrajectory

    times = np.linspace(0.0, duration_s, int(duration_s * 100) + 1)
    s = times / duration_s
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    return JointTrajectory(times, q0 + np.outer(blend, np.asarray(q1) - q0))


def rig_of(seed: int) -> dict:
    cell = real_cell(seed, rig=True)  # not started: the rig is drawn at construction
    try:
        return cell.rig
    finally:
        cell.close()


def test_rig_errors_are_drawn_within_bounds_and_reproducible_from_the_seed():
    rigs = [rig_of(seed) for seed in range(8)]
    offsets = np.degrees(np.array([r["joint_offset_rad"] for r in rigs]))
    lengths = np.array([list(r["origin_delta_m"].values()) for r in rigs])
    shifts = np.array([r["base_shift_m"] for r in rigs])
    yaws = np.degrees([r["base_yaw_rad"] for r in rigs])
    assert np.all(np.abs(offsets) <= 2.0) and np.abs(offsets).max() > 1.0
    assert np.all(np.abs(lengths) <= 0.001) and np.abs(lengths).max() > 0.0005
    assert np.all(np.abs(shifts) <= 0.005) and np.abs(shifts).max() > 0.0025
    assert np.all(np.abs(yaws) <= 1.0) and np.abs(yaws).max() > 0.5
    assert rig_of(3) == rigs[3]
    assert len({tuple(r["joint_offset_rad"]) for r in rigs}) == len(rigs)


def test_the_drawn_rig_is_the_simulated_arm():
    """MuJoCo's own frames: the base where the draw put it, each link as long as drawn, each link turned from
    its motor's reading by the drawn offset (no load on the waist: its gear carries no torque)."""
    import mujoco

    with real_cell(seed=5, rig=True) as cell:
        rig = cell.rig
        hold(cell, level_ik(0.25, 0.12))
        model, data = cell.model, cell._data
        base = data.xpos[model.body("base").id]
        assert np.allclose(base[:2], rig["base_shift_m"], atol=1e-9)
        base_x = data.xmat[model.body("base").id].reshape(3, 3)[:, 0]  # the base's forward axis: world +y nominally
        assert math.atan2(-base_x[0], base_x[1]) == pytest.approx(rig["base_yaw_rad"], abs=1e-9)
        elbow, wrist = (data.xpos[model.body(name).id] for name in ("forearm_link", "wrist_link"))
        assert np.linalg.norm(wrist - elbow) == pytest.approx(0.2 + rig["origin_delta_m"]["wrist_angle"], abs=1e-9)
        waist_link = data.xmat[model.body("waist_link").id].reshape(3, 3)[:, 0]
        link_turn = math.atan2(-waist_link[0], waist_link[1]) - rig["base_yaw_rad"]
        reading = cell.arm.read_joint_state().position_rad[0]
        assert link_turn - reading == pytest.approx(rig["joint_offset_rad"][0], abs=0.5 * BACKLASH_RAD + COUNT_RAD)
        assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "shoulder_gear") >= 0


def test_a_scene_change_keeps_the_drooping_arm_where_it_is():
    with real_cell() as cell:
        hold(cell, level_ik(0.30, 0.10))
        before = cell.gripper_point_m()
        cell.set_scene({"objects": []})
        cell.step(0.1)
        assert np.linalg.norm(cell.gripper_point_m() - before) < 2e-4


def test_the_ideal_arm_reads_the_truth_and_does_not_sag():
    with SimWorkcell(SimWorkcellConfig(seed=5, realism="ideal", camera_pose_error=False)) as cell:
        assert cell.rig is None
        q = level_ik(0.30, 0.10)
        hold(cell, q)
        for _ in range(5):
            cell.step(0.002)
            assert np.array_equal(cell.arm.read_joint_state().position_rad, cell.arm_positions())
        assert cell.gripper_point_m()[2] == pytest.approx(0.10, abs=5e-4)
        assert cell.gripper_point_m()[1] == pytest.approx(0.30, abs=5e-4)


def test_the_ur3_stays_ideal_under_real():
    cell = SimWorkcell(SimWorkcellConfig(workcell="ur3_suction", realism="real"))
    try:
        assert cell.realism == "real" and cell.rig is None
    finally:
        cell.close()
