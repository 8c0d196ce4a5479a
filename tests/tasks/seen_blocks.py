"""Detections for policy tests: armlab.vision Blocks built from the few fields a policy reads (what a look hands it)."""

from __future__ import annotations

import numpy as np

from armlab.vision.block import Block


def seen_block(color: str | None, size: str | None, x: float, y: float, z_top: float, level: int = 1, cube: bool = True,
               yaw_rad: float = 0.0, **fields) -> Block:
    """A detected block whose top face's centre is at (x, y, z_top) m, on a pile of `level` blocks."""
    return Block(color=color, size=size, position_m=np.array([x, y, z_top], float), yaw_rad=float(yaw_rad), height_m=float(z_top),
                 stack_level=level, center_px=np.zeros(2), contour_px=np.zeros((0, 2)), is_cube=cube, **fields)
