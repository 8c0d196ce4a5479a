"""Measure a real L515's imperfections on real RGB-D frames (default: ../shared/data/rob550_dev), the
magnitudes the simulated camera's `realism: real` copies (config/cameras/sim_l515.yaml `realism:`).

Per frame: the board plane fitted to the depth against the plane the tags' pose gives (the station's PnP
on the detected tags' corners with the camera_info K and distortion): its height above the tags' plane at
the tags' centre (negative: behind), its tilt and the direction it rises in (board frame, deg from +y); depth noise (residual std in 16x16-pixel
patches after a local plane fit) against range; the hole (0) fraction on the board, at cube edges and on
dark pixels; flying pixels (between top and board) at cube edges; the board grey's colour (white balance)
and brightness (exposure) and its spread over the board (uneven light).

    python bench/real_camera.py [--data DIR]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import cv2
import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "rob550_dev"
TAG_CENTRES_MM = {1: (-250.0, -25.0), 2: (250.0, -25.0), 3: (250.0, 275.0), 4: (-250.0, 275.0)}
BOARD_X_MM = (-450.0, 450.0)  # the labelled grid's extent (calibration_f21.json), well inside the board
BOARD_Y_MM = (-125.0, 425.0)
ARM_KEEP_OUT_MM = 150.0  # the arm's base stands at the world origin: its pixels are not board (plane fit)
PATCH_PX = 16


def load_frame(data: Path, name: str):
    color = cv2.imread(str(data / f"image_{name}.png"), cv2.IMREAD_COLOR)
    depth = cv2.imread(str(data / f"depth_{name}.png"), cv2.IMREAD_ANYDEPTH)
    labels = json.loads((data / f"image_{name}.labels.json").read_text())
    return color, depth, labels


def tag_pose(color_bgr: np.ndarray, K: np.ndarray, dist: np.ndarray):
    """(R, t in mm) of the world (board) frame in the camera by the station's own PnP on the detected
    tags' corners (the ROB 550 board's tagStandard41h12 tags), and the reprojection error (px); None
    with fewer than 3 tags."""
    from armlab.vision.calibration import CalibrationError, solve_board_pose
    from armlab.vision.config import load_perception_config
    from armlab.vision.tags import detect_tags

    cfg = load_perception_config(workcell="rx200_armlab")  # the same tag centres and size as the ROB 550 board
    cfg = cfg.model_copy(update={"tags": cfg.tags.model_copy(update={"dictionary": "tagStandard41h12"})})
    tags = detect_tags(color_bgr, cfg)
    try:
        T_world_camera, error_px, _ids = solve_board_pose(tags, K, dist, cfg)
    except CalibrationError:
        return None
    T_camera_world = np.linalg.inv(T_world_camera)
    return T_camera_world[:3, :3], T_camera_world[:3, 3] * 1000.0, error_px


def camera_points(depth_mm: np.ndarray, K: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """(H, W, 3) camera-frame points in mm (depth along the optical axis, undistorted rays)."""
    h, w = depth_mm.shape
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    rays = cv2.undistortPoints(np.stack([u.ravel(), v.ravel()], 1)[:, None, :], K, dist).reshape(h, w, 2)
    z = depth_mm.astype(np.float64)
    return np.dstack([rays[..., 0] * z, rays[..., 1] * z, z])


def fit_plane(points: np.ndarray, iterations: int = 5, keep_mm: float = 4.0):
    """A robust plane (unit normal n, d: n.p = d) by trimmed least squares."""
    selected = points
    for _ in range(iterations):
        centre = selected.mean(axis=0)
        normal = np.linalg.svd(selected - centre, full_matrices=False)[2][2]
        d = float(normal @ centre)
        residual = points @ normal - d
        selected = points[np.abs(residual) < max(keep_mm, 2.5 * np.median(np.abs(residual)))]
    if normal[2] < 0:
        normal, d = -normal, -d
    return normal, d


def measure(data: Path, name: str, K: np.ndarray, dist: np.ndarray) -> dict | None:
    color, depth, labels = load_frame(data, name)
    pose = tag_pose(color, K, dist)
    if pose is None:
        return None
    R, t, reprojection_px = pose
    points = camera_points(depth, K, dist)
    world = (points - t) @ R  # camera -> world (board frame), mm
    valid = depth > 0
    # The band at the image's side where the aligned depth has no returns at all (the depth camera's
    # narrower field): its own figure, not counted as holes.
    no_field = np.zeros_like(valid)
    empty_columns = np.flatnonzero((~valid).mean(axis=0) > 0.9)
    no_field[:, empty_columns] = True
    # Where each pixel's ray meets the tags' plane (z = 0): the board region, independent of the depth
    # (a hole has no depth, an object's top is above the board).
    rays = camera_points(np.ones_like(depth), K, dist)
    rays_world = rays @ R  # directions in the world frame
    origin_world = -R.T @ t
    scale = -origin_world[2] / rays_world[..., 2]
    on_plane = origin_world + rays_world * scale[..., None]
    region = ~no_field & ((on_plane[..., 0] > BOARD_X_MM[0]) & (on_plane[..., 0] < BOARD_X_MM[1]) & (on_plane[..., 1] > BOARD_Y_MM[0])
              & (on_plane[..., 1] < BOARD_Y_MM[1]))
    # Board pixels: near the tags' plane (objects stand > 15 mm above it; the offset is < 25 mm).
    arm = np.hypot(on_plane[..., 0], on_plane[..., 1]) < ARM_KEEP_OUT_MM
    near = region & ~arm & valid & (np.abs(world[..., 2]) < 25.0)
    normal, d = fit_plane(points[near][::7])
    residual = points[..., :] @ normal - d
    board = near & (np.abs(residual) < 6.0)
    # The tags' plane in the camera frame: normal R[:, 2] (world +z, toward the camera), through t.
    tag_normal = R[:, 2]
    if tag_normal[2] > 0:
        tag_normal = -tag_normal
    tag_normal = -tag_normal  # the same orientation as the fitted normal (+z camera, away from it)
    tags_centre = np.mean(list(TAG_CENTRES_MM.values()), axis=0)
    centre_cam = t + R @ np.array([tags_centre[0], tags_centre[1], 0.0])
    ray = centre_cam / np.linalg.norm(centre_cam)
    depth_plane_point = ray * (d / float(normal @ ray))  # where the centre's ray meets the depth plane
    offset_mm = -float(tag_normal @ (depth_plane_point - centre_cam))  # + toward the camera
    tilt_deg = math.degrees(math.acos(min(1.0, abs(float(normal @ tag_normal)))))
    up_world = R.T @ -normal  # the depth plane's normal toward the camera, in the board frame
    rise_deg = math.degrees(math.atan2(-up_world[0], -up_world[1]))  # the plane rises along this direction
    # Noise: residual std in small board patches after a local plane fit, against the patch's range.
    noise = []
    h, w = depth.shape
    for v0 in range(0, h - PATCH_PX, PATCH_PX):
        for u0 in range(0, w - PATCH_PX, PATCH_PX):
            mask = board[v0:v0 + PATCH_PX, u0:u0 + PATCH_PX]
            if mask.sum() < 0.9 * PATCH_PX * PATCH_PX:
                continue
            z = depth[v0:v0 + PATCH_PX, u0:u0 + PATCH_PX][mask].astype(np.float64)
            vv, uu = np.nonzero(mask)
            A = np.column_stack([uu, vv, np.ones_like(uu)]).astype(np.float64)
            coef = np.linalg.lstsq(A, z, rcond=None)[0]
            noise.append((float(z.mean()), float(np.std(z - A @ coef))))
    noise = np.array(noise)
    # Objects: region pixels well above the fitted board; their edges: a band around them.
    height = -(residual)  # + = toward the camera (above the board)
    objects = region & valid & (height > 12.0)
    objects = cv2.morphologyEx(objects.astype(np.uint8), cv2.MORPH_OPEN, np.ones((5, 5), np.uint8))
    band = (cv2.dilate(objects, np.ones((7, 7), np.uint8)) - cv2.erode(objects, np.ones((7, 7), np.uint8))).astype(bool) & region
    flying = band & valid & (height > 4.0) & (height < 14.0)  # neither board nor a cube's top (tops >= 18 mm)
    gray = cv2.cvtColor(color, cv2.COLOR_BGR2GRAY)
    dark = region & (gray < 50)
    # Board grey: board pixels that are neither the grid's lines, tags nor shadows (the brighter half).
    board_gray = board & (gray > np.percentile(gray[board], 50))
    bgr = color[board_gray].astype(np.float64).mean(axis=0)
    # Uneven light: board brightness over a 3x3 grid of the board region.
    cells = []
    for i in range(3):
        for j in range(3):
            x0 = BOARD_X_MM[0] + (BOARD_X_MM[1] - BOARD_X_MM[0]) * i / 3
            y0 = BOARD_Y_MM[0] + (BOARD_Y_MM[1] - BOARD_Y_MM[0]) * j / 3
            cell = board_gray & (world[..., 0] >= x0) & (world[..., 0] < x0 + 300) & (world[..., 1] >= y0) & (world[..., 1] < y0 + 183)
            if cell.sum() > 500:
                cells.append(float(gray[cell].mean()))
    return {
        "frame": name,
        "board_pixels": int(board.sum()),
        "reprojection_px": round(float(reprojection_px), 2),
        "no_depth_columns": int(len(empty_columns)),
        "offset_mm": round(offset_mm, 2),
        "tilt_deg": round(tilt_deg, 2),
        "rise_deg": round(rise_deg, 0),
        "board_range_mm": round(float(np.median(depth[board])), 1),
        "noise_std_mm_median": round(float(np.median(noise[:, 1])), 2) if len(noise) else None,
        "noise_by_range": noise,
        "holes_board": round(float((region & ~valid).sum() / region.sum()), 4),
        "holes_edge_band": round(float((band & ~valid).sum() / max(1, band.sum())), 4),
        "flying_edge_band": round(float(flying.sum() / max(1, band.sum())), 4),
        "holes_dark": round(float((dark & ~valid).sum() / max(1, dark.sum())), 4),
        "dark_pixels": int(dark.sum()),
        "board_bgr": [round(float(c), 1) for c in bgr],
        "light_spread": round((max(cells) - min(cells)) / float(np.mean(cells)), 3) if cells else None,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA)
    args = parser.parse_args()
    calibration = json.loads((args.data / "calibration_f21.json").read_text())
    K = np.array(calibration["K_from_camera_info"], dtype=np.float64)
    dist = np.array(calibration["D_from_camera_info_plumb_bob"], dtype=np.float64)
    names = sorted(p.name[len("image_"):-len(".labels.json")] for p in args.data.glob("image_*.labels.json"))
    rows = []
    print(f"{'frame':<14} {'reproj':>6} {'nocol':>5} {'offset':>7} {'tilt':>5} {'rises':>6} {'range':>6} {'noise':>5} {'holes':>6} {'edgeH':>6} {'edgeF':>6} "
          f"{'darkH':>6} {'board BGR':>18} {'light':>5}")
    for name in names:
        row = measure(args.data, name, K, dist)
        if row is None:
            print(f"{name:<14} (fewer than 4 labelled tags)")
            continue
        rows.append(row)
        print(f"{name:<14} {row['reprojection_px']:>6.2f} {row['no_depth_columns']:>5} {row['offset_mm']:>6.1f}m "
              f"{row['tilt_deg']:>5.2f} {row['rise_deg']:>6.0f} {row['board_range_mm']:>6.0f} "
              f"{row['noise_std_mm_median']:>5.2f} {row['holes_board']:>6.3f} {row['holes_edge_band']:>6.3f} "
              f"{row['flying_edge_band']:>6.3f} {row['holes_dark']:>6.3f} {str(row['board_bgr']):>18} {row['light_spread']}")
    noise = np.concatenate([r["noise_by_range"] for r in rows])
    print("\ndepth noise (patch residual std) by range:")
    for lo in range(900, 1100, 25):
        sel = (noise[:, 0] >= lo) & (noise[:, 0] < lo + 25)
        if sel.sum() > 20:
            print(f"  {lo}-{lo + 25} mm: median {np.median(noise[sel, 1]):.2f} mm over {sel.sum()} patches")
    gains = np.array([r["board_bgr"] for r in rows])
    print(f"\nboard grey B/G {np.round(gains[:, 0] / gains[:, 1], 3).tolist()}, R/G {np.round(gains[:, 2] / gains[:, 1], 3).tolist()}")
    print(f"board grey G spread over frames: {100 * gains[:, 1].std() / gains[:, 1].mean():.1f} % (std/mean)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
