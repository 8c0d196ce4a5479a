"""Skills: perception and manipulation steps above the station gate (armlab.station), below the tasks.

Imports go one way: armlab.tasks → armlab.skills → armlab.station → armlab.devices.
"""

from armlab.skills.arm_calibration import calibrate_arm
from armlab.skills.arm_camera import calibrate_arm_camera
from armlab.skills.manipulate import plan_pick_steps, plan_place_steps, run_steps
from armlab.skills.operator import calibrate, calibrate_points, calibration_summary, drop, grab
from armlab.skills.perceive import arm_hides_block, block_near, is_stale, look, pixel_to_world, surface_height_m
from armlab.skills.repeat import repeat

__all__ = [
    "arm_hides_block",
    "block_near",
    "calibrate",
    "calibrate_arm",
    "calibrate_arm_camera",
    "calibrate_points",
    "calibration_summary",
    "drop",
    "grab",
    "is_stale",
    "look",
    "pixel_to_world",
    "plan_pick_steps",
    "plan_place_steps",
    "repeat",
    "run_steps",
    "surface_height_m",
]
