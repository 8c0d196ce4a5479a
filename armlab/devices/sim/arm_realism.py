"""The real arm in the simulation (`realism: real`, config/sim.yaml `arm: realism:`): the servos as the Dynamixel
firmware runs them, gear play and compliance, encoder readings as the driver publishes them, and a rig whose
joint zeros, link lengths and base pose differ from the nominal by seeded draws.

How the droop is split. The servo runs proportional position control without gravity feed-forward: its PWM is
P/128 per count of error (e-Manual "Position PID Gain"), a PWM of pwm_limit drives the stall torque, so the motor
holds a load torque tau at an error tau / kp (kp = stall * (P/128) / pwm_limit * counts / 2pi, about 19 N*m/rad
for an XM430-W350 at P 800). That part is fixed by the firmware's gain and the link masses; it shows in the joint
readings (the encoder sits on the motor's output). The rest of the measured sag (23 mm at 300 mm reach, gripper
level) is what the encoder cannot see: the gear play (backlash) taken up by gravity and the compliance of the
gears, horns and links, modelled as one passive joint per arm joint behind the motor (zero torque within +-backlash/2,
a spring of gear_stiffness beyond it). The gear stiffness is the one number chosen to make up that rest: about 70 %
of the droop shows in the readings, 30 % does not (tests/devices/sim/test_sim_real_arm.py).

Backlash: a link whose joint gravity does not load (the waist, wrist_rotate) is dragged by its bearing friction
(link_friction_nm) against the trailing flank of the play, so it stands 0.25 deg apart after approaching from either
side while its encoder reads the same; the same friction leaves the motor a count or two short of its goal."""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated

import numpy as np
from pydantic import Field, model_validator

from armlab.config import StrictModel

Positive = Annotated[float, Field(gt=0.0)]
NonNegative = Annotated[float, Field(ge=0.0)]
GEAR_SUFFIX = "_gear"  # the passive joint (and its tendon) behind each motor joint
GEAR_ARMATURE = 1e-4  # kg*m^2: keeps the passive joint's mass matrix regular (the gear train's own inertia)


class RigErrorConfig(StrictModel):
    """Per rig, drawn uniformly from the seed: joint zero offsets, link lengths, the base's place and yaw on the board."""

    joint_offset_deg: NonNegative
    link_length_m: NonNegative
    base_position_m: NonNegative
    base_yaw_deg: NonNegative


class ArmRealismConfig(StrictModel):
    """One arm's real servos and rig (one value per joint where a list)."""

    position_p_gain: list[Positive]  # the firmware's Position P Gain register (KPP = value / 128 PWM per count)
    pwm_limit: Positive  # PWM register value of 100 % duty (X series: 885)
    stall_torque_nm: list[Positive]  # the joint's servos together, at the supply voltage
    no_load_speed_rad_s: list[Positive]  # back-EMF: the motor's damping is stall / no-load speed
    gear_stiffness_nm_rad: list[Positive]  # compliance behind the encoder (gears, horns, links)
    gear_damping_nm_s_rad: list[NonNegative]
    link_friction_nm: NonNegative  # the links' bearings against the frame: a moving link drags on its gear's trailing flank
    backlash_deg: NonNegative
    encoder_counts_per_turn: Annotated[int, Field(ge=16)]
    velocity_unit_rad_s: Positive  # Present Velocity's unit (0.229 rev/min)
    joint_state_rate_hz: Positive  # how often the driver publishes joint states
    rig: RigErrorConfig

    @model_validator(mode="after")
    def _one_per_joint(self) -> ArmRealismConfig:
        lists = (self.position_p_gain, self.stall_torque_nm, self.no_load_speed_rad_s, self.gear_stiffness_nm_rad,
                 self.gear_damping_nm_s_rad)
        if len({len(values) for values in lists}) != 1:
            raise ValueError("realism: position_p_gain, stall_torque_nm, no_load_speed_rad_s, gear_stiffness_nm_rad "
                             "and gear_damping_nm_s_rad need one value per joint")
        return self

    def kp_nm_rad(self) -> np.ndarray:
        """Motor torque per radian of position error below saturation (the firmware's P gain)."""
        pwm_per_count = np.asarray(self.position_p_gain) / 128.0
        counts_per_rad = self.encoder_counts_per_turn / (2.0 * math.pi)
        return np.asarray(self.stall_torque_nm) * pwm_per_count / self.pwm_limit * counts_per_rad

    def kv_nm_s_rad(self) -> np.ndarray:
        """The motor's back-EMF damping (torque-speed line of a voltage-driven DC motor)."""
        return np.asarray(self.stall_torque_nm) / np.asarray(self.no_load_speed_rad_s)


@dataclasses.dataclass(frozen=True)
class RigDraw:
    """One rig's deviations from nominal: joint zeros (link angle = reading + offset), each URDF origin's length
    change (m, by origin name), the base's shift on the board (m, world x y) and yaw (rad)."""

    joint_offset_rad: np.ndarray
    origin_delta_m: dict[str, float]
    base_shift_m: np.ndarray
    base_yaw_rad: float

    def to_dict(self) -> dict:
        return {"joint_offset_rad": self.joint_offset_rad.tolist(), "origin_delta_m": dict(self.origin_delta_m),
                "base_shift_m": self.base_shift_m.tolist(), "base_yaw_rad": self.base_yaw_rad}


def draw_rig(rng: np.random.Generator, rig: RigErrorConfig, dof: int, origin_names) -> RigDraw:
    """Uniform draws within the configured bounds, in a fixed order (a seed gives the same rig)."""
    offsets = np.radians(rng.uniform(-rig.joint_offset_deg, rig.joint_offset_deg, size=dof))
    names = list(origin_names)
    deltas = rng.uniform(-rig.link_length_m, rig.link_length_m, size=len(names))
    shift = rng.uniform(-rig.base_position_m, rig.base_position_m, size=2)
    yaw = math.radians(rng.uniform(-rig.base_yaw_deg, rig.base_yaw_deg))
    return RigDraw(offsets, {n: float(d) for n, d in zip(names, deltas)}, shift, yaw)


@dataclasses.dataclass(frozen=True)
class RealArm:
    """What the model builder needs for the real arm: servo gains and limits, gear play and compliance, the rig."""

    kp_nm_rad: np.ndarray
    kv_nm_s_rad: np.ndarray
    stall_torque_nm: np.ndarray
    gear_stiffness_nm_rad: np.ndarray
    gear_damping_nm_s_rad: np.ndarray
    link_friction_nm: float
    backlash_rad: float
    rig: RigDraw

    @classmethod
    def from_config(cls, config: ArmRealismConfig, rig: RigDraw) -> RealArm:
        return cls(config.kp_nm_rad(), config.kv_nm_s_rad(), np.asarray(config.stall_torque_nm, float),
                   np.asarray(config.gear_stiffness_nm_rad, float), np.asarray(config.gear_damping_nm_s_rad, float),
                   config.link_friction_nm, math.radians(config.backlash_deg), rig)


def rig_origins(origins_m: dict[str, tuple], rig: RigDraw) -> dict[str, tuple]:
    """The URDF joint origins with each one's length changed by its drawn delta along its own direction."""
    changed = {}
    for name, vector in origins_m.items():
        v = np.asarray(vector, dtype=float)
        length = float(np.linalg.norm(v))
        delta = rig.origin_delta_m.get(name, 0.0)
        changed[name] = tuple(v * (length + delta) / length) if length > 0 else tuple(v)
    return changed


def rig_base(T_world_base: np.ndarray, rig: RigDraw) -> np.ndarray:
    """The base pose shifted on the board and turned about the vertical by the drawn amounts."""
    c, s = math.cos(rig.base_yaw_rad), math.sin(rig.base_yaw_rad)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = rig.base_shift_m
    out = np.asarray(T_world_base, dtype=float).copy()
    out[:3, :3] = T[:3, :3] @ out[:3, :3]
    out[:3, 3] = T[:3, :3] @ out[:3, 3] + T[:3, 3]
    return out


def real_geometry(geometry, config: ArmRealismConfig, rng: np.random.Generator, rig_error: bool = True):
    """An ArmGeometry (armlab.devices.sim.mjcf) made the real arm: a rig drawn from `rng` (nominal when not
    rig_error: the servos and gears stay real), its origins and base pose, the real servos."""
    bounds = config.rig if rig_error else config.rig.model_copy(
        update={"joint_offset_deg": 0.0, "link_length_m": 0.0, "base_position_m": 0.0, "base_yaw_deg": 0.0})
    rig = draw_rig(rng, bounds, len(geometry.joint_names), geometry.origins_m)
    return dataclasses.replace(geometry, origins_m=rig_origins(geometry.origins_m, rig),
                               T_world_base=rig_base(geometry.T_world_base, rig), real=RealArm.from_config(config, rig))


class JointStatePublisher:
    """The driver's joint states: sampled every 1/rate_hz of simulated time, positions as whole encoder counts
    and velocities as whole Present Velocity units; read_joint_state returns the last sample."""

    def __init__(self, config: ArmRealismConfig) -> None:
        self.period_s = 1.0 / config.joint_state_rate_hz
        self._count_rad = 2.0 * math.pi / config.encoder_counts_per_turn
        self._velocity_unit = config.velocity_unit_rad_s
        self._next_s = 0.0
        self.sample: tuple[np.ndarray, np.ndarray, float] | None = None

    def quantise(self, position_rad: np.ndarray, velocity_rad_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return (np.round(position_rad / self._count_rad) * self._count_rad,
                np.round(velocity_rad_s / self._velocity_unit) * self._velocity_unit)

    def due(self, sim_time_s: float) -> bool:
        return self.sample is None or sim_time_s + 1e-9 >= self._next_s

    def publish(self, sim_time_s: float, position_rad: np.ndarray, velocity_rad_s: np.ndarray) -> None:
        position, velocity = self.quantise(position_rad, velocity_rad_s)
        self.sample = (position, velocity, sim_time_s)
        self._next_s = (math.floor(sim_time_s / self.period_s + 1e-6) + 1) * self.period_s
