"""Side and inclined grasps (skills.side_grasp) and to_the_sky above the top-down limit, judged from the
simulation's ground truth: a block picked from the board and set on a tower too tall for a top-down
place stands upright (body z within 15° of world z, DESIGN §7), and a to_the_sky run builds a tower
taller than the six blocks a top-down place reaches."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.kinematics import Unreachable
from armlab.motion.safety import UnsafeTrajectory
from armlab.scene import Scene
from armlab.skills import side_grasp
from armlab.skills.manipulate import plan_place, run_steps
from armlab.tasks.episode import run_episode

EDGE_M = 0.038
TOWER_XY_M = (0.157, 0.188)  # where to_the_sky puts its tower (0.245 m out, 40° off the arm's +y axis)
TOWER_BLOCKS = 8  # top at 304 mm: above top-down reach
LOOSE_XY_M = (0.0, 0.30)  # faces the arm (yaw 0 on its +y axis), as the feeder's blocks do
UPRIGHT_RAD = math.radians(15.0)


def tilt_rad(quat_wxyz) -> float:
    """Angle between a body's z axis and world z."""
    w, x, y, z = quat_wxyz
    return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y))))


def tower_scene() -> Scene:
    bearing = math.atan2(TOWER_XY_M[1], TOWER_XY_M[0])
    objects = [{"id": f"tower_{k}", "type": "block", "color": "blue", "size": "large",
                "position_m": [*TOWER_XY_M, EDGE_M / 2 + EDGE_M * k], "yaw_rad": bearing} for k in range(TOWER_BLOCKS)]
    objects.append({"id": "loose", "type": "block", "color": "red", "size": "large", "position_m": [*LOOSE_XY_M, EDGE_M / 2],
                    "yaw_rad": 0.0})
    return Scene.from_dict({"objects": objects})


@pytest.fixture()
def station(calibrated_station):
    """A synchronous, calibrated station on a fast-mode simulation of tower_scene()."""
    return calibrated_station(tower_scene(), seed=7)


def test_a_block_side_grasped_from_the_board_stands_upright_on_a_tower_out_of_top_down_reach(station):
    truth = {o["id"]: o for o in station.sim.truth()["objects"]}
    top_m = np.array(truth["loose"]["position_m"]) + [0.0, 0.0, EDGE_M / 2]
    surface_m = np.array([*TOWER_XY_M, truth[f"tower_{TOWER_BLOCKS - 1}"]["position_m"][2] + EDGE_M / 2])
    with pytest.raises((Unreachable, UnsafeTrajectory, ValueError)):
        plan_place(station, surface_m, 0.0, EDGE_M, [])  # a top-down place does not reach this tower
    pitches = side_grasp.reachable_pitches(station, top_m, surface_m, EDGE_M)
    assert pitches and max(pitches) < math.radians(70.0), "only inclined pitches reach both ends"
    used = {}

    def pick_and_place(ctx):
        pick, grasp = side_grasp.plan_side_pick_place(station, top_m, surface_m, EDGE_M, [], [], pitches,
                                                      then_rad=station.model.sleep_rad)
        run_steps(station, ctx, pick, progress=False)
        assert station.gripper.read_state().holding
        place = side_grasp.plan_side_place(station, surface_m, EDGE_M, grasp, [], then_rad=station.model.sleep_rad)
        release = [step for step in place if getattr(step, "action", None) == "release"][0]
        before = place[place.index(release) - 1].q_end_rad
        used.update(pitch=grasp.pitch_rad, planned_tilt=side_grasp.block_tilt_rad(station.model, before, grasp))
        run_steps(station, ctx, place, progress=False)

    job = station.start_job("auto", "side grasp test", pick_and_place)
    assert job.wait(300) and job.state == "succeeded", job.message
    assert used["pitch"] < math.radians(70.0) and used["planned_tilt"] < math.radians(1.0)
    after = {o["id"]: o for o in station.sim.truth()["objects"]}
    block = after["loose"]
    assert tilt_rad(block["quat_wxyz"]) < UPRIGHT_RAD, f"the placed block tilts {math.degrees(tilt_rad(block['quat_wxyz'])):.0f}°"
    assert math.dist(block["position_m"][:2], TOWER_XY_M) < 0.012
    assert block["position_m"][2] == pytest.approx(EDGE_M / 2 + EDGE_M * TOWER_BLOCKS, abs=0.004)  # on the top, not beside
    for k in range(TOWER_BLOCKS):  # and the tower it went on still stands
        assert tilt_rad(after[f"tower_{k}"]["quat_wxyz"]) < UPRIGHT_RAD
        assert math.dist(after[f"tower_{k}"]["position_m"][:2], TOWER_XY_M) < 0.012


def test_tilt_at_release_is_place_pitch_minus_grasp_pitch(station):
    """The plan-level relation the skill relies on: the same pitch keeps the block level; 30° more tilts it 30°."""
    top_m = np.array([*LOOSE_XY_M, EDGE_M])
    grasp = side_grasp.SideGrasp(math.radians(20.0), *side_grasp.nominal_hold(station, top_m, EDGE_M, math.radians(20.0)))
    for place_pitch_deg in (20.0, 50.0):
        release = side_grasp.release_point(station, (0.0, 0.25, 0.1), EDGE_M, grasp, math.radians(place_pitch_deg))
        q = station.model.ik(release, pitch=math.radians(place_pitch_deg), yaw=None, q_seed=np.zeros(5))
        tilt_deg = math.degrees(side_grasp.block_tilt_rad(station.model, q, grasp))
        assert tilt_deg == pytest.approx(place_pitch_deg - 20.0, abs=0.5)


def tallest_upright_column(objects: list[dict]) -> int:
    """Blocks in the tallest column of upright large blocks standing on the board, straight from ground
    truth: each one's centre within 15 mm (x-y) of the one under it and one edge above it (±6 mm)."""
    upright = [o for o in objects if o["size"] == "large" and tilt_rad(o["quat_wxyz"]) < UPRIGHT_RAD]
    best = 0
    for bottom in (o for o in upright if abs(o["position_m"][2] - EDGE_M / 2) < 0.006):
        column, current = 1, bottom
        while True:
            above = [o for o in upright if math.dist(o["position_m"][:2], current["position_m"][:2]) < 0.015
                     and abs(o["position_m"][2] - current["position_m"][2] - EDGE_M) < 0.006]
            if not above:
                break
            column, current = column + 1, above[0]
        best = max(best, column)
    return best


def test_to_the_sky_builds_past_the_top_down_limit_judged_from_ground_truth():
    result = run_episode("to_the_sky", 1, 0, keep_truth=True)
    height = tallest_upright_column(result["truth"]["objects"])
    assert height >= 10, f"tower of {height}: {result['failures']}"  # top-down alone stops at 5-6 blocks
    tower = next(rule for rule in result["breakdown"] if rule["rule"] == "tower")
    assert len(tower["object_ids"]) == height  # the judge sees the same tower
    assert result["within_limit"]
