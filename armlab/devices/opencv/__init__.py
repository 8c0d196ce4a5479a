"""OpenCV (cv2.VideoCapture) camera backend: a webcam index or a video file."""

from armlab.devices.opencv.camera_opencv import OpenCVCamera
from armlab.devices.opencv.configuration_opencv import IntrinsicsConfig, OpenCVCameraConfig

__all__ = ["IntrinsicsConfig", "OpenCVCamera", "OpenCVCameraConfig"]
