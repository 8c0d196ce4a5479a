"""The gripper found in the camera by its tag (armlab.vision.gripper_marker) in frames the simulation renders
with the arm at poses over the board, against MuJoCo's truth; the tag turned away from the camera is not found."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion import plan_joint_move
from armlab.vision import detect_tags
from armlab.vision.config import load_perception_config
from armlab.vision.geometry import invert_transform, transform_points
from armlab.vision.gripper_marker import MarkerNotFound, find_marker, tag_centre_px
from armlab.workcell import load_workcell

POSES = [((0.0, 0.25, 0.12), 0.0), ((0.2, 0.18, 0.22), 0.0), ((-0.2, 0.33, 0.16), 0.25), ((0.1, 0.38, 0.24), 0.0)]


@pytest.fixture(scope="module")
def sim():
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=0))
    cell.start()
    yield cell, load_arm("rx200"), load_perception_config(), load_workcell().gripper.marker
    cell.close()


def move(cell, model, position_m, pitch_rad: float, wrist_rotate_rad: float = 0.0) -> np.ndarray:
    q0 = cell.arm.read_joint_state().position_rad
    q = model.ik(np.asarray(position_m, float), pitch=pitch_rad, q_seed=q0)
    q[-1] = wrist_rotate_rad
    cell.arm.command_trajectory(plan_joint_move(q0, q, model), wait=True)
    cell.step(0.3)
    return q


@pytest.mark.parametrize("position_m, pitch_rad", POSES)
def test_the_gripper_tag_is_found_within_a_millimetre_of_the_truth(sim, position_m, pitch_rad):
    cell, model, cfg, marker = sim
    q = move(cell, model, position_m, pitch_rad)
    frame = cell.capture_next_frame()
    intrinsics = cell.camera.intrinsics
    sighting = find_marker(detect_tags(frame.color_bgr, cfg), marker.id, frame.depth_mm, intrinsics.K, np.asarray(intrinsics.dist))
    truth_world = cell.gripper_marker_m()
    T_world_camera = np.asarray(cell.truth()["camera"]["T_world_camera"])
    truth_camera = transform_points(invert_transform(T_world_camera), truth_world)[0]
    assert np.linalg.norm(sighting.point_camera_m - truth_camera) < 0.001
    # The workcell's mount is where the simulation puts the tag: FK + the configured offset lands on it.
    from_fk = transform_points(model.fk(q), np.asarray(marker.position_m))[0]
    assert np.linalg.norm(from_fk - truth_world) < 1e-4


def test_the_tag_turned_toward_the_board_is_not_found(sim):
    cell, model, cfg, marker = sim
    move(cell, model, (0.0, 0.25, 0.15), 0.0, wrist_rotate_rad=np.pi)
    frame = cell.capture_next_frame()
    intrinsics = cell.camera.intrinsics
    with pytest.raises(MarkerNotFound, match="not in view"):
        find_marker(detect_tags(frame.color_bgr, cfg), marker.id, frame.depth_mm, intrinsics.K, np.asarray(intrinsics.dist))


def test_the_centre_is_where_the_diagonals_cross_not_the_corners_mean():
    """A square seen in perspective: its centre projects where the image quad's diagonals cross."""
    corners = np.array([[0.0, 0.0], [10.0, 0.0], [8.0, 6.0], [2.0, 6.0]])  # a trapezoid: the far side shorter
    centre = tag_centre_px(corners)
    assert centre[0] == pytest.approx(5.0)
    assert centre[1] == pytest.approx(3.75)  # the diagonal (0, 0)-(8, 6) reaches x = 5 at 5/8 of its way: y = 6 * 5/8
    assert centre[1] != pytest.approx(corners[:, 1].mean())
