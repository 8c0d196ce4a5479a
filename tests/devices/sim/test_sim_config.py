"""Sim configuration: bad values in config/sim.yaml or the camera yaml are refused at start-up with an
error naming the file and field; the mount and bump-error maths are right."""

import math

import numpy as np
import pytest
import yaml

from armlab.config import config_dir
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.devices.sim.config import (
    MountConfig,
    PoseErrorConfig,
    draw_pose_error,
    load_camera_config,
    nominal_T_world_camera,
)
from armlab.errors import ConfigError
from armlab.kinematics.rotations import rotation_from_rotvec


def write_variant(tmp_path, name, edit):
    data = yaml.safe_load((config_dir() / name).read_text())
    edit(data)
    path = tmp_path / f"variant_{name.replace('/', '_')}"
    path.write_text(yaml.safe_dump(data))
    return str(path)


@pytest.mark.parametrize(
    "edit,field",
    [
        (lambda d: d["physics"].update(timestep_s=-0.002), "physics.timestep_s"),
        (lambda d: d["physics"].update(control_period_s=0.05), "control_period_s"),
        (lambda d: d["arm"].update(kp=[1.0, 2.0]), "arm"),
        (lambda d: d["objects"].update(density_kg_m3=float("nan")), "objects.density_kg_m3"),
        (lambda d: d.update(wobble=1), "wobble"),
    ],
)
def test_bad_sim_config_is_refused_naming_the_field(tmp_path, edit, field):
    path = write_variant(tmp_path, "sim.yaml", edit)
    with pytest.raises(ConfigError, match=field) as error:
        SimWorkcell(SimWorkcellConfig(sim=path))
    assert path in str(error.value)


@pytest.mark.parametrize(
    "edit,field",
    [
        (lambda d: d["intrinsics"].update(cx=2000.0), "principal point"),
        (lambda d: d["intrinsics"].update(fx=0.0), "intrinsics.fx"),
        (lambda d: d["depth"].update(min_range_m=10.0), "min_range_m"),
        (lambda d: d["mount"].update(tilt_deg=80.0), "mount.tilt_deg"),
    ],
)
def test_bad_camera_config_is_refused_naming_the_field(tmp_path, edit, field):
    path = write_variant(tmp_path, "cameras/sim_l515.yaml", edit)
    with pytest.raises(ConfigError, match=field):
        SimWorkcell(SimWorkcellConfig(camera=path))


def test_workcell_config_refuses_nonsense():
    with pytest.raises(ValueError):
        SimWorkcellConfig(camera_fps=float("nan"))
    with pytest.raises(ValueError):
        SimWorkcellConfig(camera_fps=0.0)
    with pytest.raises(ValueError):
        SimWorkcellConfig(realtime=True, wobble=1)


def test_camera_config_matches_the_l515_figures():
    camera = load_camera_config()
    assert (camera.width, camera.height) == (1280, 720)
    assert camera.intrinsics.fx == pytest.approx(904, abs=5) and camera.intrinsics.fy == pytest.approx(904, abs=5)
    assert camera.intrinsics.cx == pytest.approx(644, abs=3) and camera.intrinsics.cy == pytest.approx(361, abs=3)


def test_nominal_mount_axes_follow_opencv_and_the_tilt():
    T = nominal_T_world_camera(MountConfig(position_m=[-0.04, 0.4, 1.0], tilt_deg=12.0))
    R = T[:3, :3]
    assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(R[:, 0], [1, 0, 0])  # image right = world +x
    assert R[1, 1] < -0.9  # image down = world -y
    assert math.degrees(math.acos(-R[2, 2])) == pytest.approx(12.0)
    assert R[1, 2] < 0  # tilted toward the arm (-y)


def test_pose_error_draws_stay_within_their_bounds():
    rng = np.random.default_rng(0)
    bounds = PoseErrorConfig(position_m=0.02, rotation_deg=3.0)
    angles = []
    for _ in range(500):
        T = draw_pose_error(rng, bounds)
        assert np.all(np.abs(T[:3, 3]) <= 0.02)
        angles.append(math.degrees(math.acos(np.clip((np.trace(T[:3, :3]) - 1) / 2, -1, 1))))
    assert max(angles) <= 3.0 + 1e-9 and max(angles) > 2.5


def test_rotation_from_rotvec_matches_a_known_rotation():
    R = rotation_from_rotvec(np.array([0.0, 0.0, math.pi / 2]))
    assert np.allclose(R @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(rotation_from_rotvec(np.zeros(3)), np.eye(3))
