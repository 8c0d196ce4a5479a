"""The station's channels in Foxglove's schemas: topic names, and pure builders of each message from station data.

One definition for every sink: an MCAP recording (recorder.py) and the live Foxglove server (live.py) log the same
messages on the same channels (`StationChannels.on_file(file)`, `StationChannels.open(context)`). Units: SI; times in
nanoseconds since the Unix epoch; frame ids: "world", "base", one per joint ("<joint>" at its origin, as the arm
model's joint_frames), "gripper" (the gripper point), "camera" (the colour camera's optical frame: +z along
the view, +x right, +y down, as OpenCV's and Foxglove's), and the links of the arm's URDF (armlab.station.arm_urdf:
"<joint>_link", "tool_point", the fingers' links), each from its parent link as robot_state_publisher gives them, so
Foxglove's 3-D panel moves the URDF served by the live server.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from foxglove import Channel, Context
from foxglove.channels import (
    CameraCalibrationChannel,
    CompressedImageChannel,
    FrameTransformsChannel,
    JointStatesChannel,
    LogChannel,
    RawImageChannel,
    SceneUpdateChannel,
)
from foxglove.messages import (
    CameraCalibration,
    Color,
    CompressedImage,
    CubePrimitive,
    FrameTransform,
    FrameTransforms,
    JointState,
    JointStates,
    LinePrimitive,
    Log,
    LogLevel,
    Point3,
    Pose,
    Quaternion,
    RawImage,
    SceneEntity,
    SceneEntityDeletion,
    SceneEntityDeletionType,
    SceneUpdate,
    SpherePrimitive,
    TextPrimitive,
    Timestamp,
    Vector3,
)

from armlab.kinematics.rotations import quat_xyzw_from_matrix

# topic -> Foxglove schema name (JSON channels: their own schema title). The tests and readers key on these.
TOPICS = {
    "/joint_states": "foxglove.JointStates",  # measured (rad, rad/s)
    "/joint_commands": "foxglove.JointStates",  # the commanded reference now (rad)
    "/gripper": "armlab.Gripper",  # JSON: width_m, holding, command
    "/tf": "foxglove.FrameTransforms",  # world -> base, joints, gripper, camera
    "/camera/color/compressed": "foxglove.CompressedImage",  # JPEG
    "/camera/depth": "foxglove.RawImage",  # 16UC1, millimetres (0: no reading)
    "/camera/calibration": "foxglove.CameraCalibration",
    "/detections": "armlab.Detections",  # JSON: the blocks of GET /api/detections
    "/detections/scene": "foxglove.SceneUpdate",  # the same blocks as cubes in the world frame
    "/plan": "foxglove.SceneUpdate",  # the running task's next move: its block, a line to where it goes, a label
    "/events": "foxglove.Log",  # the station's event log, its state changes and its jobs
}

GRIPPER_SCHEMA = {
    "title": "armlab.Gripper", "type": "object",
    "properties": {"time_s": {"type": "number"}, "width_m": {"type": "number"}, "holding": {"type": "boolean"},
                   "command": {"type": "string"}},
}
DETECTIONS_SCHEMA = {
    "title": "armlab.Detections", "type": "object",
    "properties": {"time_s": {"type": "number"}, "frame_sequence": {"type": "integer"}, "blocks": {"type": "array", "items": {"type": "object"}}},
}
LOG_LEVELS = {"info": LogLevel.Info, "warn": LogLevel.Warning, "error": LogLevel.Error}
BLOCK_RGBA = {  # a display colour per block colour name; unknown names are grey
    "red": (0.85, 0.1, 0.1), "orange": (1.0, 0.5, 0.0), "yellow": (0.95, 0.85, 0.1), "green": (0.1, 0.7, 0.2),
    "blue": (0.1, 0.3, 0.9), "violet": (0.5, 0.2, 0.7), "purple": (0.5, 0.2, 0.7), "pink": (1.0, 0.4, 0.7),
}



def stamp(time_ns: int) -> Timestamp:
    return Timestamp(sec=int(time_ns // 1_000_000_000), nsec=int(time_ns % 1_000_000_000))


def seconds_to_ns(time_s: float) -> int:
    return int(round(float(time_s) * 1e9))


def joint_states(time_ns: int, names, positions_rad, velocities_rad_s=None) -> JointStates:
    positions = np.asarray(positions_rad, dtype=float).tolist()  # Python floats once, not a numpy scalar each
    velocities = [math.nan] * len(names) if velocities_rad_s is None else np.asarray(velocities_rad_s, dtype=float).tolist()
    return JointStates(timestamp=stamp(time_ns), joints=[
        JointState(name=str(name), position=q, velocity=v) for name, q, v in zip(names, positions, velocities)])


def quaternion(rotation: np.ndarray) -> Quaternion:
    """A rotation matrix as a unit quaternion (x, y, z, w)."""
    x, y, z, w = quat_xyzw_from_matrix(rotation)
    return Quaternion(x=x, y=y, z=z, w=w)


def _pose_parts(T_parent_child: np.ndarray) -> tuple[Vector3, Quaternion]:
    T = np.asarray(T_parent_child, dtype=float).tolist()  # Python floats once (the same values as T[i, j])
    x, y, z, w = quat_xyzw_from_matrix(T_parent_child)
    return Vector3(x=T[0][3], y=T[1][3], z=T[2][3]), Quaternion(x=x, y=y, z=z, w=w)


def frame_transform(time_ns: int, parent: str, child: str, T_parent_child: np.ndarray, *, timestamp: Timestamp | None = None,
                    parts: dict | None = None) -> FrameTransform:
    """parts: a cache {(parent, child): (the 4x4's bytes, translation, rotation)}: a transform that has not changed
    (a fixed frame) reuses its translation and rotation instead of computing them again."""
    if parts is None:
        translation, rotation = _pose_parts(T_parent_child)
    else:
        T = np.asarray(T_parent_child, dtype=float)
        key, matrix = (parent, child), T.tobytes()
        cached = parts.get(key)
        if cached is None or cached[0] != matrix:
            cached = parts[key] = (matrix, *_pose_parts(T))
        translation, rotation = cached[1], cached[2]
    return FrameTransform(timestamp=timestamp if timestamp is not None else stamp(time_ns), parent_frame_id=parent,
                          child_frame_id=child, translation=translation, rotation=rotation)


def frame_transforms(time_ns: int, poses_in_world: dict[str, np.ndarray], links=(), parts: dict | None = None) -> FrameTransforms:
    """{child frame: its 4x4 pose in the world frame} as transforms from "world", then `links`: (parent, child, 4x4
    pose of the child in the parent) each (the URDF's links). parts: frame_transform's cache, kept by the caller."""
    timestamp = stamp(time_ns)
    return FrameTransforms(transforms=[frame_transform(time_ns, "world", child, T, timestamp=timestamp, parts=parts)
                                       for child, T in poses_in_world.items()]
                           + [frame_transform(time_ns, parent, child, T, timestamp=timestamp, parts=parts) for parent, child, T in links])


def compressed_image(time_ns: int, jpeg: bytes, frame_id: str = "camera") -> CompressedImage:
    return CompressedImage(timestamp=stamp(time_ns), frame_id=frame_id, data=jpeg, format="jpeg")


def depth_image(time_ns: int, depth_mm: np.ndarray, frame_id: str = "camera") -> RawImage:
    depth = np.ascontiguousarray(depth_mm, dtype="<u2")
    return RawImage(timestamp=stamp(time_ns), frame_id=frame_id, width=int(depth.shape[1]), height=int(depth.shape[0]),
                    encoding="16UC1", step=int(depth.shape[1] * 2), data=depth.tobytes())


def scaled_intrinsics(intrinsics, scale: float):
    """The intrinsics of the image resized by `scale` (pixel centres kept: c' = (c + 0.5) * s - 0.5)."""
    if scale >= 1.0:
        return intrinsics
    width, height = max(1, round(intrinsics.width * scale)), max(1, round(intrinsics.height * scale))
    sx, sy = width / intrinsics.width, height / intrinsics.height
    return replace(intrinsics, width=width, height=height, fx=intrinsics.fx * sx, fy=intrinsics.fy * sy,
                   cx=(intrinsics.cx + 0.5) * sx - 0.5, cy=(intrinsics.cy + 0.5) * sy - 0.5)


def camera_calibration(time_ns: int, intrinsics, frame_id: str = "camera") -> CameraCalibration:
    """armlab.devices.camera Intrinsics (pinhole, OpenCV's plumb_bob distortion) as Foxglove's calibration."""
    fx, fy, cx, cy = float(intrinsics.fx), float(intrinsics.fy), float(intrinsics.cx), float(intrinsics.cy)
    return CameraCalibration(
        timestamp=stamp(time_ns), frame_id=frame_id, width=int(intrinsics.width), height=int(intrinsics.height),
        distortion_model="plumb_bob", D=[float(d) for d in intrinsics.dist],
        K=[fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0], R=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        P=[fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0])


def log_message(time_ns: int, level: str, message: str, name: str = "station") -> Log:
    return Log(timestamp=stamp(time_ns), level=LOG_LEVELS.get(level, LogLevel.Info), message=message, name=name, file="", line=0)


def detections_scene(time_ns: int, blocks: list[dict]) -> SceneUpdate:
    """Detected blocks (wire dicts of GET /api/detections) as cubes in the world frame: a cube of the block's
    height standing on the board at its position, turned by its yaw. The blocks of earlier updates are deleted first
    (a block no longer seen disappears)."""
    entities = []
    for block in blocks:
        edge_m = float(block.get("height_m") or 0.0) or 0.02
        x, y, z = (float(v) for v in block["position_m"])
        yaw = float(block.get("yaw_rad", 0.0))
        r, g, b = BLOCK_RGBA.get(str(block.get("color")), (0.6, 0.6, 0.6))
        cube = CubePrimitive(
            pose=Pose(position=Vector3(x=x, y=y, z=z - edge_m / 2.0),
                      orientation=Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))),
            size=Vector3(x=edge_m, y=edge_m, z=edge_m), color=Color(r=r, g=g, b=b, a=0.8))
        entities.append(SceneEntity(timestamp=stamp(time_ns), frame_id="world", id=f"block-{block.get('id')}",
                                    frame_locked=False, cubes=[cube]))
    return SceneUpdate(deletions=[SceneEntityDeletion(timestamp=stamp(time_ns), type=SceneEntityDeletionType.All)], entities=entities)


PLAN_ENTITY = "plan"
PLAN_LIFT_M = 0.05  # the line from the block to its destination is drawn this high above both


def plan_scene(time_ns: int, plan: dict | None) -> SceneUpdate:
    """The running task's next move (its progress's next_block, a wire block dict, and next_target_m) as one entity:
    a sphere on the block, a line up, across and down to the destination, a sphere there and a label; None or no
    block: the entity deleted (no move planned)."""
    block = (plan or {}).get("next_block")
    deletion = [SceneEntityDeletion(timestamp=stamp(time_ns), type=SceneEntityDeletionType.MatchingId, id=PLAN_ENTITY)]
    if not block or block.get("position_m") is None:
        return SceneUpdate(deletions=deletion)
    start = [float(v) for v in block["position_m"]]
    target = plan.get("next_target_m")
    color = Color(r=1.0, g=0.85, b=0.0, a=1.0)
    points = [start, [start[0], start[1], start[2] + PLAN_LIFT_M]]
    spheres = [SpherePrimitive(pose=Pose(position=Vector3(x=start[0], y=start[1], z=start[2]), orientation=Quaternion(w=1.0)),
                               size=Vector3(x=0.03, y=0.03, z=0.03), color=Color(r=1.0, g=0.85, b=0.0, a=0.5))]
    if target is not None:
        end = [float(v) for v in target]
        top = max(start[2], end[2]) + PLAN_LIFT_M
        points = [start, [start[0], start[1], top], [end[0], end[1], top], end]
        spheres.append(SpherePrimitive(pose=Pose(position=Vector3(x=end[0], y=end[1], z=end[2]), orientation=Quaternion(w=1.0)),
                                       size=Vector3(x=0.02, y=0.02, z=0.02), color=color))
    label = f"next: {block.get('color') or ''} {block.get('size') or ''}".rstrip()
    entity = SceneEntity(
        timestamp=stamp(time_ns), frame_id="world", id=PLAN_ENTITY, frame_locked=False, spheres=spheres,
        lines=[LinePrimitive(pose=Pose(position=Vector3(x=0.0, y=0.0, z=0.0), orientation=Quaternion(w=1.0)), thickness=0.004,
                             points=[Point3(x=x, y=y, z=z) for x, y, z in points], color=color)],
        texts=[TextPrimitive(pose=Pose(position=Vector3(x=start[0], y=start[1], z=points[1][2] + 0.02), orientation=Quaternion(w=1.0)),
                             billboard=True, font_size=14.0, scale_invariant=True, color=color, text=label)])
    return SceneUpdate(deletions=deletion, entities=[entity])




# attribute of StationChannels -> (topic, message class or JSON schema)
CHANNELS = {
    "joint_states": ("/joint_states", JointStates),
    "joint_commands": ("/joint_commands", JointStates),
    "gripper": ("/gripper", GRIPPER_SCHEMA),
    "tf": ("/tf", FrameTransforms),
    "color": ("/camera/color/compressed", CompressedImage),
    "depth": ("/camera/depth", RawImage),
    "calibration": ("/camera/calibration", CameraCalibration),
    "detections": ("/detections", DETECTIONS_SCHEMA),
    "detections_scene": ("/detections/scene", SceneUpdate),
    "plan": ("/plan", SceneUpdate),
    "events": ("/events", Log),
}
_SDK_CHANNELS = {JointStates: JointStatesChannel, FrameTransforms: FrameTransformsChannel, CompressedImage: CompressedImageChannel,
                 RawImage: RawImageChannel, CameraCalibration: CameraCalibrationChannel, SceneUpdate: SceneUpdateChannel, Log: LogChannel}


@dataclass
class StationChannels:
    """The channels of TOPICS, each with log(message, log_time=ns) and close(): on a foxglove Context (every sink of
    the context, e.g. a live WebSocket server, gets every message) or on an MCAP file (mcap_file.McapFile)."""

    joint_states: Any
    joint_commands: Any
    gripper: Any
    tf: Any
    color: Any
    depth: Any
    calibration: Any
    detections: Any
    detections_scene: Any
    plan: Any
    events: Any

    @classmethod
    def open(cls, context: Context) -> StationChannels:
        """The channels on a foxglove Context."""
        return cls(**{
            name: Channel(topic, schema=schema, context=context) if isinstance(schema, dict) else _SDK_CHANNELS[schema](topic, context=context)
            for name, (topic, schema) in CHANNELS.items()
        })

    @classmethod
    def on_file(cls, file: Any) -> StationChannels:
        """The channels on an McapFile (its channel(topic, schema))."""
        return cls(**{name: file.channel(topic, schema) for name, (topic, schema) in CHANNELS.items()})

    def close(self) -> None:
        for channel in vars(self).values():
            channel.close()
