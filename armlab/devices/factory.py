"""make_camera / make_arm / make_gripper: build a device from its config's `type` string.

A config is a validated config model, a mapping (parsed YAML), or the name of a file in
config/cameras/ or config/devices/ (or a path). Backends are imported lazily from the table below,
so choosing "opencv" never imports pyrealsense2 or ROS, and importing this module imports no backend.
Simulated devices ("sim") belong to one SimWorkcell (one MuJoCo model for arm, gripper, camera and
blocks): pass it as `workcell=` and the factory returns its device.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from armlab.config import read_config_file, resolve_config_path, validate_config
from armlab.errors import ConfigError

# type -> (module, config class, device class), per device kind. "sim" is handled by _sim_device.
BACKENDS: dict[str, dict[str, tuple[str, str, str]]] = {
    "camera": {
        "opencv": ("armlab.devices.opencv", "OpenCVCameraConfig", "OpenCVCamera"),
        "realsense": ("armlab.devices.realsense", "RealSenseCameraConfig", "RealSenseCamera"),
        "recorded": ("armlab.devices.recorded", "RecordedCameraConfig", "RecordedCamera"),
    },
    "arm": {
        "interbotix": ("armlab.devices.interbotix", "InterbotixArmConfig", "InterbotixArm"),
        "none": ("armlab.devices.none", "NoArmConfig", "NoArm"),
    },
    "gripper": {
        "interbotix": ("armlab.devices.interbotix", "InterbotixGripperConfig", "InterbotixGripper"),
        "none": ("armlab.devices.none", "NoGripperConfig", "NoGripper"),
    },
}
CONFIG_SUBDIRS = {"camera": "cameras", "arm": "devices", "gripper": "devices"}


def _as_mapping(config, kind: str) -> tuple[Mapping | object, str]:
    """(config, source) where config is a mapping or a model; names and paths are read from config/."""
    if isinstance(config, (str, Path)):
        path = resolve_config_path(config, CONFIG_SUBDIRS[kind])
        return read_config_file(path), str(path)
    return config, f"{kind} config"


def _config_type(config, source: str) -> str:
    kind_type = config.get("type") if isinstance(config, Mapping) else getattr(config, "type", None)
    if not isinstance(kind_type, str):
        raise ConfigError(f"{source}: type: missing (one of the backend names, e.g. 'sim', 'opencv')")
    return kind_type


def _build(kind: str, config, workcell=None, **device_kwargs):
    config, source = _as_mapping(config, kind)
    backend = _config_type(config, source)
    if backend == "sim":
        return _sim_device(kind, workcell, source)
    if backend not in BACKENDS[kind]:
        allowed = ", ".join(["sim", *BACKENDS[kind]])
        raise ConfigError(f"{source}: type: unknown {kind} backend '{backend}' (allowed: {allowed})")
    module_name, config_class_name, device_class_name = BACKENDS[kind][backend]
    module = importlib.import_module(module_name)
    config_class, device_class = getattr(module, config_class_name), getattr(module, device_class_name)
    if isinstance(config, Mapping):
        config = validate_config(dict(config), config_class, source)
    elif not isinstance(config, config_class):
        raise ConfigError(f"{source}: expected a {config_class_name} for type '{backend}', got {type(config).__name__}")
    return device_class(config, **device_kwargs)


def _sim_device(kind: str, workcell, source: str):
    """The simulated device of `workcell` (armlab.devices.sim.SimWorkcell): its .camera, .arm or .gripper."""
    if workcell is None:
        raise ConfigError(
            f"{source}: type 'sim': simulated devices share one MuJoCo workcell; create "
            f"armlab.devices.sim.SimWorkcell(...) and pass it as workcell= (or use its .{kind} directly)"
        )
    device = getattr(workcell, kind, None)
    if device is None:
        raise ConfigError(f"{source}: type 'sim': {type(workcell).__name__} has no .{kind}")
    return device


def make_camera(config, workcell=None):
    """A Camera from a config (model, mapping, or name in config/cameras/); not yet connected."""
    return _build("camera", config, workcell)


def make_arm(config, workcell=None):
    """An Arm from a config (model, mapping, or name in config/devices/); not yet connected."""
    return _build("arm", config, workcell)


def make_gripper(config, workcell=None, arm=None):
    """A Gripper; with an Interbotix `arm`, the gripper shares the arm's ROS connection."""
    connection = getattr(arm, "connection", None)
    if connection is not None:
        mapping, source = _as_mapping(config, "gripper")
        if _config_type(mapping, source) == "interbotix":
            return _build("gripper", config, workcell, connection=connection)
    return _build("gripper", config, workcell)


@dataclass(frozen=True)
class Devices:
    """The three devices a station runs on (not yet connected, unless they came from a started workcell)."""

    arm: object
    gripper: object
    camera: object


def make_devices(arm_config, gripper_config, camera_config, workcell=None) -> Devices:
    """Arm, gripper and camera from three configs; an Interbotix gripper shares the Interbotix arm's node.

    Backends may be mixed (e.g. the real arm with a webcam); "sim" devices come from `workcell`.
    """
    arm = make_arm(arm_config, workcell)
    gripper = make_gripper(gripper_config, workcell, arm=arm)
    camera = make_camera(camera_config, workcell)
    return Devices(arm=arm, gripper=gripper, camera=camera)
