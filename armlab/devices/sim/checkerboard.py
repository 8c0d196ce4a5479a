"""The simulation's checkerboard target for intrinsic calibration: a flat, contact-free mocap body with a
printed checkerboard (geometry from config/intrinsics.yaml `target:`, the same board the station looks
for), parked out of sight until the operator, or a test, places it at a pose in view.

Board frame: origin at the board's centre, x along its columns of squares, y along its rows, z out of
the printed face (the camera must look at the face: the printed plane is one-sided)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.config import config_dir, read_config_file
from armlab.errors import ConfigError, InvalidInput

BODY_NAME = "checkerboard"
PARKED_POSITION_M = (0.0, 0.0, 10.0)  # 9 m above the camera, which looks down: never in view
TEXTURE_PX_PER_SQUARE = 64


@dataclass(frozen=True)
class CheckerboardTarget:
    """inner_corners (columns, rows); square_m: edge of a square; margin_squares: white border width."""

    inner_corners: tuple[int, int]
    square_m: float
    margin_squares: float

    @property
    def squares(self) -> tuple[int, int]:
        return self.inner_corners[0] + 1, self.inner_corners[1] + 1

    @property
    def size_m(self) -> tuple[float, float]:
        """Printed size (width along x, height along y) including the margin."""
        cols, rows = self.squares
        return ((cols + 2 * self.margin_squares) * self.square_m, (rows + 2 * self.margin_squares) * self.square_m)


def load_checkerboard_target(path=None) -> CheckerboardTarget:
    """The `target:` section of config/intrinsics.yaml; ConfigError naming the field when invalid."""
    path = path or config_dir() / "intrinsics.yaml"
    target = read_config_file(path).get("target")
    try:
        cols, rows = (int(v) for v in target["inner_corners"])
        square_m, margin = float(target["square_m"]), float(target.get("margin_squares", 1.0))
    except (TypeError, KeyError, ValueError) as error:
        raise ConfigError(f"{path}: target: needs inner_corners [cols, rows] and square_m ({error})") from error
    if cols < 2 or rows < 2 or not (0.0 < square_m < 1.0) or not (0.5 <= margin <= 5.0):
        raise ConfigError(f"{path}: target: inner_corners >= 2x2, 0 < square_m < 1 and 0.5 <= margin_squares <= 5 needed")
    return CheckerboardTarget((cols, rows), square_m, margin)


def checkerboard_texture(target: CheckerboardTarget, px_per_square: int = TEXTURE_PX_PER_SQUARE) -> np.ndarray:
    """RGB uint8 print of the board: black and white squares (black at the -x/+y corner) on a white margin.
    Row 0 is the board's +y edge, column 0 its -x edge (as MuJoCo maps a 2D texture on a plane)."""
    cols, rows = target.squares
    margin_px = int(round(target.margin_squares * px_per_square))
    ii, jj = np.indices((rows, cols))
    squares = np.where((ii + jj) % 2 == 0, 0, 255).astype(np.uint8)
    image = np.kron(squares, np.ones((px_per_square, px_per_square), dtype=np.uint8))
    image = np.pad(image, margin_px, constant_values=255)
    return np.repeat(image[:, :, None], 3, axis=2)


def checkerboard_xml(target: CheckerboardTarget) -> tuple[str, str]:
    """(asset xml, body xml): the texture and a mocap body with a contact-free textured plane, parked."""
    half_w, half_h = (0.5 * s for s in target.size_m)
    asset = (f'<texture name="{BODY_NAME}" type="2d" file="{BODY_NAME}.png"/>'
             f'<material name="{BODY_NAME}" texture="{BODY_NAME}" specular="0" shininess="0"/>')
    x, y, z = PARKED_POSITION_M
    body = (f'<body name="{BODY_NAME}" mocap="true" pos="{x:g} {y:g} {z:g}">'
            f'<geom name="{BODY_NAME}" type="plane" size="{half_w:.9g} {half_h:.9g} 0.001" material="{BODY_NAME}" '
            f'contype="0" conaffinity="0" group="2"/></body>')
    return asset, body


def checked_pose(position_m, rotation_matrix) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), rotation (3, 3)) as floats; ValueError unless finite, the position within 3 m of
    the origin and the rotation orthonormal."""
    position = np.asarray(position_m, dtype=float).reshape(3)
    R = np.asarray(rotation_matrix, dtype=float).reshape(3, 3)
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(R))):
        raise InvalidInput("checkerboard pose: position and rotation must be finite")
    if np.linalg.norm(position) > 3.0:
        raise InvalidInput(f"checkerboard pose: position {position.round(3).tolist()} m is more than 3 m from the origin")
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise InvalidInput("checkerboard pose: the rotation is not a proper rotation matrix")
    return position, R


FACING_CAMERA = np.diag([1.0, -1.0, -1.0])  # R_camera_board of a board square to the camera, upright in the image


def pose_in_camera_frame(T_world_camera: np.ndarray, position_camera_m, rotvec_rad=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """World (position, R_world_board) of a board whose centre is at position_camera_m in the camera's
    OpenCV frame (z = along the optical axis), turned by rotvec_rad (camera axes) from squarely facing it."""
    import cv2

    R_turn = cv2.Rodrigues(np.asarray(rotvec_rad, dtype=float).reshape(3, 1))[0]
    T = np.asarray(T_world_camera, dtype=float)
    position = T[:3, :3] @ np.asarray(position_camera_m, dtype=float) + T[:3, 3]
    return position, T[:3, :3] @ R_turn @ FACING_CAMERA


def calibration_poses(count: int, seed: int = 0, size_m: tuple[float, float] = (0.36, 0.27),
                      image_px: tuple[int, int] = (1280, 720), focal_px: float = 900.0) -> list[tuple[tuple, tuple]]:
    """`count` varied (position_camera_m, rotvec_rad) poses in the camera frame that keep a board of size_m
    inside an image of image_px at about focal_px (nominal numbers: no calibration is needed to place it):
    distances 0.5-0.8 m (the board stays well above the table), the board's centre swept over the image (corners and edges first), tilted by
    15-35 degrees about a varying axis. Seeded: the same arguments give the same poses."""
    rng = np.random.default_rng(seed)
    sweep = [(0, 0), (1, 1), (0, 1), (1, 0), (0.5, 0.5), (0.5, 0), (0.5, 1), (0, 0.5), (1, 0.5)]
    width, height = image_px
    poses = []
    for index in range(count):
        fu, fv = sweep[index] if index < len(sweep) else tuple(rng.uniform(0.0, 1.0, 2))
        z = 0.5 + 0.3 * ((index * 0.618) % 1.0)
        half_u, half_v = (0.68 * s * focal_px / z for s in size_m)  # the projected half-size, with room for the tilt
        u = half_u + fu * max(0.0, width - 2 * half_u)
        v = half_v + fv * max(0.0, height - 2 * half_v)
        position = ((u - width / 2) * z / focal_px, (v - height / 2) * z / focal_px, z)
        angle = rng.uniform(0.26, 0.6)
        axis_angle = rng.uniform(0.0, 2 * np.pi)
        rotvec = (angle * np.cos(axis_angle), angle * np.sin(axis_angle), rng.uniform(-0.25, 0.25))
        poses.append((tuple(float(x) for x in position), tuple(float(x) for x in rotvec)))
    return poses
