"""The MuJoCo model of an arm described by a standard DH table (config/arms/<name>.yaml `dh:`), with a
vacuum suction cup at its tool point: one body per joint, placed by the DH rows so that the bodies'
frames are the DH frames; links drawn as capsules along the DH offsets (d along the joint axis, then a
along x: the skeleton UR's DH table describes); the tool point site at the last frame times dh.tool.

The cup (body "suction_cup" in the tool frame, approach axis +x): a cylinder behind the lip and the lip,
a ring of small spheres whose contact shells (LIP_MARGIN_M) reach past the plane through the tool point. The suction
gripper measures each lip sphere's distance to the objects' faces to decide whether the lip seals
(armlab.devices.sim.suction.seal_object); MuJoCo's adhesion actuator "suction" pulls on the cup's
contacts while the vacuum holds.
Pure: same inputs, same XML."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.config import read_config_file, resolve_config_path
from armlab.devices.arm_body import ArmBody, arm_body, dh_link_radii_m
from armlab.devices.sim.config import ArmServoConfig, SimConfig
from armlab.devices.sim.mjcf_numbers import feed_forward_actuator
from armlab.devices.sim.mjcf_numbers import fmt_numbers as _fmt
from armlab.kinematics import load_arm
from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.rotations import quat_wxyz_from_matrix as _quat
from armlab.kinematics.rotations import rotation_about

GRIPPER_SITE = "gripper_point"  # same name as the RX200 model's (armlab.devices.sim.mjcf)
CUP_BODY = "suction_cup"
LIP_PREFIX = "lip_"
SUCTION_ACTUATOR = "suction"
# The lip's contact shell: contacts (and so the adhesion, which acts through them) start LIP_MARGIN_M
# from the lip spheres, which sit half that behind the tool point's plane: a face in that plane is in
# contact (pressed 0.5 mm). Without the shell a block resting exactly under the lip, asleep, has no
# contact for the vacuum to pull through.
LIP_MARGIN_M = 0.001
ARM_GEOM = 'contype="2" conaffinity="1" group="1"'


def _rx(angle: float) -> np.ndarray:
    return rotation_about((1.0, 0.0, 0.0), angle)


def _rz(angle: float) -> np.ndarray:
    return rotation_about((0.0, 0.0, 1.0), angle)


@dataclass(frozen=True)
class SuctionCup:
    """config/arms/<name>.yaml suction_cup (metres)."""

    lip_radius_m: float
    body_radius_m: float
    body_length_m: float


@dataclass(frozen=True)
class DhArmGeometry:
    """What the model needs of a DH-described arm with a suction cup, and its base pose on the board."""

    name: str
    joint_names: tuple[str, ...]
    dh_rows: np.ndarray  # (n, 5): theta_offset_rad, d_m, a_m, alpha_rad, joint_sign
    tool: np.ndarray  # (4, 4): last DH frame -> tool point frame (x = approach axis)
    lower_rad: np.ndarray
    upper_rad: np.ndarray
    velocity_limit_rad_s: np.ndarray
    T_world_base: np.ndarray
    sleep_rad: np.ndarray
    cup: SuctionCup
    config: ArmConfig  # the validated arm file (its links' shapes: armlab.devices.arm_body)

    @classmethod
    def load(cls, name: str, T_world_base: np.ndarray | None = None) -> DhArmGeometry:
        """From config/arms/<name>.yaml; T_world_base (the workcell's base pose) replaces the file's if given.
        ValueError naming the file and field if the arm has no dh table or no suction_cup."""
        path = resolve_config_path(name, "arms")
        config = load_arm(path).config  # validated
        if config.dh is None:
            raise ValueError(f"{path}: dh: the simulation builds this arm from its DH table, and there is none")
        if config.suction_cup is None:
            raise ValueError(f"{path}: suction_cup: missing (the simulated DH arm carries a suction cup)")
        data = read_config_file(path)
        return cls(
            name=config.name,
            joint_names=tuple(config.joint_names),
            dh_rows=np.asarray(config.dh.rows, dtype=float),
            tool=np.asarray(config.dh.tool, dtype=float),
            lower_rad=np.radians(np.asarray(config.limits.lower_deg, dtype=float)),
            upper_rad=np.radians(np.asarray(config.limits.upper_deg, dtype=float)),
            velocity_limit_rad_s=np.asarray(config.limits.velocity_rad_s, dtype=float),
            T_world_base=np.asarray(data["T_world_base"] if T_world_base is None else T_world_base, dtype=float),
            sleep_rad=np.asarray(config.poses.sleep_rad, dtype=float),
            cup=SuctionCup(**config.suction_cup.model_dump()),
            config=config,
        )

    # The RX200 geometry's finger fields, for code that reads them off either geometry: no fingers.
    finger_offset_min_m = 0.0
    finger_offset_max_m = 0.0
    pad_thickness_m = 0.0

    def mjcf(self, sim: SimConfig) -> tuple[str, str]:
        """(worldbody xml of the arm, actuator xml)."""
        servo = sim.servos(self.name)
        if sim.suction is None:
            raise ValueError("config/sim.yaml: suction: missing (the simulated suction cup's parameters)")
        return _chain_xml(self, servo, sim), _actuators_xml(self, servo, sim)


def _geoms(body: ArmBody, frame: int) -> str:
    """The arm body's parts on frame `frame` (armlab.devices.arm_body: 0 the base, 1 + i joint i's link) as geoms."""
    out = []
    for part in body.parts:
        if part.frame != frame:
            continue
        T = part.T_frame_part
        size = part.size_m if part.shape == "box" else part.size_m[:2]
        material = "arm" if part.shape == "capsule" else "arm_dark"
        out.append(f'<geom name="{part.name}" type="{part.shape}" size="{_fmt(size)}" pos="{_fmt(T[:3, 3])}" '
                   f'quat="{_fmt(_quat(T[:3, :3]))}" material="{material}" {ARM_GEOM}/>')
    return "".join(out)


def _inertial(d: float, a: float, mass: float, radius: float) -> str:
    length = math.hypot(d, a)
    centre = (0.5 * a, 0.0, 0.5 * d) if length > 1e-9 else (0.0, 0.0, 0.0)
    inertia = mass * (length**2 / 12.0 + radius**2 / 4.0) + 1e-5
    return f'<inertial pos="{_fmt(centre)}" mass="{mass}" diaginertia="{inertia:.6g} {inertia:.6g} {inertia:.6g}"/>'


def _cup_xml(arm: DhArmGeometry, sim: SimConfig) -> str:
    """The suction cup in the tool frame (origin = lip centre, +x = approach): body cylinder and lip ring."""
    suction = sim.suction
    cup = arm.cup
    r_s = suction.lip_sphere_radius_m
    lip = []
    for k in range(suction.lip_points):
        angle = 2.0 * math.pi * k / suction.lip_points
        y, z = cup.lip_radius_m * math.cos(angle), cup.lip_radius_m * math.sin(angle)
        lip.append(
            f'<geom name="{LIP_PREFIX}{k}" type="sphere" size="{r_s:.9g}" pos="{-r_s - 0.5 * LIP_MARGIN_M:.9g} {y:.9g} {z:.9g}" material="pad" '
            f'condim="4" friction="{_fmt(suction.lip_friction)}" solref="{_fmt(suction.lip_solref)}" solmix="1000" '
            f'margin="{LIP_MARGIN_M}" {ARM_GEOM}/>'
        )
    back = -cup.body_length_m
    front = -2.0 * r_s - LIP_MARGIN_M - 0.001  # the body ends behind the lip: only the lip touches a face
    return (
        f'<body name="{CUP_BODY}" gravcomp="1">'
        f'<inertial pos="{0.5 * (back + front):.9g} 0 0" mass="{suction.cup_mass_kg}" diaginertia="1e-5 1e-5 1e-5"/>'
        f'<geom name="cup_body" type="cylinder" size="{cup.body_radius_m:.9g}" fromto="{back:.9g} 0 0 {front:.9g} 0 0" '
        f'material="pad" {ARM_GEOM}/>'
        f'{"".join(lip)}</body>'
    )


def _chain_xml(arm: DhArmGeometry, servo: ArmServoConfig, sim: SimConfig) -> str:
    """Base (static) -> one body per joint (frame = DH frame i-1 turned by theta_offset_i; the joint turns
    about its z) -> the flange (DH frame n) -> the tool frame ("gripper_link", site at the tool point)."""
    rows = arm.dh_rows
    radii = dh_link_radii_m(arm.config, servo.link_radius_m)  # the same rule as the stations' body_of
    # The links' shapes: the arm body (armlab.devices.arm_body) with those radii
    body = arm_body(arm.config.model_copy(update={"link_radii_m": radii}))
    opened = []
    for i, name in enumerate(arm.joint_names):
        offset, d, a, alpha, sign = rows[i]
        if i == 0:
            pos, R = np.zeros(3), _rz(offset)
        else:
            prev = rows[i - 1]
            pos, R = np.array([prev[2], 0.0, prev[1]]), _rx(prev[3]) @ _rz(offset)
        lo, hi = arm.lower_rad[i], arm.upper_rad[i]
        opened.append(
            f'<body name="{name}_link" pos="{_fmt(pos)}" quat="{_fmt(_quat(R))}" gravcomp="1">'
            f'{_inertial(d, a, servo.link_masses_kg[i], radii[i])}'
            f'<joint name="{name}" axis="0 0 {sign:g}" range="{lo:.9g} {hi:.9g}" armature="{servo.armature[i]}" '
            f'damping="{servo.damping[i]}" actuatorfrcrange="{-servo.force_limit_nm[i]} {servo.force_limit_nm[i]}"/>'
            f'{_geoms(body, 1 + i)}'
        )
    last = rows[-1]
    flange = np.array([last[2], 0.0, last[1]])
    tool_pos = arm.tool[:3, 3]
    tool_quat = _quat(arm.tool[:3, :3])
    tool = (
        f'<body name="flange" pos="{_fmt(flange)}" quat="{_fmt(_quat(_rx(last[3])))}" gravcomp="1">'
        f'<body name="gripper_link" pos="{_fmt(tool_pos)}" quat="{_fmt(tool_quat)}" gravcomp="1">'
        f'<site name="{GRIPPER_SITE}" pos="0 0 0" size="0.003" rgba="1 0 1 0.5" group="4"/>'
        f'{_cup_xml(arm, sim)}</body></body>'
    )
    return (
        f'<body name="base" pos="{_fmt(arm.T_world_base[:3, 3])}" quat="{_fmt(_quat(arm.T_world_base[:3, :3]))}">'
        f'{_geoms(body, 0)}'
        f'{"".join(opened)}{tool}{"</body>" * len(opened)}</body>'
    )


def _actuators_xml(arm: DhArmGeometry, servo: ArmServoConfig, sim: SimConfig) -> str:
    """Per joint: a position servo (kp), a velocity servo (kv) whose reference is capped at the joint's
    speed limit and the acceleration feed-forward (mjcf_numbers.feed_forward_actuator); the cup's adhesion actuator (ctrl 0 = vented .. 1 = full vacuum)."""
    actuators = []
    for i, name in enumerate(arm.joint_names):
        v = arm.velocity_limit_rad_s[i]
        actuators.append(
            f'<position name="{name}_pos" joint="{name}" kp="{servo.kp[i]}" ctrlrange="{arm.lower_rad[i]:.9g} {arm.upper_rad[i]:.9g}"/>'
            f'<velocity name="{name}_vel" joint="{name}" kv="{servo.kv[i]}" ctrlrange="{-v:.9g} {v:.9g}"/>'
            f'{feed_forward_actuator(name, servo.force_limit_nm[i])}'
        )
    actuators.append(
        f'<adhesion name="{SUCTION_ACTUATOR}" body="{CUP_BODY}" ctrlrange="0 1" gain="{sim.suction.adhesion_force_n}"/>'
    )
    return "".join(actuators)
