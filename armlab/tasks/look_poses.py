"""Where a job parks the arm while the camera looks: the arm's sleep pose, the workcell's look_pose_rad, or an
overhead pose that hides no block (the look pose of jobs that must see every block)."""

from __future__ import annotations

import math

import numpy as np

from armlab.errors import InvalidInput
from armlab.scene import as_workcell
from armlab.station.core import Station


def park_pose(model) -> np.ndarray:
    """Where the arm waits while the camera looks: the sleep pose (folded beside the base, low)."""
    return np.asarray(model.sleep_rad, float)


def look_pose(station: Station) -> np.ndarray:
    """Where a job parks the arm while the camera looks: the station's workcell's look_pose_rad (one that
    hides nothing from that workcell's camera), else the arm's sleep pose (park_pose)."""
    q = as_workcell(getattr(station.config, "workcell", None)).look_pose_rad
    if q is None:
        return park_pose(station.model)
    if len(q) != station.model.dof:
        raise InvalidInput(f"workcell look_pose_rad has {len(q)} joints; the arm has {station.model.dof}")
    return np.asarray(q, float)


OVERHEAD_LOOK_POINT_M = (0.0, 0.09, 0.22)  # gripper point, pointing down, elbow up over the base


def overhead_look_pose(model) -> np.ndarray:
    """A look pose that hides no block: the arm upright over its base, the gripper pointing down high
    in front of it. Everything stays within ~0.1 m of the base axis and high above the blocks, so
    the camera (above the board's far side) sees the arm only over the board strip behind the base,
    and the self-filter's inflated volume holds no block; the sleep pose's low gripper masks blocks
    beside it. The wrist is turned a quarter turn so the gripper's wide side (the fingers' travel)
    lies along the arm: crosswise it hid a block at (90, -65) mm, pick_sort's first large slot."""
    q = model.ik(OVERHEAD_LOOK_POINT_M, pitch=math.pi / 2, yaw=0.0, q_seed=np.zeros(model.dof))
    q[-1] = math.pi / 2
    return q


def seeing_look_pose(station: Station) -> np.ndarray:
    """The look pose of a job that must see every block (pick_sort, pick_stack): the station's workcell's
    look_pose_rad when it defines one (chosen for that workcell's camera), else overhead_look_pose, which
    is the RX200's (its IK point is out of other arms' reach at pitch 90 deg, e.g. the UR3's)."""
    if as_workcell(getattr(station.config, "workcell", None)).look_pose_rad is not None:
        return look_pose(station)
    return overhead_look_pose(station.model)
