"""Numbers as MJCF text wants them, and the servo pieces both model writers (armlab.devices.sim.mjcf, mjcf_dh) write."""

from __future__ import annotations

import numpy as np

FEED_FORWARD_SUFFIX = "_ff"  # the ideal servo's acceleration feed-forward actuator: <joint>_ff


def fmt_numbers(values) -> str:
    """Space-separated numbers, 9 significant digits (an MJCF attribute value)."""
    return " ".join(f"{float(v):.9g}" for v in np.ravel(values))


def feed_forward_actuator(joint: str, force_limit_nm: float) -> str:
    """The ideal servo's acceleration feed-forward: a torque motor on the joint whose ctrl the workcell sets to the
    torque the commanded acceleration takes (SimWorkcell._inverse_dynamics). Without it the position and
    velocity servo reaches a new commanded acceleration only through a tracking error, then overshoots it (14 %
    of every step of the acceleration at the servos' damping, ~1.3-1.7x the limit where a jog or a blend reverses
    it). The joint's actuatorfrcrange caps the servo's total torque as before."""
    return (f'<motor name="{joint}{FEED_FORWARD_SUFFIX}" joint="{joint}" gear="1" '
            f'ctrlrange="{-force_limit_nm:.9g} {force_limit_nm:.9g}"/>')
