"""Synthetic overhead frames with exact ground truth, made independently of the simulator:
a board texture with tags, seen through a known pinhole camera by a plane homography."""

from __future__ import annotations

import cv2
import numpy as np

from armlab.devices.camera import Intrinsics

MM_PER_TEXEL = 0.5
BOARD_X_M = (-0.5, 0.5)
BOARD_Y_M = (-0.175, 0.475)
L515 = Intrinsics(width=1280, height=720, fx=904.0, fy=904.0, cx=644.0, cy=361.0)


def look_at_pose(position_m, target_m, up_hint=(0.0, 1.0, 0.0)) -> np.ndarray:
    """T_world_camera for a camera at position_m looking at target_m (OpenCV axes, image up ~ +y)."""
    position, target = np.asarray(position_m, float), np.asarray(target_m, float)
    z = target - position
    z /= np.linalg.norm(z)
    x = np.cross(z, np.asarray(up_hint, float))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = position
    return T


def board_texture(tags: dict[int, tuple[float, float]], tag_size_m: float = 0.025, dictionary=cv2.aruco.DICT_APRILTAG_36h11) -> np.ndarray:
    """Top-down board image (row 0 = +y edge) with grey wood, 50 mm grid lines and tags on white margins."""
    width = int(round((BOARD_X_M[1] - BOARD_X_M[0]) * 1000 / MM_PER_TEXEL))
    height = int(round((BOARD_Y_M[1] - BOARD_Y_M[0]) * 1000 / MM_PER_TEXEL))
    tex = np.full((height, width, 3), (150, 150, 150), np.uint8)
    for x in np.arange(-0.45, 0.451, 0.05):
        c = int(round((x - BOARD_X_M[0]) * 1000 / MM_PER_TEXEL))
        tex[:, c] = (90, 90, 90)
    for y in np.arange(-0.175, 0.476, 0.05):
        r = int(round((BOARD_Y_M[1] - y) * 1000 / MM_PER_TEXEL))
        tex[min(r, height - 1), :] = (90, 90, 90)
    aruco_dict = cv2.aruco.getPredefinedDictionary(dictionary)
    side = int(round(tag_size_m * 1000 / MM_PER_TEXEL))
    for tag_id, (cx, cy) in tags.items():
        marker = cv2.aruco.generateImageMarker(aruco_dict, tag_id, side)
        margin = side // 4
        c0 = int(round((cx - BOARD_X_M[0]) * 1000 / MM_PER_TEXEL)) - side // 2
        r0 = int(round((BOARD_Y_M[1] - cy) * 1000 / MM_PER_TEXEL)) - side // 2
        tex[r0 - margin : r0 + side + margin, c0 - margin : c0 + side + margin] = 255
        tex[r0 : r0 + side, c0 : c0 + side] = marker[:, :, None]
    return tex


def texture_to_world() -> np.ndarray:
    """3x3 map from texture pixel centres (col, row, 1) to board metres (x, y, 1)."""
    s = MM_PER_TEXEL / 1000.0
    return np.array([[s, 0, BOARD_X_M[0] + s / 2], [0, -s, BOARD_Y_M[1] - s / 2], [0, 0, 1.0]])


def render_board(T_world_camera: np.ndarray, intrinsics: Intrinsics = L515, tags=None, tag_size_m=0.025, shade=False):
    """(color_bgr, depth_mm) of the bare board seen by the camera; depth from exact ray-plane geometry."""
    tags = tags or {1: (-0.25, -0.025), 2: (0.25, -0.025), 3: (0.25, 0.275), 4: (-0.25, 0.275)}
    tex = board_texture(tags, tag_size_m)
    K = intrinsics.K
    T_camera_world = np.linalg.inv(T_world_camera)
    H_img_world = K @ np.column_stack([T_camera_world[:3, 0], T_camera_world[:3, 1], T_camera_world[:3, 3]])
    H = H_img_world @ texture_to_world()
    color = cv2.warpPerspective(tex, H, (intrinsics.width, intrinsics.height), flags=cv2.INTER_AREA, borderValue=(60, 60, 60))
    if shade:  # a soft shadow band across the image
        ramp = np.linspace(1.0, 0.45, intrinsics.width, dtype=np.float32)[None, :, None]
        color = np.clip(color.astype(np.float32) * ramp, 0, 255).astype(np.uint8)
    u, v = np.meshgrid(np.arange(intrinsics.width), np.arange(intrinsics.height))
    rays = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u, dtype=float)], axis=-1)
    dz = rays @ T_world_camera[2, :3]
    s = -T_world_camera[2, 3] / dz
    depth = np.where(s > 0, np.round(s * 1000.0), 0).astype(np.uint16)
    return color, depth


def render_sim(scene, seed: int, arm_q=None) -> tuple:
    """(Frame, truth) of a scene in the MuJoCo workcell with the camera rig bumped by `seed`."""
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=seed, camera_pose_error=True))
    cell.start()
    try:
        cell.set_scene(scene)
        cell.step(0.5)
        if arm_q is not None:
            cell.apply_arm_reference(np.asarray(arm_q, float), np.zeros(5))
            cell.step(3.0)
        return cell.render(), cell.truth()
    finally:
        cell.close()
