"""Numbers as MJCF text wants them, shared by the model writers (armlab.devices.sim.mjcf, mjcf_dh)."""

from __future__ import annotations

import numpy as np


def fmt_numbers(values) -> str:
    """Space-separated numbers, 9 significant digits (an MJCF attribute value)."""
    return " ".join(f"{float(v):.9g}" for v in np.ravel(values))


def quat_wxyz_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix."""
    import mujoco

    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R, dtype=float).ravel())
    return quat
