"""The arm's body, one description for every user: the simulation builds its arm's shapes from it, the planning
checks (armlab.motion.clearance), the self-filter (armlab.vision.self_filter), the side grasp's outline
(armlab.skills.side_grasp) and the 3-D view's fallback shapes (armlab.station.arm_urdf) read it.

Each part is a MuJoCo-style primitive in one of the arm's frames: a capsule or cylinder along its own z (size:
radius, half length), a box (size: half extents). Frames (index into ArmBody.frames): 0 the base, 1 + i the link
joint i moves, and last the tool point (x = approach axis). Built from config/arms/<arm>.yaml (joint origins or the
DH table, link_radii_m, the gripper's finger range, the suction cup) and, for a finger gripper, config/sim.yaml's
`gripper:` sizes (armlab.devices.finger_gripper). Placed in the world from the arm model's joint frames
(ArmModel.joint_frames), so a calibrated model moves the body with it. Pure: no devices.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from armlab.config import read_config_file, resolve_config_path, validate_config
from armlab.devices.finger_gripper import FingerGripperConfig, FingerGripperOutline, load_finger_gripper_config
from armlab.errors import ConfigError
from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.dh import dh_transform
from armlab.kinematics.rotations import rotation_taking

# The base's housing and the waist's turntable of an arm with URDF joint origins (the RX200's), as the simulation
# draws them: they are not in the arm file, which describes the moving links.
BASE_BOX_HALF_M = (0.05, 0.05, 0.03)
BASE_BOX_CENTRE_M = (-0.01, 0.0, 0.03)
WAIST_HOUSING_RADIUS_M = 0.04
WAIST_HOUSING_HALF_M = 0.015
WAIST_HOUSING_Z_M = 0.017
FINGER_LINK_HALF_THICKNESS_M = 0.004  # a finger link's half thickness along the closing axis
DH_LINK_FRACTION = 0.8  # a DH arm's link capsules are this fraction of its joint housings' radius


@dataclass(frozen=True)
class Part:
    """One primitive of the arm's body. T_frame_part: its pose in frame `frame` (capsules and cylinders along its
    z); size_m: (radius, half length, 0) or box half extents. finger: +1 / -1 for a part on the left / right finger
    (it slides along the tool frame's y with the finger; T_frame_part is with the fingers fully open), else 0."""

    name: str
    shape: str  # "capsule", "cylinder" or "box"
    frame: int
    T_frame_part: np.ndarray
    size_m: tuple[float, float, float]
    finger: int = 0


@dataclass(frozen=True)
class PlacedBody:
    """The body's parts in the world for N joint vectors: poses (N, P, 4, 4), with the parts' shapes and sizes."""

    parts: tuple[Part, ...]
    poses: np.ndarray

    def indices(self, *shapes: str) -> list[int]:
        return [k for k, part in enumerate(self.parts) if part.shape in shapes]

    def segments(self, index: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """((N, C, 2, 3) world ends of the axes, (C,) radii) of the capsules or cylinders parts[index]."""
        half = np.array([self.parts[k].size_m[1] for k in index]).reshape(-1)
        poses = self.poses[:, index]
        axis = poses[..., :3, 2] * half[None, :, None]
        centre = poses[..., :3, 3]
        radii = np.array([self.parts[k].size_m[0] for k in index]).reshape(-1)
        return np.stack([centre - axis, centre + axis], axis=2), radii

    def boxes(self, index: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """((N, B, 4, 4) poses, (B, 3) half extents) of the boxes parts[index] (a cylinder: the box around it)."""
        half = [_half(self.parts[k]) for k in index]
        return self.poses[:, index], np.array(half, dtype=float).reshape(-1, 3)


@dataclass(frozen=True)
class ArmBody:
    """The parts of one arm's body (see the module doc) and how its frames follow from the joint frames."""

    arm: str
    parts: tuple[Part, ...]
    kind: str  # "urdf": frames from URDF joint origins (PoX), "dh": from the DH table
    link_inverse: np.ndarray  # (dof, 4, 4): per joint, the transform that takes the next joint frame back to its link's
    finger_offset_max_m: float = 0.0

    def link_frames(self, joint_frames: np.ndarray) -> np.ndarray:
        """(N, dof + 2, 4, 4): the base, each link and the tool point, from ArmModel.joint_frames (N, dof + 1, 4, 4)
        and the base pose in frame 0's place (joint_frames of a DH arm start at the base)."""
        frames = np.asarray(joint_frames, float)
        dof = frames.shape[1] - 1
        out = np.empty((frames.shape[0], dof + 2, 4, 4))
        out[:, -1] = frames[:, -1]
        if self.kind == "urdf":  # link i: at joint i's origin, turned as joint i + 1's frame (oriented as its parent)
            out[:, 1:-1] = frames[:, 1:] @ self.link_inverse
            out[:, 1:-1, :3, 3] = frames[:, :-1, :3, 3]
        else:  # DH: link i's frame is DH frame i turned by theta_i, the next frame times the inverse of d, a, alpha
            nxt = np.concatenate([frames[:, 1:-1], frames[:, -1:]], axis=1)
            out[:, 1:-1] = nxt @ self.link_inverse
        return out

    def tool_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(T_tool_box (4, 4), half extents (3,)): the box around the tool's parts (open fingers, palm, cup) in the
        tool frame, axis-aligned there; zero extents at the tool point for an arm without a tool."""
        corners = [part.T_frame_part[:3, :3] @ (np.array(c) * _half(part)) + part.T_frame_part[:3, 3]
                   for part in self.parts if part.frame == self.tool_frame
                   for c in np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T]
        low, high = (np.min(corners, axis=0), np.max(corners, axis=0)) if corners else (np.zeros(3), np.zeros(3))
        T = np.eye(4)
        T[:3, 3] = 0.5 * (low + high)
        return T, 0.5 * (high - low)

    @property
    def tool_frame(self) -> int:
        return len(self.link_inverse) + 1

    def finger_outline(self) -> FingerGripperOutline:
        """The palm and open fingers around the finger plane, relative to the gripper point (side grasps' planning
        and the palm's board check); ConfigError for an arm without a finger gripper."""
        parts = {part.name: part for part in self.parts}
        palm, finger = parts.get("palm"), parts.get("left_finger_link")
        if palm is None or finger is None:
            raise ConfigError(f"config/arms/{self.arm}.yaml: a finger gripper outline needs a gripper (and the "
                              "simulation's finger sizes)")
        palm_x, finger_x = palm.T_frame_part[0, 3], finger.T_frame_part[0, 3]
        return FingerGripperOutline(
            palm_half_height_m=palm.size_m[2],
            palm_front_behind_m=-(palm_x + palm.size_m[0]),
            palm_back_behind_m=-(palm_x - palm.size_m[0]),
            finger_half_height_m=finger.size_m[2],
            finger_tip_beyond_m=finger_x + finger.size_m[0],
            open_outer_m=palm.size_m[1],
        )

    def place(self, model, positions_rad, finger_offset_m: float | None = None,
              held_edge_m: float | None = None) -> PlacedBody:
        """The body at joint vectors (N, dof) (or one (dof,)) of `model` (an ArmModel), the fingers at
        finger_offset_m from the centre line (None: open), with a held block of held_edge_m (None: none)."""
        q = np.atleast_2d(np.asarray(positions_rad, float))
        frames = self.link_frames(np.asarray(model.joint_frames(q), float).reshape(len(q), -1, 4, 4))
        frames[:, 0] = np.asarray(model.T_world_base, float)
        parts = self.parts + ((held_block(held_edge_m, frames.shape[1] - 1),) if held_edge_m else ())
        local = np.array([part.T_frame_part for part in parts])
        if finger_offset_m is not None:
            shift = float(finger_offset_m) - self.finger_offset_max_m
            local = local.copy()
            local[:, 1, 3] += np.array([part.finger for part in parts]) * shift
        poses = frames[:, [part.frame for part in parts]] @ local[None]
        return PlacedBody(parts, poses)


def _half(part: Part) -> tuple[float, float, float]:
    """A box part's half extents, or those of the box around a capsule or cylinder (along its z)."""
    if part.shape == "box":
        return part.size_m
    radius, half_length = part.size_m[:2]
    return radius, radius, half_length + (radius if part.shape == "capsule" else 0.0)


def held_block(edge_m: float, tool_frame: int) -> Part:
    """A held block of edge edge_m as the checks count it: across the fingers a block wide, along the approach from
    half an edge behind the gripper point (how deep a grasp may take it) to a full edge beyond it."""
    T = np.eye(4)
    T[0, 3] = 0.25 * edge_m
    return Part("held block", "box", tool_frame, T, (0.75 * edge_m, 0.5 * edge_m, 0.5 * edge_m))


def _pose(position=(0.0, 0.0, 0.0), z_axis=None) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = position
    if z_axis is not None:
        T[:3, :3] = rotation_taking((0.0, 0.0, 1.0), z_axis)
    return T


def _along(name: str, shape: str, frame: int, start, end, radius_m: float) -> Part | None:
    """A capsule or cylinder from `start` to `end` (frame coordinates), None when they coincide."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(end - start))
    if length < 1e-9:
        return None
    return Part(name, shape, frame, _pose(0.5 * (start + end), end - start), (radius_m, 0.5 * length, 0.0))


def _finger_parts(config: ArmConfig, g: FingerGripperConfig, tool: int) -> list[Part]:
    """Palm, finger links and pads in the tool frame (the fingers open), the sizes the simulation builds."""
    gp = float(config.urdf_origins["gripper_point"][0]) if config.urdf_origins is not None else 0.0
    fmax, pad_t = config.gripper.finger_offset_max_m, config.gripper.pad_thickness_m
    tip = g.tip_beyond_gripper_point_m
    finger_start = g.palm_depth_m - gp  # the palm's front face, in the tool frame
    finger_len = tip - finger_start
    parts = [Part("palm", "box", tool, _pose((finger_start - 0.5 * g.palm_depth_m, 0.0, 0.0)),
                  (0.5 * g.palm_depth_m, fmax + g.palm_side_margin_m, g.palm_half_height_m))]
    for side, sign in (("left", 1), ("right", -1)):
        parts.append(Part(f"{side}_finger_link", "box", tool,
                          _pose((finger_start + 0.5 * finger_len, sign * (fmax + FINGER_LINK_HALF_THICKNESS_M), 0.0)),
                          (0.5 * finger_len, FINGER_LINK_HALF_THICKNESS_M, 0.5 * g.pad_width_m + g.finger_link_margin_m), sign))
        parts.append(Part(f"{side}_pad", "box", tool, _pose((tip - 0.5 * g.pad_length_m, sign * (fmax - 0.5 * pad_t), 0.0)),
                          (0.5 * g.pad_length_m, 0.5 * pad_t, 0.5 * g.pad_width_m), sign))
    return parts


def _urdf_body(config: ArmConfig, g: FingerGripperConfig | None) -> ArmBody:
    names = list(config.joint_names)
    origins = [np.asarray(config.urdf_origins[key], float) for key in [*names, "gripper_point"]]
    radii = config.link_radii_m or [0.0] * len(names)
    tool = len(names) + 1
    parts = [Part("base_link", "box", 0, _pose(BASE_BOX_CENTRE_M), BASE_BOX_HALF_M),
             Part("waist_geom", "cylinder", 1, _pose((0.0, 0.0, WAIST_HOUSING_Z_M)),
                  (WAIST_HOUSING_RADIUS_M, WAIST_HOUSING_HALF_M, 0.0))]
    for i, name in enumerate(names):
        if radii[i] > 0.0:  # joint i's link: from its origin to the next joint's (the gripper point's)
            part = _along(f"{name}_capsule", "capsule", 1 + i, (0.0, 0.0, 0.0), origins[i + 1], radii[i])
            parts += [part] if part is not None else []
    if config.gripper is not None and g is not None:
        parts += _finger_parts(config, g, tool)
    inverse = np.broadcast_to(np.eye(4), (len(names), 4, 4)).copy()
    inverse[-1, :3, :3] = np.asarray(config.pox.M, float)[:3, :3].T  # the gripper point's frame turned back to the link's
    return ArmBody(config.name, tuple(parts), "urdf", inverse,
                   config.gripper.finger_offset_max_m if config.gripper is not None else 0.0)


def _dh_body(config: ArmConfig, g: FingerGripperConfig | None) -> ArmBody:
    rows = np.asarray(config.dh.rows, float)
    tool_T = np.asarray(config.dh.tool, float)
    radii = config.link_radii_m or [0.0] * len(rows)
    tool = len(rows) + 1
    parts = []
    for i, (_offset, d, a, _alpha, _sign) in enumerate(rows):
        name, r = config.joint_names[i], radii[i]
        if r <= 0.0:
            continue
        housing_z = 2.1 * r if i == 0 else 0.0  # the first joint's housing sits on the base's
        parts.append(Part(f"{name}_housing", "cylinder", 1 + i, _pose((0.0, 0.0, housing_z)), (r, r, 0.0)))
        start = np.copysign(housing_z, d) if i == 0 else 0.0
        for suffix, p0, p1 in (("d", (0, 0, start), (0, 0, d)), ("a", (0, 0, d), (a, 0, d))):
            part = _along(f"{name}_{suffix}", "capsule", 1 + i, p0, p1, DH_LINK_FRACTION * r)
            parts += [part] if part is not None else []
    if radii[0] > 0.0:
        base = 1.1 * radii[0]
        parts.insert(0, Part("base_link", "cylinder", 0, _pose((0.0, 0.0, 0.5 * base)), (base, 0.5 * base, 0.0)))
    if config.suction_cup is not None:
        cup = config.suction_cup
        parts.append(_along("cup_body", "cylinder", tool, (-cup.body_length_m, 0, 0), (0, 0, 0), cup.body_radius_m))
    elif config.gripper is not None and g is not None:
        parts += _finger_parts(config, g, tool)
    inverse = np.empty((len(rows), 4, 4))
    for i, (_offset, d, a, alpha, _sign) in enumerate(rows):
        after = dh_transform(0.0, d, a, alpha)  # link i's frame -> DH frame i + 1
        if i == len(rows) - 1:
            after = after @ tool_T  # the last joint frame given is the tool point's
        inverse[i] = np.linalg.inv(after)
    return ArmBody(config.name, tuple(parts), "dh", inverse,
                   config.gripper.finger_offset_max_m if config.gripper is not None else 0.0)


def arm_body(config: ArmConfig, gripper: FingerGripperConfig | None = None) -> ArmBody:
    """The body of the arm `config` describes; `gripper`: the finger gripper's sizes (for an arm with a gripper)."""
    return _urdf_body(config, gripper) if config.urdf_origins is not None else _dh_body(config, gripper)


@lru_cache(maxsize=8)
def load_arm_body(arm: str, sim: str = "sim") -> ArmBody:
    """The body of config/arms/<arm>.yaml with config/<sim>.yaml's finger gripper sizes."""
    path = resolve_config_path(arm, "arms")
    config = validate_config(read_config_file(path), ArmConfig, str(path))
    return arm_body(config, load_finger_gripper_config(sim) if config.gripper is not None else None)


def load_finger_gripper_outline(arm: str, sim: str = "sim") -> FingerGripperOutline:
    """The outline of `arm`'s finger gripper, from its body (config/arms/<arm>.yaml, config/<sim>.yaml gripper)."""
    return load_arm_body(arm, sim).finger_outline()


def body_of(model) -> ArmBody:
    """The body of an arm model (ArmModel or CalibratedArm): body_of_config of its config."""
    return body_of_config(model.config)


_BODIES: dict[int, tuple[ArmConfig, ArmBody]] = {}


DEFAULT_DH_LINK_RADIUS_M = 0.03  # a DH arm's link capsule when neither its arm file nor config/sim.yaml gives one


def dh_link_radii_m(config: ArmConfig, simulated_m=None) -> list[float]:
    """A DH arm's link radii, the one rule the simulation (mjcf_dh) and body_of share: the arm file's link_radii_m,
    else the simulation's (`simulated_m`: config/sim.yaml's arms.<name>.link_radius_m), else DEFAULT_DH_LINK_RADIUS_M."""
    if config.link_radii_m is not None:
        return list(config.link_radii_m)
    return [float(r) for r in simulated_m] if simulated_m else [DEFAULT_DH_LINK_RADIUS_M] * len(config.joint_names)


def simulated_link_radii_m(config: ArmConfig, sim: str = "sim") -> list[float]:
    """dh_link_radii_m with config/<sim>.yaml's arms.<name>.link_radius_m: the radii the simulation builds with."""
    section = read_config_file(resolve_config_path(sim, ".")).get("arms") or {}
    radii = (section.get(config.name) or {}).get("link_radius_m") if isinstance(section, dict) else None
    return dh_link_radii_m(config, radii)


def body_of_config(config: ArmConfig) -> ArmBody:
    """The body of an arm config with config/sim.yaml's gripper sizes (and a DH arm's simulated link radii)."""
    cached = _BODIES.get(id(config))
    if cached is None or cached[0] is not config:
        shaped = config if config.urdf_origins is not None else config.model_copy(update={"link_radii_m": simulated_link_radii_m(config)})
        cached = (config, arm_body(shaped, load_finger_gripper_config() if config.gripper is not None else None))
        _BODIES[id(config)] = cached
    return cached[1]
