"""The to_the_sky feeder: a new large block appears at the feed spot whenever the spot is clear (no
object near it, no part of the arm at it), until the feeder's count is used; ground truth lists only
blocks that were fed. Checked by teleporting blocks away (a test-only helper) and by a real pick."""

import math

import mujoco
import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.devices.sim.mjcf import OBJECT_PREFIX
from armlab.scene import Scene, SceneObject, generate_scene
from armlab.scene.model import Feeder
from armlab.workcell import load_workcell
from sim_helpers import move_to

WORKCELL = load_workcell()
SPOT = WORKCELL.feeder.spot_m
EDGE = WORKCELL.block_edge_m("large")
# Board spots clear of the feed spot (relative to it, so the test follows the workcell config).
ELSEWHERE = [(SPOT[0] + dx, SPOT[1] + dy) for dx, dy in ((-0.15, 0.0), (-0.10, -0.12), (0.12, -0.10), (0.05, -0.15))]


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(seed=3, color_noise=False, depth_noise=False, camera_pose_error=False)) as sim:
        yield sim


def teleport(cell: SimWorkcell, object_id: str, xy) -> None:
    """Test-only: put an object down at (x, y) on the board, at rest (as a hand would)."""
    with cell.lock:
        model, data = cell.model, cell._data
        joint = model.body_jntadr[model.body(OBJECT_PREFIX + object_id).id]
        qpos, dof = model.jnt_qposadr[joint], model.jnt_dofadr[joint]
        data.qpos[qpos : qpos + 7] = (xy[0], xy[1], EDGE / 2 + 1e-4, 1.0, 0.0, 0.0, 0.0)
        data.qvel[dof : dof + 6] = 0.0
        mujoco.mj_forward(model, data)


def objects(truth) -> dict[str, dict]:
    return {o["id"]: o for o in truth["objects"]}


def at_spot(truth) -> list[str]:
    return [o["id"] for o in truth["objects"] if math.dist(o["position_m"][:2], SPOT) < 0.005]


def test_feeder_refills_the_spot_until_its_count_is_used(cell):
    other = SceneObject("other", "block", "green", "small", (-0.15, 0.15, 0.0125))
    cell.set_scene(Scene((other,), feeder=Feeder(spot_m=SPOT, count=3)))
    truth = cell.truth()
    assert truth["feeder"] == {"spot_m": list(SPOT), "count": 3, "fed": 1, "remaining": 2}
    assert sorted(objects(truth)) == ["feed_0", "other"], "parked blocks are not in the truth"
    assert at_spot(truth) == ["feed_0"]
    for fed in (1, 2, 3):
        teleport(cell, f"feed_{fed - 1}", ELSEWHERE[fed - 1])
        cell.step(0.3)
        truth = cell.truth()
        if fed < 3:
            assert at_spot(truth) == [f"feed_{fed}"]
            block = objects(truth)[f"feed_{fed}"]
            assert block["size"] == "large" and block["position_m"][2] == pytest.approx(EDGE / 2, abs=5e-4)
        assert truth["feeder"]["fed"] == min(fed + 1, 3) and truth["feeder"]["remaining"] == max(2 - fed, 0)
    assert at_spot(truth) == [], "an empty feeder feeds nothing"
    assert len(truth["objects"]) == 4
    for index, xy in enumerate(ELSEWHERE[:3]):
        assert objects(truth)[f"feed_{index}"]["position_m"][:2] == pytest.approx(xy, abs=0.002)


def test_feeder_waits_while_an_object_is_near_the_spot(cell):
    cell.set_scene(Scene((), feeder=Feeder(spot_m=SPOT, count=5)))
    teleport(cell, "feed_0", (SPOT[0] + 0.035, SPOT[1]))  # 35 mm: not clear
    cell.step(0.5)
    assert cell.truth()["feeder"]["fed"] == 1 and at_spot(cell.truth()) == []
    teleport(cell, "feed_0", (SPOT[0], SPOT[1] + 0.12))
    cell.step(0.1)
    assert cell.truth()["feeder"]["fed"] == 2 and at_spot(cell.truth()) == ["feed_1"]


def test_a_real_pick_empties_the_spot_and_the_arm_at_the_spot_holds_the_feeder_back(cell):
    cell.set_scene(Scene((), feeder=Feeder(spot_m=SPOT, count=4)))
    cell.gripper.release()
    block = np.array([*SPOT, EDGE / 2])
    move_to(cell, block + [0, 0, 0.08])
    move_to(cell, block)
    cell.gripper.grasp()
    move_to(cell, block + [0, 0, 0.12])
    truth = cell.truth()
    assert truth["gripper"]["holding_id"] == "feed_0"
    assert truth["feeder"]["fed"] == 1, "the held block above the spot keeps it occupied"
    place = np.array([SPOT[0] + 0.02, SPOT[1] - 0.10, EDGE / 2])
    move_to(cell, place + [0, 0, 0.12], speed_rad_s=2.0)
    truth = cell.truth()
    assert truth["feeder"]["fed"] == 2 and at_spot(truth) == ["feed_1"], "the spot refilled once the block left"
    move_to(cell, place + [0, 0, 0.002])
    cell.gripper.release()
    move_to(cell, place + [0, 0, 0.10])
    assert objects(cell.truth())["feed_0"]["position_m"] == pytest.approx(place, abs=0.004)
    # The open gripper around the spot: take feed_1 away from under it; nothing is fed while it stays.
    move_to(cell, block + [0, 0, 0.08])
    move_to(cell, block + [0, 0, 0.005])
    teleport(cell, "feed_1", (SPOT[0] - 0.12, SPOT[1]))
    cell.step(0.5)
    assert cell.truth()["feeder"]["fed"] == 2 and at_spot(cell.truth()) == []
    move_to(cell, block + [0, 0, 0.10])
    cell.step(0.1)
    assert cell.truth()["feeder"]["fed"] == 3 and at_spot(cell.truth()) == ["feed_2"]


def test_fast_mode_feeding_is_deterministic():
    def run() -> list:
        with SimWorkcell(SimWorkcellConfig(seed=4), scene=generate_scene("to_the_sky", 1, seed=2)) as sim:
            for index in range(3):
                teleport(sim, f"feed_{index}", ELSEWHERE[index])
                sim.step(0.25)
            truth = sim.truth()
            return [truth["feeder"], truth["objects"]]

    first = run()
    assert first[0]["fed"] == 4 and first == run()


def test_truth_round_trips_through_set_scene_with_the_feeder_state(cell):
    cell.set_scene(Scene((), feeder=Feeder(spot_m=SPOT, count=3)))
    teleport(cell, "feed_0", ELSEWHERE[0])
    cell.step(0.2)
    truth = cell.truth()
    assert truth["feeder"]["fed"] == 2
    cell.set_scene(truth)
    again = cell.truth()
    assert again["feeder"] == truth["feeder"]
    assert sorted(objects(again)) == ["feed_0", "feed_1"]


def test_real_time_feeder_refills_while_the_physics_thread_runs():
    config = SimWorkcellConfig(realtime=True, seed=5, camera_fps=5.0)
    with SimWorkcell(config, scene=Scene((), feeder=Feeder(spot_m=SPOT, count=2))) as sim:
        assert sim.wait_for(lambda: sim.feeder_status()["fed"] == 1, timeout_s=5.0)
        teleport(sim, "feed_0", ELSEWHERE[0])
        assert sim.wait_for(lambda: sim.feeder_status()["fed"] == 2, timeout_s=5.0)
        assert at_spot(sim.truth()) == ["feed_1"]
