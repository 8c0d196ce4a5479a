"""Perception and calibration: tags, extrinsic/intrinsic calibration, pixel <-> world, block and
depth-object detection, overlay drawing. Pure functions over images; no device or HTTP knowledge."""

from armlab.vision.blocks import Block, detect_blocks
from armlab.vision.calibration import Calibration, CalibrationError, calibrate_extrinsics, project_grid
from armlab.vision.config import PerceptionConfig, load_perception_config
from armlab.vision.intrinsics import IntrinsicCalibration, calibrate_intrinsics
from armlab.vision.objects import DepthObject, detect_objects_from_depth
from armlab.vision.overlay import OverlayLayers, draw_overlay, top_down_view
from armlab.vision.pipeline import PerceptionPipeline, PerceptionResult
from armlab.vision.pixel_world import pixel_to_world, world_to_pixel
from armlab.vision.tags import Tag, detect_tags

__all__ = [
    "Block",
    "Calibration",
    "CalibrationError",
    "DepthObject",
    "IntrinsicCalibration",
    "OverlayLayers",
    "PerceptionConfig",
    "PerceptionPipeline",
    "PerceptionResult",
    "Tag",
    "calibrate_extrinsics",
    "calibrate_intrinsics",
    "detect_blocks",
    "detect_objects_from_depth",
    "detect_tags",
    "draw_overlay",
    "load_perception_config",
    "pixel_to_world",
    "project_grid",
    "top_down_view",
    "world_to_pixel",
]
