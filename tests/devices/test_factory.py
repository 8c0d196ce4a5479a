"""The device factory: backend chosen by `type`, lazy imports, clear errors, shipped configs valid."""

from __future__ import annotations

import subprocess
import sys
import types

import numpy as np
import pytest

from armlab.devices.factory import make_arm, make_camera, make_gripper
from armlab.devices.opencv import OpenCVCamera, OpenCVCameraConfig
from armlab.devices.opencv.recording import write_video
from armlab.errors import ConfigError, DeviceNotConnectedError


def test_opencv_camera_from_a_mapping_connects_and_reads(tmp_path):
    path = write_video(tmp_path / "clip.avi", [np.full((24, 32, 3), 100, np.uint8)] * 3)
    camera = make_camera({"type": "opencv", "source": str(path)})
    assert isinstance(camera, OpenCVCamera)
    camera.connect()
    try:
        assert camera.async_read(timeout_ms=2000).color_bgr.shape == (24, 32, 3)
    finally:
        camera.close()


def test_config_model_and_shipped_names_are_accepted():
    model = OpenCVCameraConfig(source=3)
    assert make_camera(model).config is model
    assert make_camera("webcam").config.source == 0  # config/cameras/webcam.yaml
    realsense = make_camera("realsense_l515")
    assert type(realsense).__name__ == "RealSenseCamera"
    assert (realsense.config.width, realsense.config.height, realsense.config.fps) == (1280, 720, 30)
    arm = make_arm("interbotix_arm")
    assert arm.joint_names == ("waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate") and not arm.is_connected
    gripper = make_gripper("interbotix_gripper", arm=arm)
    assert gripper.connection is arm.connection  # one ROS node for both


@pytest.mark.parametrize(
    "maker, config, message",
    [
        (make_camera, {"type": "kinect", "source": 0}, r"unknown camera backend 'kinect' \(allowed: sim, opencv, realsense, recorded\)"),
        (make_camera, {"source": 0}, "type: missing"),
        (make_camera, {"type": "opencv", "source": 0, "fps": -5}, "fps"),
        (make_arm, {"type": "opencv"}, "unknown arm backend 'opencv'"),
        (make_gripper, {"type": "interbotix", "pressure": 2.0}, "pressure"),
        (make_camera, "no_such_camera", "no config 'no_such_camera'"),
    ],
)
def test_bad_configs_are_config_errors(maker, config, message):
    with pytest.raises(ConfigError, match=message):
        maker(config)


def test_sim_type_needs_the_workcell_and_returns_its_device():
    with pytest.raises(ConfigError, match="SimWorkcell"):
        make_camera({"type": "sim"})
    workcell = types.SimpleNamespace(camera=object(), arm=object(), gripper=object())
    assert make_camera({"type": "sim"}, workcell=workcell) is workcell.camera
    assert make_arm({"type": "sim"}, workcell=workcell) is workcell.arm
    assert make_gripper({"type": "sim"}, workcell=workcell) is workcell.gripper


def test_missing_sdks_give_install_instructions_naming_the_device():
    realsense = make_camera({"type": "realsense"})
    with pytest.raises(ImportError, match=r"^RealSenseCamera\(first\): .*pip install 'armlab\[realsense\]'"):
        realsense.connect()
    assert not realsense.is_connected
    with pytest.raises(DeviceNotConnectedError, match=r"^RealSenseCamera"):
        realsense.read_latest()

    arm = make_arm({"type": "interbotix"})
    with pytest.raises(ImportError, match=r"^InterbotixArm\(rx200\): .*ROS 2.*interbotix"):
        arm.connect()
    assert not arm.is_connected
    for call in (arm.read_joint_state, arm.stop, arm.is_moving):
        with pytest.raises(DeviceNotConnectedError, match=r"^InterbotixArm\(rx200\)"):
            call()
    gripper = make_gripper({"type": "interbotix"})
    with pytest.raises(ImportError, match=r"^InterbotixGripper\(rx200\)"):
        gripper.connect()
    with pytest.raises(DeviceNotConnectedError):
        gripper.grasp()


def test_importing_the_factory_and_choosing_opencv_imports_no_vendor_sdk():
    code = (
        "import sys\n"
        "from armlab.devices.factory import make_camera\n"
        "make_camera({'type': 'opencv', 'source': 0})\n"
        "heavy = [m for m in ('pyrealsense2', 'rclpy', 'interbotix_xs_modules', 'mujoco', 'armlab.devices.realsense',"
        " 'armlab.devices.interbotix') if m in sys.modules]\n"
        "print(heavy)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


def test_make_devices_mixes_backends_and_shares_the_interbotix_node(tmp_path):
    from armlab.devices.factory import make_devices

    devices = make_devices("interbotix_arm", "interbotix_gripper", {"type": "opencv", "source": str(tmp_path / "x.avi")})
    assert type(devices.arm).__name__ == "InterbotixArm" and type(devices.camera).__name__ == "OpenCVCamera"
    assert devices.gripper.connection is devices.arm.connection
    workcell = types.SimpleNamespace(camera=object(), arm=object(), gripper=object())
    sim = make_devices({"type": "sim"}, {"type": "sim"}, {"type": "sim"}, workcell=workcell)
    assert (sim.arm, sim.gripper, sim.camera) == (workcell.arm, workcell.gripper, workcell.camera)
