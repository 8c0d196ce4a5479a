"""Intel RealSense backend (pyrealsense2, an optional extra imported only inside connect())."""

from armlab.devices.realsense.camera_realsense import RealSenseCamera, RealSenseNotInstalledError
from armlab.devices.realsense.configuration_realsense import RealSenseCameraConfig

__all__ = ["RealSenseCamera", "RealSenseCameraConfig", "RealSenseNotInstalledError"]
