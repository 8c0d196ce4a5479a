"""A simulated frame is stamped with a time no later than the state it shows was copied: a render thread
preempted between copying the state and reading the clock (a loaded machine) stamped a frame of the scene
before a change with a time after it, and a request that waits for a frame taken after its arrival
(frame_after: the intrinsics capture, the arm's calibration poses) got the old scene."""

from __future__ import annotations

import time

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig


def test_the_frame_time_is_taken_before_the_state_is_copied():
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=0)) as cell:
        cell.start()
        render_thread = cell._renderer()
        copied_at_s = []
        snapshot = render_thread._snapshot

        def timed_snapshot(renderer):
            copied_at_s.append(time.time())
            return snapshot(renderer)

        render_thread._snapshot = timed_snapshot
        images = cell.render_raw()
        assert copied_at_s and images.wall_time_s <= copied_at_s[-1]
