"""What the station remembers holding is a typed value (armlab.station.held.HeldBlock), not a wire dict: a job's pick
sets it with the block's colour, size and true edge (the scene's), the body check reads its edge, and a dict is
refused where a HeldBlock belongs."""

from __future__ import annotations

import pytest

from armlab.station.held import HeldBlock
from armlab.tasks import start_auto

SCENE = {"objects": [  # a block's edge is twice the height of its centre resting on the board
    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.22, 0.019], "yaw_rad": 0.3},
]}
RED_EDGE_M = 2 * 0.019


def test_a_jobs_pick_holds_a_typed_block_with_its_colour_and_true_edge(calibrated_station):
    station = calibrated_station(SCENE)
    job = start_auto(station, "pick_sort", 1)
    held = None
    for _ in range(30000):  # the job's thread drives the fast simulation; poll until the pick set what it holds
        held = station.held_block
        if held is not None or job.done:
            break
        job.done_event.wait(0.01)
    try:
        assert isinstance(held, HeldBlock), held
        assert held.color == "red" and held.size == "large"
        assert held.edge_m == pytest.approx(RED_EDGE_M, abs=1e-3)
        assert station.sim.truth()["gripper"]["holding_id"] == "red"
    finally:
        station.cancel_job()
        job.wait(120)


def test_a_wire_dict_is_refused_where_a_held_block_belongs(calibrated_station):
    station = calibrated_station({"objects": []})
    with pytest.raises(TypeError, match="HeldBlock"):
        station.set_held_block({"color": "red", "size": "large", "edge_m": RED_EDGE_M})
    assert station.held_block is None
    station.set_held_block(HeldBlock(edge_m=RED_EDGE_M, color="red", size="large"))
    assert station.held_block == HeldBlock(RED_EDGE_M, "red", "large")
    station.set_held_block(None)
