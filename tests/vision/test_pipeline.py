"""The per-frame pipeline the station runs: tags tracked near their calibrated spots, blocks, overlay."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.vision import OverlayLayers, PerceptionPipeline, calibrate_extrinsics, detect_blocks, detect_tags
from synth import L515


def test_pipeline_matches_the_standalone_functions(event_frame, cfg):
    frame, _ = event_frame
    cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg, depth_mm=frame.depth_mm)
    pipeline = PerceptionPipeline(cfg)
    result = pipeline.process(frame.color_bgr, frame.depth_mm, cal)
    full = detect_tags(frame.color_bgr, cfg)
    full = [t for t in full if t.id in cfg.tags.board_tags]  # the gripper's tag (workcell gripper.marker) is in view too
    assert [t.id for t in result.tags] == [t.id for t in full] == [1, 2, 3, 4]
    for tracked, found in zip(result.tags, full):
        np.testing.assert_allclose(tracked.corners_px, found.corners_px, atol=0.05)
    standalone = detect_blocks(frame.color_bgr, frame.depth_mm, cal, cfg)
    assert [(b.color, b.size, b.stack_level) for b in result.blocks] == [(b.color, b.size, b.stack_level) for b in standalone]
    assert result.overlay_bgr.shape == frame.color_bgr.shape and np.any(result.overlay_bgr != frame.color_bgr)
    assert pipeline.process(frame.color_bgr, frame.depth_mm, cal, layers=None).overlay_bgr is None


def test_pipeline_without_calibration_and_with_a_hidden_tag(event_frame, cfg):
    frame, _ = event_frame
    pipeline = PerceptionPipeline(cfg)
    uncalibrated = pipeline.process(frame.color_bgr, frame.depth_mm, None, layers=OverlayLayers(grid=True))
    assert [t.id for t in uncalibrated.tags if t.id in cfg.tags.board_tags] == [1, 2, 3, 4] and uncalibrated.blocks == []
    cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg)
    covered = frame.color_bgr.copy()
    u, v = np.round(uncalibrated.tags[1].center_px).astype(int)
    covered[v - 20 : v + 20, u - 20 : u + 20] = 40  # something dark over tag 2
    assert [t.id for t in pipeline.find_tags(covered, cal)] == [1, 3, 4]


def test_detect_blocks_refuses_bad_frames_and_finds_nothing_on_a_bare_board(event_frame, cfg, board_frame):
    frame, _ = event_frame
    cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg)
    with pytest.raises(ValueError, match="1280x720"):
        detect_blocks(frame.color_bgr[:360], frame.depth_mm[:360], cal, cfg)
    with pytest.raises(ValueError, match="uint16"):
        detect_blocks(frame.color_bgr, frame.depth_mm.astype(np.float32), cal, cfg)
    with pytest.raises(ValueError, match="BGR"):
        detect_blocks(frame.color_bgr[..., 0].copy(), frame.depth_mm, cal, cfg)
    with pytest.raises(ValueError, match="empty"):
        detect_blocks(np.zeros((0, 0, 3), np.uint8), frame.depth_mm, cal, cfg)
    bare_color, bare_depth = board_frame  # synthetic board: tags and grid, nothing standing on it
    bare_cal = calibrate_extrinsics(bare_color, L515, cfg)
    assert detect_blocks(bare_color, bare_depth, bare_cal, cfg) == []


def test_uncalibrated_tags_are_tracked_and_the_whole_image_searched_again_now_and_then(event_frame, cfg):
    """Uncalibrated, a whole-image search (~80 ms at 1280x720) runs on one frame in UNCALIBRATED_FULL_SEARCH_EVERY and
    the tags it found are tracked in between; a tag that appears is found within that many frames, and a tag that
    moves out of its window is found where it went on the same frame (a lost tag starts a whole-image search)."""
    from armlab.vision.pipeline import UNCALIBRATED_FULL_SEARCH_EVERY

    frame, _ = event_frame
    board = set(cfg.tags.board_tags)
    pipeline = PerceptionPipeline(cfg)
    full = [t for t in detect_tags(frame.color_bgr, cfg) if t.id in board]
    covered = frame.color_bgr.copy()
    u, v = np.round(full[1].center_px).astype(int)
    covered[v - 25 : v + 25, u - 25 : u + 25] = 40  # tag 2 hidden at first
    assert {t.id for t in pipeline.find_tags(covered, None)} & board == {1, 3, 4}
    seen = [{t.id for t in pipeline.find_tags(frame.color_bgr, None)} & board for _ in range(UNCALIBRATED_FULL_SEARCH_EVERY)]
    assert seen[-1] == {1, 2, 3, 4}, seen  # uncovered: found by the next whole-image search
    searches = pipeline.whole_image_searches
    for _ in range(3 * UNCALIBRATED_FULL_SEARCH_EVERY):
        tracked = [t for t in pipeline.find_tags(frame.color_bgr, None) if t.id in board]
        assert [t.id for t in tracked] == [1, 2, 3, 4]
        for mine, truth in zip(tracked, full):
            np.testing.assert_allclose(mine.corners_px, truth.corners_px, atol=0.05)
    assert pipeline.whole_image_searches - searches == 3  # one frame in UNCALIBRATED_FULL_SEARCH_EVERY
    shifted = np.roll(frame.color_bgr, (90, 140), axis=(0, 1))  # the camera looked elsewhere: every tag out of its window
    moved = [t for t in pipeline.find_tags(shifted, None) if t.id in board]
    assert [t.id for t in moved] == [1, 2, 3, 4]
    for mine, truth in zip(moved, full):
        np.testing.assert_allclose(mine.center_px, truth.center_px + [140, 90], atol=0.05)
