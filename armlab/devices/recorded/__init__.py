"""Recorded RGB-D camera backend: a folder of image_*.png + depth_*.png pairs, or a ROS bag, as a live camera."""

from armlab.devices.recorded.camera_recorded import RecordedCamera
from armlab.devices.recorded.configuration_recorded import RecordedCameraConfig
from armlab.devices.recorded.errors import RecordingError

__all__ = ["RecordedCamera", "RecordedCameraConfig", "RecordingError"]
