"""Which arm model the simulation builds for a workcell: the RX200 with its fingers (mjcf.ArmGeometry), or
a DH-described arm with a suction cup (mjcf_dh.DhArmGeometry), placed at the workcell's base pose. The
workcell decides the arm; a caller naming another arm, an arm without what its gripper type needs, or
missing simulation parameters stop start-up with a ConfigError naming the file and field."""

from __future__ import annotations

import dataclasses

from armlab.devices.sim.config import SimConfig
from armlab.devices.sim.mjcf import ArmGeometry
from armlab.devices.sim.mjcf_dh import DhArmGeometry
from armlab.errors import ConfigError
from armlab.workcell import Workcell


def select_arm(workcell: Workcell, arm: str | None, sim: SimConfig, sim_name: str = "sim") -> ArmGeometry | DhArmGeometry:
    """The geometry to build for `workcell`; `arm` (a caller's choice, None = the workcell's) must agree."""
    if arm is not None and arm != workcell.arm:
        raise ConfigError(f"SimWorkcellConfig.arm: '{arm}' contradicts workcell '{workcell.name}', whose arm "
                          f"is '{workcell.arm}' (the workcell decides the arm: leave arm unset)")
    workcell.check_arm_fits()
    T_world_base = None if workcell.arm_base is None else workcell.arm_base.T_world_base
    try:
        if workcell.gripper.type == "suction":
            if sim.suction is None:
                raise ValueError(f"config/{sim_name}.yaml: suction: missing (the simulated cup's parameters)")
            sim.servos(workcell.arm)  # ValueError naming arms.<name> if the arm's servos are not configured
            return DhArmGeometry.load(workcell.arm, T_world_base)
        if workcell.arm != "rx200":
            raise ValueError(f"workcell '{workcell.name}': the simulation builds finger grippers on the RX200 only, "
                             f"not on '{workcell.arm}'")
        geometry = ArmGeometry.load(workcell.arm)
    except ValueError as error:
        raise ConfigError(str(error)) from None
    return geometry if T_world_base is None else dataclasses.replace(geometry, T_world_base=T_world_base)
