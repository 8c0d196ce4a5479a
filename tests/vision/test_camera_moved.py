"""The camera knows it moved: with the station's calibration in use, the board tags' image positions
are checked every few seconds (simulated clock); the simulated mount bumped by 5 mm or 1 degree
warns "camera moved: recalibrate", an unmoved camera with the arm working in view stays quiet for
10 simulated minutes, and a new calibration clears the warning."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.scene import generate_scene
from armlab.vision import PerceptionPipeline, calibrate_extrinsics, load_perception_config
from armlab.vision.drift import CAMERA_MOVED, CAMERA_UNCONFIRMED, DriftMonitor

# Arm poses swept over the board (waist left to right, reaching over the tag rows); the arm moves
# smoothly from each to the next over MOVE_S, never resting, so every check sees it in motion.
WORK_POSES_RAD = [np.array([w, 0.35, 0.25, 1.0, 0.0]) for w in (-1.3, -0.7, 0.0, 0.7, 1.3, 0.7, 0.0, -0.7)]
MOVE_S = 4.5  # not a multiple of the 3 s check period: checks fall at every phase of a move
SERVO_STEP_S = 0.1


def work_reference(t_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The working arm's joint reference (position, velocity) at time t_s: smooth-step moves between the poses."""
    k, phase = divmod(t_s / MOVE_S, 1.0)
    a, b = WORK_POSES_RAD[int(k) % len(WORK_POSES_RAD)], WORK_POSES_RAD[(int(k) + 1) % len(WORK_POSES_RAD)]
    blend, rate = 3 * phase**2 - 2 * phase**3, (6 * phase - 6 * phase**2) / MOVE_S
    return a + (b - a) * blend, (b - a) * rate


@pytest.fixture()
def station_like():
    """A calibrated sim cell, a perception pipeline and a DriftMonitor, as the perception thread holds them."""
    cfg = load_perception_config()
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=21, camera_pose_error=True))
    cell.start()
    cell.set_scene(generate_scene("pick_sort", level=2, seed=21))
    cell.step(0.5)
    frame = cell.render()
    cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg, depth_mm=frame.depth_mm)
    yield cell, cfg, PerceptionPipeline(cfg), DriftMonitor(cfg.calibration), cal
    cell.close()


def _checks(cell, cfg, pipeline, monitor, cal, duration_s: float, arm_working: bool = False, seen: list | None = None) -> list[str | None]:
    """Run the cell for duration_s of simulated time, looking once per check period; the warnings seen.
    arm_working: the arm keeps moving over the board (servo references every 0.1 s). seen, if given,
    collects (board tags found, arm joints rad) at each check."""
    period_s = cfg.calibration.drift_check_period_s
    warnings = []
    for _ in range(int(round(duration_s / period_s))):
        for _ in range(int(round(period_s / SERVO_STEP_S))):
            if arm_working:
                cell.apply_arm_reference(*work_reference(cell.sim_time_s))
            cell.step(SERVO_STEP_S)
        frame = cell.render()
        tags = pipeline.find_tags(frame.color_bgr, cal)
        if seen is not None:
            seen.append((len({t.id for t in tags if t.id in cfg.tags.board_tags}), cell.arm_positions()))
        warnings.append(monitor.update(cell.sim_time_s, tags, cal, cfg))
    return warnings


def _bump(translation_m=(0.0, 0.0, 0.0), rotation_deg=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = cv2.Rodrigues(np.radians(np.asarray(rotation_deg, dtype=float)))[0]
    T[:3, 3] = translation_m
    return T


def test_quiet_for_ten_minutes_with_the_arm_working_in_view(station_like):
    cell, cfg, pipeline, monitor, cal = station_like
    seen = []
    warnings = _checks(cell, cfg, pipeline, monitor, cal, 600.0, arm_working=True, seen=seen)
    assert len(warnings) == 200 and not any(warnings), [w for w in warnings if w][:3]
    assert monitor.last_drift_px is not None and monitor.last_drift_px < 0.5
    # The arm was working in view: at a new place at (nearly) every check, and now and then hiding a board tag.
    moved_rad = [float(np.abs(b - a).max()) for (_, a), (_, b) in zip(seen, seen[1:])]
    assert sum(m > 0.05 for m in moved_rad) >= 150, sorted(moved_rad)[:10]
    assert any(count < len(cfg.tags.board_tags) for count, _ in seen)


@pytest.mark.parametrize("bump", [_bump(translation_m=(0.005, 0.0, 0.0)), _bump(rotation_deg=(1.0, 0.0, 0.0)),
                                  _bump(rotation_deg=(0.0, 0.0, 1.0))], ids=["5mm", "1deg-tilt", "1deg-roll"])
def test_a_bumped_mount_warns_and_a_new_calibration_clears_it(station_like, bump):
    cell, cfg, pipeline, monitor, cal = station_like
    assert not any(_checks(cell, cfg, pipeline, monitor, cal, 6.0))
    cell.bump_camera(bump)
    warnings = _checks(cell, cfg, pipeline, monitor, cal, 9.0, arm_working=True)
    assert warnings[-1] is not None and warnings[-1].startswith(CAMERA_MOVED)
    assert warnings[0] is None  # one check alone is not enough (drift_confirm_checks = 2)
    frame = cell.render()
    new_cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg, depth_mm=frame.depth_mm)
    assert not any(_checks(cell, cfg, pipeline, monitor, new_cal, 9.0))


def _overhead_calibration():
    """A camera 1 m above the board looking straight down (K of DESIGN.md §3), no distortion."""
    from armlab.vision import Calibration

    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # camera z down, x along world x
    T[:3, 3] = (0.0, 0.15, 1.0)
    K = np.array([[904.0, 0.0, 640.0], [0.0, 904.0, 360.0], [0.0, 0.0, 1.0]])
    return Calibration(T_world_camera=T, K=K, dist=np.zeros(5), width=1280, height=720, reprojection_error_px=0.3)


def _tags_at(cal, cfg, ids, offset_px=(0.0, 0.0)):
    """Board tags `ids` where `cal` puts them (+ offset_px), as the detector reports them."""
    from armlab.vision.geometry import project_points
    from armlab.vision.tags import Tag

    world = np.array([[*cfg.tags.board_tags[i], 0.0] for i in ids])
    centres = project_points(cal.T_world_camera, cal.K, cal.dist, world) + np.asarray(offset_px)
    return [Tag(id=i, corners_px=np.repeat(c[None], 4, axis=0), center_px=c) for i, c in zip(ids, centres)]


def test_too_few_board_tags_confirmed_is_a_warning_until_they_confirm_again():
    """Issue 18 item 3: after a large knock no board tag is where the check looks; that must not pass as
    'nothing to say'. Fewer than two board tags confirmed on drift_confirm_checks checks in a row warns (the
    calibration is not trusted); a check that confirms the camera again clears that warning."""
    cfg = load_perception_config()
    cal, monitor = _overhead_calibration(), DriftMonitor(cfg.calibration)
    period_s, ids = cfg.calibration.drift_check_period_s, sorted(cfg.tags.board_tags)
    assert monitor.update(0.0, _tags_at(cal, cfg, ids), cal, cfg) is None
    verdicts = [monitor.update(period_s * k, _tags_at(cal, cfg, ids[:1]), cal, cfg) for k in range(1, 4)]
    assert verdicts[0] is None  # one check alone is not enough (an arm over the tags for a moment)
    assert verdicts[-1] is not None and verdicts[-1].startswith(CAMERA_UNCONFIRMED), verdicts
    assert "1 of the 4 board tags" in verdicts[-1]
    assert monitor.update(period_s * 4, [], cal, cfg).startswith(CAMERA_UNCONFIRMED)
    assert monitor.update(period_s * 5, _tags_at(cal, cfg, ids[:2]), cal, cfg) is None  # confirmed again
    # A camera that moved stays 'moved' when the tags later vanish, and is not cleared by them.
    for k in range(6, 8):
        moved = monitor.update(period_s * k, _tags_at(cal, cfg, ids, offset_px=(9.0, 0.0)), cal, cfg)
    assert moved.startswith(CAMERA_MOVED)
    for k in range(8, 11):
        assert monitor.update(period_s * k, [], cal, cfg).startswith(CAMERA_MOVED)
