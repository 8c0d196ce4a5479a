"""Blocks reach a job as types (issue 20, item 3): a look hands the policy armlab.vision Blocks (with the frame's
capture time and the arm's joints then) and StandingObjects for what depth alone finds, never wire dicts read with
o.get("is_cube", True); the job's progress still reports its next block as the detection's wire dict (server's
Detection), the same keys and values GET /api/detections gives."""

from __future__ import annotations

import numpy as np
import pytest
from seen_blocks import seen_block

from armlab.tasks import pick_sort, runner, start_auto
from armlab.tasks.runner import Progress
from armlab.tasks.seen import StandingObject
from armlab.vision.block import Block
from server.response_models import Detection, DetectionsResponse

ONE_BLOCK = {"objects": [
    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.22, 0.019], "yaw_rad": 0.3},
]}


def test_a_job_in_simulation_hands_its_policy_blocks_seen_with_their_frame_time_and_arm_pose(calibrated_station, monkeypatch):
    station = calibrated_station(ONE_BLOCK)
    looks: list[list] = []
    progress: list[dict] = []
    sort = pick_sort.policy

    def recording_policy(objects, given_up, standing_at=None):
        looks.append(list(objects))
        return sort(objects, given_up, standing_at)

    report = runner.TaskRunner.report

    def recording_report(self, step):
        report(self, step)
        if step.startswith("picking"):
            progress.append(self.progress.to_dict())

    monkeypatch.setattr(pick_sort, "policy", recording_policy)
    monkeypatch.setattr(runner.TaskRunner, "report", recording_report)
    job = start_auto(station, "pick_sort", 1)
    assert job.wait(300) and job.state == "succeeded", job.message
    assert looks and all(looks), looks  # every look saw the red block
    for objects in looks:
        for block in objects:
            assert isinstance(block, Block), type(block)
            assert block.seen_time_s is not None and block.seen_arm_joints_rad is not None
            assert len(block.seen_arm_joints_rad) == len(station.model.home_rad)
    first = looks[0][0]
    assert first.color == "red" and first.size == "large" and first.is_cube
    assert np.hypot(*(first.position_m[:2] - (0.10, 0.22))) < 0.01  # where the simulation put it
    # The progress the page and the recorder read: the detection's wire dict, as the REST schema types it.
    (picking,) = progress
    wire = picking["next_block"]
    Detection.model_validate(wire)
    assert wire["id"] == 0 and wire["color"] == "red" and wire["seen_time_s"] == first.seen_time_s
    assert wire["position_m"] == [float(v) for v in first.position_m] and isinstance(wire["position_m"][0], float)


def test_a_policy_handed_wire_dicts_refuses_them():
    wire = {"color": "red", "size": "large", "position_m": [0.1, 0.25, 0.038], "stack_level": 1, "is_cube": True, "yaw_rad": 0.0}
    with pytest.raises(AttributeError):
        pick_sort.policy([wire], set())


def test_progress_reports_the_next_block_as_a_detection_wire_dict():
    block = seen_block("blue", "small", 0.1, -0.2, 0.025, yaw_rad=0.25, seen_time_s=12.5, seen_arm_joints_rad=(0.0, 0.1, 0.2, 0.3, 0.4))
    progress = Progress(done=1, left=2, step="picking", next_block=block, next_block_id=3, next_target_m=[0.2, -0.1, 0.0])
    assert progress.to_dict()["next_block"] == {
        "id": 3, "color": "blue", "size": "small", "position_m": [0.1, -0.2, 0.025], "yaw_rad": 0.25, "height_m": 0.025,
        "stack_level": 1, "stack_sizes": [], "center_px": [0.0, 0.0], "is_cube": True, "occluded": False, "aruco_id": None,
        "destination": None, "seen_time_s": 12.5,
    }
    assert list(progress.to_dict()) == ["done", "left", "step", "attempts", "failures", "moves", "next_block", "next_target_m"]


def test_a_column_seen_only_by_depth_is_an_obstacle_no_policy_picks():
    column = StandingObject.at((0.15, -0.1), 0.114)
    plan = pick_sort.policy([column], set())
    assert plan.finished and not plan.moves and plan.left == 0
    assert not column.is_cube and column.color is None and column.position_m.tolist() == [0.15, -0.1, 0.114]


WIRE_KEYS = ["id", "color", "size", "position_m", "yaw_rad", "height_m", "stack_level", "stack_sizes", "center_px", "is_cube",
             "occluded", "aruco_id", "destination", "seen_time_s"]  # and color_lab (before seen_time_s) when measured


def test_the_stations_detections_are_blocks_and_their_wire_form_is_unchanged(calibrated_station):
    station = calibrated_station(ONE_BLOCK)
    station.fresh_perception()
    detections = station.detections()
    assert not detections.stale and len(detections.blocks) == 1
    (block,) = detections.blocks
    assert isinstance(block, Block) and block.seen_time_s is not None and detections.blocks.index(block) == 0
    truth = next(o for o in station.sim.truth()["objects"] if o["id"] == "red")["position_m"]
    assert np.hypot(*(block.position_m[:2] - np.asarray(truth[:2]))) < 0.01  # the detection is the simulation's block
    wire = detections.to_dict()
    DetectionsResponse.model_validate(wire)
    assert list(wire) == ["data", "count", "time_s", "frame_sequence", "stale", "stale_reason"]
    assert wire["count"] == 1 and wire["stale"] is False and wire["stale_reason"] is None
    (data,) = wire["data"]
    assert [key for key in data if key != "color_lab"] == WIRE_KEYS
    assert data["id"] == 0 and data["seen_time_s"] == block.seen_time_s and data["color"] == "red" and data["size"] == "large"
    assert all(isinstance(v, float) for v in data["position_m"] + data["center_px"]) and isinstance(data["yaw_rad"], float)
