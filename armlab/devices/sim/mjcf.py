"""Build the MuJoCo model of the workcell (MJCF text + in-memory texture assets) from config and a
Scene: the RX200 from its URDF joint origins, a two-finger gripper with pads (or a DH-described arm
with a suction cup: armlab.devices.sim.mjcf_dh), the board and its tags
(from the workcell config), the overhead camera, the scene's objects as free bodies and the feeder's
blocks parked out of sight. Pure: same inputs, same XML."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.config import read_config_file, resolve_config_path, validate_config
from armlab.devices.arm_body import arm_body
from armlab.devices.sim import textures
from armlab.devices.sim.arm_realism import GEAR_ARMATURE, GEAR_SUFFIX, RealArm
from armlab.devices.sim.checkerboard import BODY_NAME as CHECKERBOARD
from armlab.devices.sim.checkerboard import checkerboard_texture, checkerboard_xml, load_checkerboard_target
from armlab.devices.sim.clutter import realism_world_xml
from armlab.devices.sim.config import SceneRealismConfig, SimCameraConfig, SimConfig
from armlab.devices.sim.feeder import FEEDER_PROBE, parked_objects
from armlab.devices.sim.mjcf_dh import DhArmGeometry
from armlab.devices.sim.mjcf_numbers import feed_forward_actuator
from armlab.devices.sim.mjcf_numbers import fmt_numbers as _fmt
from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.rotations import quat_wxyz_from_matrix
from armlab.scene import Scene, SceneObject
from armlab.workcell import Workcell, load_workcell

CAMERA_NAME = "overhead"
GRIPPER_SITE = "gripper_point"
OBJECT_PREFIX = "obj:"
GRIPPER_MARKER = "gripper_marker"
STICKER_FRACTION = 0.9  # the ArUco sticker covers this fraction of a block's top face

COLOR_RGBA = {
    "red": (0.80, 0.08, 0.08, 1.0),
    "orange": (0.95, 0.45, 0.05, 1.0),
    "yellow": (0.92, 0.82, 0.08, 1.0),
    "green": (0.08, 0.60, 0.20, 1.0),
    "blue": (0.08, 0.22, 0.80, 1.0),
    "violet": (0.45, 0.18, 0.65, 1.0),
}


@dataclass(frozen=True)
class ArmGeometry:
    """The parts of config/arms/<name>.yaml the model needs (SI units, radians)."""

    joint_names: tuple[str, ...]
    origins_m: dict[str, tuple[float, float, float]]
    lower_rad: np.ndarray
    upper_rad: np.ndarray
    finger_offset_min_m: float
    finger_offset_max_m: float
    pad_thickness_m: float
    grasp_effort_n: float
    T_world_base: np.ndarray
    sleep_rad: np.ndarray
    link_radii_m: tuple[float, ...] = ()  # the arm config's link_radii_m (the links' capsules)
    real: RealArm | None = None  # the real arm (armlab.devices.sim.arm_realism; origins and base already the rig's)
    config: ArmConfig | None = None  # the validated arm file (its shapes: armlab.devices.arm_body, with origins_m)

    @classmethod
    def load(cls, name: str = "rx200") -> ArmGeometry:
        path = resolve_config_path(name, "arms")
        data = read_config_file(path)
        gripper = data["gripper"]
        return cls(
            joint_names=tuple(data["joint_names"]),
            origins_m={key: tuple(float(v) for v in value) for key, value in data["urdf_origins"].items()},
            lower_rad=np.radians(np.asarray(data["limits"]["lower_deg"], dtype=float)),
            upper_rad=np.radians(np.asarray(data["limits"]["upper_deg"], dtype=float)),
            finger_offset_min_m=float(gripper["finger_offset_min_m"]),
            finger_offset_max_m=float(gripper["finger_offset_max_m"]),
            pad_thickness_m=float(gripper["pad_thickness_m"]),
            grasp_effort_n=float(gripper["grasp_effort_n"]),
            T_world_base=np.asarray(data["T_world_base"], dtype=float),
            sleep_rad=np.asarray(data["poses"]["sleep_rad"], dtype=float),
            link_radii_m=tuple(float(v) for v in data.get("link_radii_m") or ()),
            config=validate_config(data, ArmConfig, str(path)),
        )


    def mjcf(self, sim: SimConfig, gripper_extras: str = "") -> tuple[str, str]:
        """(worldbody xml of the arm with its fingers, actuator xml); gripper_extras: geoms added to the
        gripper link (its frame: origin at the wrist_rotate joint, x = approach axis)."""
        return _arm_xml(self, sim, gripper_extras), _finger_arm_actuators(self, sim)

    def tendon_xml(self) -> str:
        """The real arm's gear springs (`<tendon>` content), empty for the ideal arm."""
        return _gear_tendons(self)


def _arm_xml(arm: ArmGeometry, sim: SimConfig, gripper_extras: str = "") -> str:
    """The arm's kinematic tree. Joint axes: waist z; shoulder, elbow, wrist_angle +y (positive pitches the
    arm forward and down); wrist_rotate +x. Fingers slide along the gripper's +-y axis."""
    o = arm.origins_m
    radii = arm.link_radii_m
    if len(radii) != len(arm.joint_names):
        raise ValueError(f"the arm config's link_radii_m (one per joint) is needed to build the simulated links, got {radii}")
    servo = sim.arm
    g = sim.gripper
    base_quat = quat_wxyz_from_matrix(arm.T_world_base[:3, :3])
    lo, hi = arm.lower_rad, arm.upper_rad
    names = arm.joint_names
    m = servo.link_masses_kg

    real = arm.real
    gravcomp = 1 if real is None else 0  # the ideal servos compensate gravity; the real firmware does not

    def joint(i: int, axis: str) -> str:
        if real is None:
            return (
                f'<joint name="{names[i]}" axis="{axis}" range="{lo[i]:.9g} {hi[i]:.9g}" armature="{servo.armature[i]}" '
                f'damping="{servo.damping[i]}" actuatorfrcrange="{-servo.force_limit_nm[i]} {servo.force_limit_nm[i]}"/>'
            )
        # The motor (its reading; the link stands at reading + the rig's zero offset: ref), then the gear behind it.
        return (
            f'<joint name="{names[i]}" axis="{axis}" range="{lo[i]:.9g} {hi[i]:.9g}" armature="{servo.armature[i]}" '
            f'damping="{servo.damping[i]}" ref="{-real.rig.joint_offset_rad[i]:.9g}"/>'
            f'<joint name="{names[i]}{GEAR_SUFFIX}" axis="{axis}" armature="{GEAR_ARMATURE}"/>'
        )

    # The shapes come from the arm's body (armlab.devices.arm_body): the same parts the planning checks, the
    # self-filter and the 3-D view read. Tool-frame parts go on the gripper link (origin at the wrist_rotate joint).
    body = arm_body(arm.config.model_copy(update={"urdf_origins": {k: list(v) for k, v in o.items()},
                                                  "link_radii_m": list(radii)}), g)
    T_link_tool = np.eye(4)
    T_link_tool[:3, :3] = np.asarray(arm.config.pox.M, float)[:3, :3]
    T_link_tool[:3, 3] = o["gripper_point"]
    gp = o["gripper_point"][0]
    fmax = arm.finger_offset_max_m
    fmin = arm.finger_offset_min_m
    tool = len(names) + 1
    arm_geom = 'contype="2" conaffinity="1" group="1"'

    def geoms(frame: int, finger: int = 0) -> str:
        """The body's parts on frame `frame` (the tool's on the gripper link; a finger's relative to its body)."""
        out = []
        for part in body.parts:
            if part.frame != frame or part.finger != finger:
                continue
            T = part.T_frame_part
            if frame == tool:
                T = T_link_tool @ T
                T[1, 3] -= finger * fmax  # a finger's body sits at its open offset
            size = part.size_m if part.shape == "box" else part.size_m[:2]
            pad = part.name.endswith("_pad")
            material = "pad" if pad else "arm" if part.shape == "capsule" else "arm_dark"
            extra = (f' condim="4" friction="{_fmt(g.pad_friction)}" solref="{_fmt(g.pad_solref)}" '
                     f'solimp="{_fmt(g.pad_solimp)}" solmix="1000"') if pad else ""
            out.append(f'<geom name="{part.name}" type="{part.shape}" size="{_fmt(size)}" pos="{_fmt(T[:3, 3])}" '
                       f'quat="{_fmt(quat_wxyz_from_matrix(T[:3, :3]))}" material="{material}"{extra} {arm_geom}/>')
        return "".join(out)

    finger_start = g.palm_depth_m
    finger_len = gp + g.tip_beyond_gripper_point_m - finger_start

    def finger(side: str, sign: int) -> str:
        return f"""
                <body name="{side}_finger" pos="0 {sign * fmax:.9g} 0" gravcomp="{gravcomp}">
                  <inertial pos="{finger_start + 0.5 * finger_len:.9g} {sign * 0.004:.9g} 0" mass="{g.finger_mass_kg}" diaginertia="4e-6 4e-6 1e-6"/>
                  <joint name="{side}_finger" type="slide" axis="0 {sign:g} 0" range="{fmin} {fmax}" ref="{fmax}"
                         armature="{g.armature_kg}" damping="{g.damping_n_s_m}"/>
                  {geoms(tool, sign)}
                </body>"""

    return f"""
    <body name="base" pos="{_fmt(arm.T_world_base[:3, 3])}" quat="{_fmt(base_quat)}">
      {geoms(0)}
      <body name="waist_link" pos="{_fmt(o['waist'])}" gravcomp="{gravcomp}">
        <inertial pos="0 0 0.02" mass="{m[0]}" diaginertia="3e-4 3e-4 3e-4"/>
        {joint(0, "0 0 1")}
        {geoms(1)}
        <body name="shoulder_link" pos="{_fmt(o['shoulder'])}" gravcomp="{gravcomp}">
          <inertial pos="0.025 0 0.1" mass="{m[1]}" diaginertia="1e-3 1e-3 1e-4"/>
          {joint(1, "0 1 0")}
          {geoms(2)}
          <body name="forearm_link" pos="{_fmt(o['elbow'])}" gravcomp="{gravcomp}">
            <inertial pos="0.1 0 0" mass="{m[2]}" diaginertia="1e-4 6e-4 6e-4"/>
            {joint(2, "0 1 0")}
            {geoms(3)}
            <body name="wrist_link" pos="{_fmt(o['wrist_angle'])}" gravcomp="{gravcomp}">
              <inertial pos="0.03 0 0" mass="{m[3]}" diaginertia="5e-5 5e-5 5e-5"/>
              {joint(3, "0 1 0")}
              {geoms(4)}
              <body name="gripper_link" pos="{_fmt(o['wrist_rotate'])}" gravcomp="{gravcomp}">
                <inertial pos="0.03 0 0" mass="{m[4]}" diaginertia="1e-4 1e-4 1e-4"/>
                {joint(4, "1 0 0")}
                {geoms(5)}{geoms(tool)}
                <site name="{GRIPPER_SITE}" pos="{gp:.9g} 0 0" size="0.003" rgba="1 0 1 0.5" group="4"/>
                {gripper_extras}
                {finger("left", 1)}
                {finger("right", -1)}
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>"""


def _gear_tendons(arm: ArmGeometry) -> str:
    """The real arm's gears: per joint a spring on its passive gear joint, slack within +-backlash/2 (a
    tendon's dead band), of the joint's gear stiffness beyond; and the link's bearing friction against the frame
    (a tendon on motor + gear: the link's angle). Nothing for the ideal arm."""
    real = arm.real
    if real is None:
        return ""
    half = 0.5 * real.backlash_rad
    return "".join(
        f'<fixed name="{name}{GEAR_SUFFIX}" stiffness="{real.gear_stiffness_nm_rad[i]:.9g}" '
        f'damping="{real.gear_damping_nm_s_rad[i]:.9g}" springlength="{-half:.9g} {half:.9g}">'
        f'<joint joint="{name}{GEAR_SUFFIX}" coef="1"/></fixed>'
        f'<fixed name="{name}_link" frictionloss="{real.link_friction_nm:.9g}">'
        f'<joint joint="{name}" coef="1"/><joint joint="{name}{GEAR_SUFFIX}" coef="1"/></fixed>'
        for i, name in enumerate(arm.joint_names))


def _finger_arm_actuators(arm: ArmGeometry, sim: SimConfig) -> str:
    """Position + velocity servo per joint (the ideal arm's with its acceleration feed-forward, mjcf_numbers.feed_forward_actuator), a position servo
    per finger capped at the grasp effort. The real arm's: the firmware's P gain with its PWM (torque) saturating at
    the stall torque, and the motor's back-EMF damping (the velocity actuator, fed no velocity: the firmware's
    feed-forward gains are 0)."""
    actuators = []
    real = arm.real
    for i, name in enumerate(arm.joint_names):
        if real is None:
            actuators.append(
                f'<position name="{name}_pos" joint="{name}" kp="{sim.arm.kp[i]}" '
                f'ctrlrange="{arm.lower_rad[i]:.9g} {arm.upper_rad[i]:.9g}"/>'
            )
            actuators.append(f'<velocity name="{name}_vel" joint="{name}" kv="{sim.arm.kv[i]}" ctrlrange="-10 10"/>')
            actuators.append(feed_forward_actuator(name, sim.arm.force_limit_nm[i]))
            continue
        stall = real.stall_torque_nm[i]
        actuators.append(
            f'<position name="{name}_pos" joint="{name}" kp="{real.kp_nm_rad[i]:.9g}" '
            f'ctrlrange="{arm.lower_rad[i]:.9g} {arm.upper_rad[i]:.9g}" forcerange="{-stall:.9g} {stall:.9g}"/>'
        )
        actuators.append(f'<velocity name="{name}_vel" joint="{name}" kv="{real.kv_nm_s_rad[i]:.9g}" ctrlrange="-10 10"/>')
    for side in ("left", "right"):
        actuators.append(
            f'<position name="{side}_finger" joint="{side}_finger" kp="{sim.gripper.kp_n_m}" '
            f'ctrlrange="{arm.finger_offset_min_m} {arm.finger_offset_max_m + sim.gripper.open_preload_m:.9g}" '
            f'forcerange="{-arm.grasp_effort_n} {arm.grasp_effort_n}"/>'
        )
    return "".join(actuators)


def _prism_vertices(outline_xy: list[tuple[float, float]], height_m: float) -> str:
    """Vertices of a vertical prism over a convex outline (MuJoCo takes their convex hull)."""
    points = [(x, y, z) for x, y in outline_xy for z in (-0.5 * height_m, 0.5 * height_m)]
    return _fmt(points)


def _object_xml(obj: SceneObject, density: float, friction: list[float], solref: list[float],
                workcell: Workcell, parked: bool = False) -> tuple[str, str]:
    """(asset xml, body xml) of one free object. Body origin = footprint bounding-box centre, mid-height.
    parked: a feeder block waiting out of sight, weightless and without contacts until it is fed."""
    ext_x, ext_y, height = obj.dimensions_m
    scale = ext_x / workcell.object_dimensions_m(obj.type, None)[0] if obj.type != "block" else 1.0
    collide = 0 if parked else 1
    common = (f'material="c_{obj.color}" density="{density}" friction="{_fmt(friction)}" solref="{_fmt(solref)}" '
              f'contype="{collide}" conaffinity="{collide}"')
    mesh_name = f"mesh_{obj.type}_{obj.id}"
    asset = ""
    if obj.type == "block":
        geoms = f'<geom type="box" size="{_fmt([ext_x / 2, ext_y / 2, height / 2])}" {common}/>'
    elif obj.type == "cylinder":
        geoms = f'<geom type="cylinder" size="{ext_x / 2:.9g} {height / 2:.9g}" {common}/>'
    elif obj.type == "semicircle":
        radius = ext_x / 2
        outline = [(radius * math.cos(a), -ext_y / 2 + radius * math.sin(a)) for a in np.linspace(0.0, math.pi, 17)]
        asset = f'<mesh name="{mesh_name}" vertex="{_prism_vertices(outline, height)}"/>'
        geoms = f'<geom type="mesh" mesh="{mesh_name}" {common}/>'
    elif obj.type == "triangle":
        outline = [(-ext_x / 2, -ext_y / 2), (ext_x / 2, -ext_y / 2), (0.0, ext_y / 2)]
        asset = f'<mesh name="{mesh_name}" vertex="{_prism_vertices(outline, height)}"/>'
        geoms = f'<geom type="mesh" mesh="{mesh_name}" {common}/>'
    else:  # arch: two pillars and a lintel, with a hole underneath
        pillar_half_x = 0.01 * scale
        lintel_half_z = 0.005 * scale
        pillar_half_z = height / 2 - lintel_half_z
        geoms = "".join(
            f'<geom type="box" size="{pillar_half_x:.9g} {ext_y / 2:.9g} {pillar_half_z:.9g}" '
            f'pos="{sign * (ext_x / 2 - pillar_half_x):.9g} 0 {-lintel_half_z:.9g}" {common}/>'
            for sign in (-1.0, 1.0)
        ) + (
            f'<geom type="box" size="{ext_x / 2:.9g} {ext_y / 2:.9g} {lintel_half_z:.9g}" '
            f'pos="0 0 {height / 2 - lintel_half_z:.9g}" {common}/>'
        )
    if obj.aruco_id is not None:
        # A visual-only sticker on the top face carrying the ArUco tag (texture upright toward body +y).
        name = f"aruco_{obj.id}"
        asset += (
            f'<texture name="{name}" type="2d" file="{name}.png"/>'
            f'<material name="{name}" texture="{name}" specular="0" shininess="0"/>'
        )
        half = 0.5 * ext_x * STICKER_FRACTION
        geoms += (
            f'<geom type="box" size="{half:.9g} {half:.9g} 0.00005" pos="0 0 {height / 2 + 0.00005:.9g}" '
            f'material="{name}" contype="0" conaffinity="0" mass="0" group="2"/>'
        )
    gravcomp = ' gravcomp="1"' if parked else ""
    body = (
        f'<body name="{OBJECT_PREFIX}{obj.id}" pos="{_fmt(obj.position_m)}" quat="{_fmt(obj.quat_wxyz)}"{gravcomp}>'
        f"<freejoint/>{geoms}</body>"
    )
    return asset, body


def _gripper_marker_xml(workcell: Workcell, arm: ArmGeometry, assets: dict[str, bytes]) -> tuple[str, str]:
    """(asset xml, gripper-link geom xml) of the workcell's gripper marker: the tag with its white border on
    a thin visual-only card whose top face is at the marker's position (the gripper-point frame moved to the
    gripper link's); ("", "") without a marker. Adds the texture PNG to assets."""
    marker = workcell.gripper.marker
    if marker is None:
        return "", ""
    image, span = textures.tag_texture(marker.id, workcell.board_tags.detector)
    assets[GRIPPER_MARKER + ".png"] = textures.encode_png(image)
    half, thick = 0.5 * marker.size_m * span, 0.00005
    x, y, z = marker.position_m
    asset = (f'<texture name="{GRIPPER_MARKER}" type="2d" file="{GRIPPER_MARKER}.png"/>'
             f'<material name="{GRIPPER_MARKER}" texture="{GRIPPER_MARKER}" specular="0" shininess="0"/>')
    geom = (f'<geom name="{GRIPPER_MARKER}" type="box" size="{half:.9g} {half:.9g} {thick}" '
            f'pos="{x + arm.origins_m["gripper_point"][0]:.9g} {y:.9g} {z - thick:.9g}" material="{GRIPPER_MARKER}" '
            f'contype="0" conaffinity="0" mass="0" group="2"/>')
    return asset, geom


def camera_xml_attributes(T_world_camera: np.ndarray, camera: SimCameraConfig) -> str:
    """A MuJoCo camera (looks along its -z, y up) placed at an OpenCV-axes pose, with the intrinsics."""
    R_world_mj = T_world_camera[:3, :3] @ np.diag([1.0, -1.0, -1.0])
    k = camera.intrinsics
    pixel_m = 1e-5  # any sensor pixel size: MuJoCo only uses focal/principal in pixel units with it
    return (
        f'pos="{_fmt(T_world_camera[:3, 3])}" quat="{_fmt(quat_wxyz_from_matrix(R_world_mj))}" '
        f'resolution="{camera.width} {camera.height}" sensorsize="{camera.width * pixel_m:.9g} {camera.height * pixel_m:.9g}" '
        f'focalpixel="{k.fx:.9g} {k.fy:.9g}" principalpixel="{camera.width / 2 - k.cx - 0.5:.9g} {camera.height / 2 - k.cy - 0.5:.9g}"'
    )


def _feeder_xml(scene: Scene, workcell: Workcell) -> str:
    """An invisible, contact-free probe the size of a large block at the feed spot (the feeder measures
    the arm's distance to it), or nothing without a feeder."""
    if scene.feeder is None:
        return ""
    half = 0.5 * workcell.block_edge_m("large")
    x, y = scene.feeder.spot_m
    return (f'<geom name="{FEEDER_PROBE}" type="box" size="{half:.9g} {half:.9g} {half:.9g}" pos="{x:.9g} {y:.9g} {half:.9g}" '
            f'contype="0" conaffinity="0" group="5" rgba="0 0 0 0"/>')


def build_model_xml(
    arm: ArmGeometry | DhArmGeometry, sim: SimConfig, camera: SimCameraConfig, T_world_camera: np.ndarray, scene: Scene,
    workcell: Workcell | None = None, realism: SceneRealismConfig | None = None,
) -> tuple[str, dict[str, bytes]]:
    """The whole workcell as MJCF text plus the texture PNGs it references (MuJoCo in-memory assets);
    realism: the realistic workcell's second light (with its shadow map) and clutter, None for the ideal one."""
    import cv2

    workcell = workcell or load_workcell()
    board = workcell.board
    assets = {"board.png": textures.encode_png(textures.board_texture(board))}
    block_dictionary = getattr(cv2.aruco, workcell.block_tags.dictionary)
    tag_assets, tag_geoms = [], []
    for tag_id, (x, y) in workcell.board_tags.centres_m.items():
        image, span = textures.tag_texture(tag_id, workcell.board_tags.detector)
        tag_half_m = 0.5 * workcell.board_tags.size_m * span
        assets[f"tag{tag_id}.png"] = textures.encode_png(image)
        tag_assets.append(
            f'<texture name="tag{tag_id}" type="2d" file="tag{tag_id}.png"/>'
            f'<material name="tag{tag_id}" texture="tag{tag_id}" specular="0" shininess="0"/>'
        )
        tag_geoms.append(
            f'<geom name="tag{tag_id}" type="plane" size="{tag_half_m:.9g} {tag_half_m:.9g} 0.001" '
            f'pos="{x} {y} 0.0003" material="tag{tag_id}" contype="0" conaffinity="0"/>'
        )
    target = load_checkerboard_target()  # intrinsics target, parked out of sight (checkerboard.py)
    assets[f"{CHECKERBOARD}.png"] = textures.encode_png(checkerboard_texture(target))
    checker_asset, checker_body = checkerboard_xml(target)
    colors = "".join(
        f'<material name="c_{name}" rgba="{_fmt(rgba)}" specular="0.1" shininess="0.1"/>' for name, rgba in COLOR_RGBA.items()
    )
    object_assets, object_bodies = [], []
    parked = parked_objects(scene.feeder, workcell) if scene.feeder is not None else []
    for obj, is_parked in [(obj, False) for obj in scene.objects] + [(obj, True) for obj in parked]:
        if obj.aruco_id is not None:
            rgb = tuple(int(255 * c) for c in COLOR_RGBA[obj.color][:3])
            assets[f"aruco_{obj.id}.png"] = textures.encode_png(
                textures.block_top_texture(obj.aruco_id, rgb, dictionary=block_dictionary))
        asset, body = _object_xml(obj, sim.objects.density_kg_m3, sim.objects.friction, sim.objects.solref,
                                  workcell, parked=is_parked)
        object_assets.append(asset)
        object_bodies.append(body)
    finger_arm = isinstance(arm, ArmGeometry)  # the RX200 with fingers (above), else a DH arm with a cup (mjcf_dh)
    marker_asset, marker_geom = _gripper_marker_xml(workcell, arm, assets) if finger_arm else ("", "")
    arm_bodies, actuators = arm.mjcf(sim, marker_geom) if finger_arm else arm.mjcf(sim)
    tendons = arm.tendon_xml() if finger_arm else ""
    p = sim.physics
    xml = f"""<mujoco model="armlab_workcell">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{p.timestep_s}" integrator="implicitfast" cone="{p.cone}" impratio="{p.impratio}" noslip_iterations="{p.noslip_iterations}">
    <flag sleep="{'enable' if p.sleep else 'disable'}"/>
  </option>
  <statistic extent="1" center="0 0.15 0.2"/>
  <visual>
    <global offwidth="{camera.width}" offheight="{camera.height}"/>
    <quality shadowsize="{realism.shadow_size_px if realism is not None else 0}" offsamples="{sim.render.multisamples}"/>
    <map znear="0.05" zfar="20"/>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.35 0.35 0.35" specular="0 0 0"/>
  </visual>
  <asset>
    <texture name="board" type="2d" file="board.png"/>
    <material name="board" texture="board" texrepeat="1 1" texuniform="false" specular="0" shininess="0"/>
    {''.join(tag_assets)}
    <material name="table" rgba="0.32 0.24 0.17 1" specular="0" shininess="0"/>
    <material name="arm" rgba="0.15 0.15 0.17 1" specular="0.2"/>
    <material name="arm_dark" rgba="0.08 0.08 0.09 1" specular="0.2"/>
    <material name="pad" rgba="0.2 0.2 0.2 1" specular="0"/>
    {colors}
    {''.join(object_assets)}
    {checker_asset}
    {marker_asset}
  </asset>
  <worldbody>
    <light name="sun" directional="true" pos="0.2 0.3 2" dir="-0.1 -0.15 -1" castshadow="false" diffuse="0.55 0.55 0.55" specular="0 0 0"/>
    <geom name="board" type="plane" size="{0.5 * board.size_m[0]:.9g} {0.5 * board.size_m[1]:.9g} 0.05"
          pos="{_fmt(np.mean(board.corners_m, axis=0))} 0" material="board"
          friction="{_fmt(sim.objects.board_friction)}" solref="{_fmt(sim.objects.solref)}" contype="1" conaffinity="1"/>
    <geom name="table" type="plane" size="1.5 1.5 0.05" pos="0 0.15 -0.003" material="table" contype="1" conaffinity="1"/>
    {''.join(tag_geoms)}
    {realism_world_xml(realism)}
    {_feeder_xml(scene, workcell)}
    <camera name="{CAMERA_NAME}" mode="fixed" {camera_xml_attributes(T_world_camera, camera)}/>
    {arm_bodies}
    {''.join(object_bodies)}
    {checker_body}
  </worldbody>
  {f"<tendon>{tendons}</tendon>" if tendons else ""}
  <actuator>
    {actuators}
  </actuator>
</mujoco>"""
    return xml, assets
