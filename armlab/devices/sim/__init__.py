"""The simulated workcell (MuJoCo): the default backend. `SimWorkcell` owns the model and hands out
the sim Arm, Gripper and Camera; `SimWorkcellConfig` chooses fast/real-time mode, seed and noise.

MuJoCo picks its GL backend when it is first imported, so this package defaults MUJOCO_GL to "egl"
(headless, works on a CPU-only machine) before importing it; set MUJOCO_GL yourself to override."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

from armlab.devices.sim.config import SimCameraConfig, SimWorkcellConfig  # noqa: E402
from armlab.devices.sim.workcell import SimWorkcell  # noqa: E402

__all__ = ["SimCameraConfig", "SimWorkcell", "SimWorkcellConfig"]
