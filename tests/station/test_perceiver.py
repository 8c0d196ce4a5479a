"""What the gate sees, on its own (armlab.station.perceiving.Perceiver), without a station, a camera or a simulation:
frames and perception are published into its slots by hand (as its threads would) or captured on demand; fresh
frames are never older than asked, the frame after a change never shows the world before it, perception waits for
a frame captured after the request, and detections say why they are stale (the camera lost, or old)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from armlab.devices.camera import Frame
from armlab.station.jobs import JobCancelled
from armlab.station.perceiving import Perceiver
from armlab.station.perception import Perception
from armlab.vision.block import Block

CAMERA_TIMEOUT_S = 1.0
SHORT_S = 0.05  # a timeout that must expire: nothing is published


def frame(timestamp_s: float, sequence: int = 0) -> Frame:
    return Frame(np.zeros((2, 2, 3), np.uint8), None, timestamp_s, sequence)


def block(x: float) -> Block:
    return Block(color="red", size="large", position_m=np.array([x, 0.1, 0.02]), yaw_rad=0.0, height_m=0.02, stack_level=1,
                 center_px=np.zeros(2), contour_px=np.zeros((0, 2)))


def make(camera_lost=None, capture_now=None) -> Perceiver:
    return Perceiver(lambda: None, None, lambda: None, lambda: None, lambda: camera_lost, CAMERA_TIMEOUT_S, capture_now=capture_now)


def publish_later(slot, value) -> threading.Thread:
    """Publish `value` from another thread (the camera or perception thread), once the test waits or before: either way
    it is newer than what the waiter saw."""
    thread = threading.Thread(target=slot.publish, args=(value,))
    thread.start()
    return thread


def test_the_newest_frame_is_fresh_enough_when_recent():
    perceiver = make()
    recent = frame(time.time())
    perceiver.frames.publish(recent)
    assert perceiver.fresh_frame() is recent


def test_an_old_frame_is_not_fresh_a_newer_one_is_waited_for():
    perceiver = make()
    perceiver.frames.publish(frame(time.time() - 10.0, 1))
    newer = frame(time.time(), 2)
    thread = publish_later(perceiver.frames, newer)
    assert perceiver.fresh_frame(timeout_s=10.0, max_age_s=2.0) is newer
    thread.join()


def test_no_fresh_frame_is_a_timeout():
    perceiver = make()
    perceiver.frames.publish(frame(time.time() - 10.0))
    with pytest.raises(TimeoutError, match="no fresh camera frame"):
        perceiver.fresh_frame(timeout_s=SHORT_S, max_age_s=1.0)


def test_the_frame_after_a_change_is_never_one_taken_before_it():
    perceiver = make()
    changed_s = time.time()
    perceiver.frames.publish(frame(changed_s - 0.2, 1))  # recent, but from before the change
    after = frame(changed_s + 0.01, 2)
    thread = publish_later(perceiver.frames, after)
    assert perceiver.frame_after(changed_s, timeout_s=10.0) is after
    thread.join()
    with pytest.raises(TimeoutError, match="no camera frame newer"):
        perceiver.frame_after(time.time() + 5.0, timeout_s=SHORT_S)


def test_fresh_perception_waits_for_a_frame_captured_after_the_request():
    perceiver = make()
    perceiver.results.publish(Perception(capture_time_s=time.time() - 1.0))  # seen before the request
    fresh = Perception(capture_time_s=time.time() + 1.0)
    thread = publish_later(perceiver.results, fresh)
    assert perceiver.fresh_perception(timeout_s=10.0) is fresh
    thread.join()


def test_a_perception_published_during_the_wait_but_of_an_older_frame_is_not_fresh():
    """The perception thread may finish a frame captured before the request while it waits: not that one."""
    perceiver = make()
    stale, fresh = Perception(capture_time_s=time.time() - 1.0), Perception(capture_time_s=time.time() + 1.0)
    to_publish = [stale, fresh]

    class PublishingOnCheck:  # each look of the wait (its cancel check) is when the thread publishes its next result
        def check(self):
            if to_publish:
                perceiver.results.publish(to_publish.pop(0))

    assert perceiver.fresh_perception(PublishingOnCheck(), timeout_s=10.0) is fresh


def test_fresh_perception_stops_waiting_when_the_job_is_cancelled():
    perceiver = make()

    class Cancelled:
        def check(self):
            raise JobCancelled("cancelled")

    with pytest.raises(JobCancelled):
        perceiver.fresh_perception(Cancelled(), timeout_s=10.0)


def test_on_demand_frames_are_captured_now_and_published():
    captured = []

    def capture_now() -> Frame:
        captured.append(frame(time.time(), len(captured)))
        return captured[-1]

    perceiver = make(capture_now=capture_now)
    assert perceiver.threads(None, None, None, 5.0, lambda: None, lambda *a: None) == []  # no camera thread
    first = perceiver.fresh_frame()
    assert first is captured[0] and perceiver.frames.get()[0] is first
    assert perceiver.frame_after(time.time() + 60.0) is captured[1]  # rendered now: never waits for the future
    assert perceiver.camera_problem() is None


def test_detections_are_the_newest_blocks_with_the_time_they_were_seen():
    perceiver = make()
    assert perceiver.detections().to_dict()["count"] == 0 and perceiver.detections().to_dict()["stale"] is False
    seen_s = time.time()
    perceiver.results.publish(Perception(blocks=(block(0.1), block(0.2)), capture_time_s=seen_s, frame_sequence=7))
    detections = perceiver.detections().to_dict()
    assert detections["count"] == 2 and detections["frame_sequence"] == 7 and not detections["stale"]
    assert [d["position_m"][0] for d in detections["data"]] == [0.1, 0.2]
    assert all(d["seen_time_s"] == seen_s for d in detections["data"])


def test_detections_are_stale_and_empty_while_the_camera_is_lost():
    perceiver = make(camera_lost="ConnectionError: unplugged")
    perceiver.results.publish(Perception(blocks=(block(0.1),), capture_time_s=time.time()))
    detections = perceiver.detections().to_dict()
    assert detections["data"] == [] and detections["stale"] and "camera is lost (ConnectionError: unplugged)" in detections["stale_reason"]


def test_detections_are_stale_when_perception_is_old_unless_captured_on_demand():
    perceiver = make()
    perceiver.results.publish(Perception(blocks=(block(0.1),), capture_time_s=time.time() - 5.0))
    detections = perceiver.detections().to_dict()
    assert detections["data"] == [] and detections["stale"] and "s old" in detections["stale_reason"]
    on_demand = make(capture_now=lambda: frame(time.time()))
    on_demand.results.publish(Perception(blocks=(block(0.1),), capture_time_s=time.time() - 5.0))
    assert on_demand.detections().to_dict()["count"] == 1  # nothing newer is coming until asked: not stale
