"""The gripper's parts against the board: the boxes the station keeps above it at every sample of a motion (the open
fingers, a finger gripper's palm), as corners in the gripper frame. Pure functions; the palm is the box the
simulation builds from config/sim.yaml `gripper:` (armlab.devices.finger_gripper), so the check and the physics agree."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from armlab.devices.arm_body import load_finger_gripper_outline
from armlab.errors import ConfigError
from armlab.motion.clearance import lowest_corners_m
from armlab.motion.gripper_step import FingerBox
from armlab.motion.safety import UnsafeTrajectory, excuse_a_resting_start


@lru_cache(maxsize=8)
def palm_corners_m(arm_name: str) -> np.ndarray | None:
    """(8, 3) corners of `arm_name`'s finger-gripper palm in the gripper frame, the box the simulation builds from
    config/sim.yaml `gripper:` (wider and taller than the fingers' box: the check left it out and the simulated palm
    met the board); None when the arm has no finger gripper outline. Read from the config files once per arm."""
    try:
        o = load_finger_gripper_outline(arm_name)
    except ConfigError:
        return None
    # The palm as a FingerBox: from palm_back_behind_m behind the gripper point to its front face, palm_front_behind_m
    # behind it (a negative reach).
    corners = FingerBox(o.palm_back_behind_m, -o.palm_front_behind_m, o.open_outer_m, o.palm_half_height_m).corners_m()
    corners.setflags(write=False)
    return corners


# A part resting on the board sits this far into it in the simulation's contact (and a real board's give).
RESTING_CONTACT_M = 1e-6


def check_parts_above_board(model, positions_rad: np.ndarray, times_s: np.ndarray, parts_corners_m: dict[str, np.ndarray]) -> None:
    """UnsafeTrajectory naming the part, how deep and when, if any corner of a part (name -> (K, 3) corners in the
    gripper frame) goes below the board (z = 0) at any sample. A motion that starts with a part already on or in
    the board (an arm slumped onto it with its torque off) may leave it: it is refused only for going deeper than
    where it starts, or for ending in the board (the rule the links' check keeps: excuse_a_resting_start)."""
    for part, corners_m in parts_corners_m.items():
        lowest_m, gripper_z_m = lowest_corners_m(model, positions_rad, corners_m)
        below = np.flatnonzero(excuse_a_resting_start(lowest_m + RESTING_CONTACT_M, 0.0) < 0.0)
        if below.size:
            sample = int(below[np.argmin(lowest_m[below])])
            raise UnsafeTrajectory(
                f"the {part} would go {-lowest_m[sample] * 1000:.1f} mm into the board (gripper point at z = "
                f"{gripper_z_m[sample] * 1000:.1f} mm) at t = {times_s[sample]:.3f} s", part=part,
                at_q_rad=positions_rad[sample],
            )
