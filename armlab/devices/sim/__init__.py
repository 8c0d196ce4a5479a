"""The simulated workcell (MuJoCo): the default backend. `SimWorkcell` owns the model and hands out
the sim Arm, Gripper and Camera; `SimWorkcellConfig` chooses fast/real-time mode, seed and noise."""

from armlab.devices.sim.config import SimCameraConfig, SimWorkcellConfig
from armlab.devices.sim.workcell import SimWorkcell

__all__ = ["SimCameraConfig", "SimWorkcell", "SimWorkcellConfig"]
