"""The arm as a URDF for the browser's 3-D panel (urdf-loader), generated from the arm's own config (one
fact, one place): joint origins and axes from config/arms/<name>.yaml (`urdf_origins` with the PoX screw axes'
directions, else the DH table, body frames as the simulation builds them: armlab.devices.sim.mjcf_dh), its base
pose on the board (the station model's T_world_base), the tool point, the fingers or the suction cup; and the
vendor's meshes on the links from config/arm_meshes/<name>.yaml when there is one (else the links are drawn
as cylinders between the joints, as the simulation's shapes).

Robot root: link "world" (the board frame); the tool point: link "tool_point" (x = approach axis); the
fingers (an arm with a `gripper:`): prismatic joints "left_finger" / "right_finger" whose value is each
finger's offset from the centre line (metres, the arm file's finger_offset range)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from armlab.config import config_dir, read_config_file
from armlab.devices.arm_body import body_of_config
from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.rotations import matrix_from_rpy, rpy_from_matrix

TOOL_LINK = "tool_point"
FINGER_JOINTS = ("left_finger", "right_finger")
LINK_RADIUS_M = 0.005  # the lines drawn for links the arm's body gives no shape, without meshes


def transform(xyz=(0.0, 0.0, 0.0), R=None) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = xyz
    if R is not None:
        T[:3, :3] = R
    return T


def _origin(T: np.ndarray) -> str:
    xyz = " ".join(f"{v:.9g}" for v in T[:3, 3])
    rpy = " ".join(f"{v:.9g}" for v in rpy_from_matrix(T[:3, :3]))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


@dataclass(frozen=True)
class MeshSet:
    """config/arm_meshes/<arm>.yaml: the vendor's meshes per link."""

    url: str
    scale: float
    color: tuple[float, float, float]
    visuals: list[dict]
    source: str
    licence: str
    link_frames: str = "config"  # "dh_after_d": the vendor's link frames sit d_i along the joint axis
    fingers_origin_m: tuple[float, float, float] | None = None

    @classmethod
    def load(cls, arm_name: str, folder: Path | None = None) -> MeshSet | None:
        """config/arm_meshes/<arm_name>.yaml, None when the arm has none."""
        path = (folder or config_dir() / "arm_meshes") / f"{arm_name}.yaml"
        if not path.exists():
            return None
        data = read_config_file(path)
        return cls(url=data["url"], scale=float(data.get("scale", 1.0)), color=tuple(data.get("color", (0.6, 0.6, 0.6))),
                   visuals=list(data["visuals"]), source=data["source"], licence=data["licence"],
                   link_frames=data.get("link_frames", "config"),
                   fingers_origin_m=tuple(data["fingers_origin_m"]) if "fingers_origin_m" in data else None)


@dataclass
class _Chain:
    """Links (name -> visuals xml) and joints (xml) being assembled."""

    links: dict[str, list[str]] = field(default_factory=dict)
    joints: list[str] = field(default_factory=list)

    def link(self, name: str) -> None:
        self.links.setdefault(name, [])

    def joint(self, name: str, kind: str, parent: str, child: str, T: np.ndarray, axis=None, limits=None) -> None:
        self.link(child)
        extra = f'<axis xyz="{" ".join(f"{v:.9g}" for v in axis)}"/>' if axis is not None else ""
        if limits is not None:
            extra += f'<limit lower="{limits[0]:.9g}" upper="{limits[1]:.9g}" effort="1" velocity="1"/>'
        self.joints.append(f'<joint name={quoteattr(name)} type="{kind}"><parent link={quoteattr(parent)}/>'
                           f'<child link={quoteattr(child)}/>{_origin(T)}{extra}</joint>')

    def collision(self, link: str, name: str, T: np.ndarray, geometry: str) -> None:
        self.links[link].append(f'<collision name={quoteattr(name)}>{_origin(T)}<geometry>{geometry}</geometry></collision>')

    def visual(self, link: str, T: np.ndarray, geometry: str, material: str) -> None:
        self.links[link].append(f'<visual>{_origin(T)}<geometry>{geometry}</geometry>'
                                f'<material name="{material}"/></visual>')

    def xml(self, name: str, materials: str) -> str:
        links = "".join(f'<link name={quoteattr(n)}>{"".join(v)}</link>' for n, v in self.links.items())
        return f'<?xml version="1.0"?><robot name={quoteattr(name)}>{materials}{links}{"".join(self.joints)}</robot>'


def _cylinder(chain: _Chain, link: str, start, end, radius: float, material: str) -> None:
    """A cylinder from `start` to `end` (link frame), the simulation's shape for a link without a mesh."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(end - start))
    if length < 1e-6:
        return
    z = (end - start) / length
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    chain.visual(link, transform(0.5 * (start + end), R), f'<cylinder radius="{radius:.9g}" length="{length:.9g}"/>', material)


def part_links(config: ArmConfig) -> dict[str, list[str]]:
    """The URDF links (arm_urdf's names) of every part a refused motion can name (UnsafeTrajectory.part): a joint
    (at its limit, too fast) its moving link; a joint's origin (the link around it in the board check) the links
    that meet there; the gripper's parts the fingers (or the suction cup's tool link) and the link carrying them."""
    names = list(config.joint_names)
    carrier = f"{names[-1]}_link"
    tool = [f"{joint}_link" for joint in FINGER_JOINTS] if config.gripper is not None else [TOOL_LINK]
    links = {name: [f"{name}_link"] for name in names}
    for i, name in enumerate(names):
        links[f"{name} origin"] = [f"{names[i - 1]}_link" if i else "base", f"{name}_link"]
    links |= {"gripper point": [carrier, *tool], "finger tips": tool, "fingers": tool, "held block": tool, "palm": [carrier]}
    return links


def arm_urdf(config: ArmConfig, T_world_base: np.ndarray, meshes: MeshSet | None) -> str:
    """The arm's URDF (see the module doc). Link names: world, base, <joint>_link per joint, tool_point."""
    chain = _Chain()
    chain.link("world")
    chain.joint("base_mount", "fixed", "world", "base", np.asarray(T_world_base, float))
    lower, upper = np.radians(config.limits.lower_deg), np.radians(config.limits.upper_deg)
    names = list(config.joint_names)
    link_T = {}  # joint name -> (parent link, T parent->link at q = 0, axis, vendor frame in the link frame)
    if config.urdf_origins is not None:
        parent = "base"
        for i, name in enumerate(names):
            axis = np.asarray(config.pox.screw_axes[i][:3], float)
            link_T[name] = (parent, transform(config.urdf_origins[name]), axis, np.eye(4))
            parent = f"{name}_link"
        tool_T = transform(config.urdf_origins["gripper_point"])
    else:
        rows = np.asarray(config.dh.rows, float)
        parent = "base"
        for i, name in enumerate(names):
            offset, d, _a, _alpha, sign = rows[i]
            if i == 0:
                T = transform(R=matrix_from_rpy((0.0, 0.0, offset)))
            else:
                _o, pd, pa, palpha, _s = rows[i - 1]
                T = transform((pa, 0.0, pd), matrix_from_rpy((palpha, 0.0, 0.0)) @ matrix_from_rpy((0.0, 0.0, offset)))
            vendor = transform((0.0, 0.0, d)) if meshes is not None and meshes.link_frames == "dh_after_d" else np.eye(4)
            link_T[name] = (parent, T, np.array([0.0, 0.0, sign]), vendor)
            parent = f"{name}_link"
        _o, d, a, alpha, _s = rows[-1]
        tool_T = transform((a, 0.0, d), matrix_from_rpy((alpha, 0.0, 0.0))) @ np.asarray(config.dh.tool, float)
    for i, name in enumerate(names):
        parent, T, axis, _vendor = link_T[name]
        chain.joint(name, "revolute", parent, f"{name}_link", T, axis=axis, limits=(lower[i], upper[i]))
    last = f"{names[-1]}_link"
    chain.joint("tool_point", "fixed", last, TOOL_LINK, tool_T)
    frames = {"base": ("base", np.eye(4))} | {name: (f"{name}_link", link_T[name][3]) for name in names}
    fingers = config.gripper is not None and meshes is not None and meshes.fingers_origin_m is not None
    if config.gripper is not None:
        # The fingers slide along the tool frame's +-y by the finger offset; with the vendor's meshes their frame is
        # the vendor's fingers link, else the tool point.
        origin = transform(meshes.fingers_origin_m) if fingers else tool_T
        g = config.gripper
        for joint, sign in zip(FINGER_JOINTS, (1.0, -1.0)):
            chain.joint(joint, "prismatic", last, f"{joint}_link", origin, axis=(0.0, sign, 0.0),
                        limits=(g.finger_offset_min_m, g.finger_offset_max_m))
            frames[joint] = (f"{joint}_link", np.eye(4))
    finger_from_tool = np.linalg.inv(origin) @ tool_T if config.gripper is not None else np.eye(4)
    drawn = _body(chain, config, names, meshes is None, finger_from_tool)
    if meshes is not None:
        scale = f"{meshes.scale:g} {meshes.scale:g} {meshes.scale:g}"
        for visual in meshes.visuals:
            link, vendor = frames[visual["link"]]
            T = vendor @ transform(visual.get("xyz", (0.0, 0.0, 0.0)), matrix_from_rpy(visual.get("rpy", (0.0, 0.0, 0.0))))
            chain.visual(link, T, f'<mesh filename={quoteattr(meshes.url + visual["file"])} scale="{scale}"/>', "arm")
    else:
        _skeleton(chain, names, link_T, tool_T, config, drawn)
    if config.suction_cup is not None:
        cup = config.suction_cup
        _cylinder(chain, TOOL_LINK, (-0.004, 0, 0), (0, 0, 0), cup.lip_radius_m + 0.002, "tool")  # the lip
    color = meshes.color if meshes is not None else (0.15, 0.15, 0.17)
    materials = (f'<material name="arm"><color rgba="{color[0]:g} {color[1]:g} {color[2]:g} 1"/></material>'
                 '<material name="tool"><color rgba="0.25 0.25 0.27 1"/></material>')
    return chain.xml(config.name, materials)


def _body(chain: _Chain, config: ArmConfig, names: list[str], visuals: bool, finger_from_tool: np.ndarray) -> set[str]:
    """The arm's body (armlab.devices.arm_body, the shapes the simulation and the planning checks use) as each
    link's collision shapes, and as its visuals when there are no meshes (a capsule: a cylinder and two spheres;
    a finger's parts on its finger link, open fingers at the full offset; finger_from_tool: the tool point's frame in a
    finger link's at zero offset). The links that got a shape."""
    body = body_of_config(config)
    frames = ["base", *[f"{name}_link" for name in names], TOOL_LINK]
    fmax = body.finger_offset_max_m
    drawn = set()
    for part in body.parts:
        link, T = frames[part.frame], part.T_frame_part
        if part.finger:
            link, T = f"{FINGER_JOINTS[0 if part.finger > 0 else 1]}_link", T.copy()
            T[1, 3] -= part.finger * fmax  # the finger link's frame moves with the finger offset
            T = finger_from_tool @ T
        chain.link(link)
        drawn.add(link)
        if part.shape == "box":
            shapes = [(T, f'<box size="{" ".join(f"{2 * v:.9g}" for v in part.size_m)}"/>')]
        else:
            radius, half = part.size_m[:2]
            shapes = [(T, f'<cylinder radius="{radius:.9g}" length="{2 * half:.9g}"/>')]
            if part.shape == "capsule":
                shapes += [(T @ transform((0.0, 0.0, end)), f'<sphere radius="{radius:.9g}"/>') for end in (-half, half)]
        for pose, geometry in shapes:
            chain.collision(link, part.name, pose, geometry)
            if visuals:
                chain.visual(link, pose, geometry, "tool" if part.frame == len(frames) - 1 else "arm")
    return drawn


def _skeleton(chain: _Chain, names: list[str], link_T: dict, tool_T: np.ndarray, config: ArmConfig, drawn: set[str]) -> None:
    """Thin cylinders from each joint to the next (and the last to the tool point) for the links the arm's body
    gives no shape (a link without a radius in the arm file): the arm without meshes."""
    if "base" not in drawn:
        _cylinder(chain, "base", (0, 0, 0), (0, 0, 0.04), 6 * LINK_RADIUS_M, "arm")
    for i, name in enumerate(names):
        nxt = link_T[names[i + 1]][1] if i + 1 < len(names) else tool_T
        link = f"{name}_link"
        if link in drawn:
            continue
        if config.dh is not None and config.urdf_origins is None:  # DH: d along z, then a along x
            _o, d, a, _alpha, _s = config.dh.rows[i]
            _cylinder(chain, link, (0, 0, 0), (0, 0, d), LINK_RADIUS_M, "arm")
            _cylinder(chain, link, (0, 0, d), (a, 0, d), LINK_RADIUS_M, "arm")
        else:
            _cylinder(chain, link, (0, 0, 0), nxt[:3, 3], LINK_RADIUS_M, "arm")
