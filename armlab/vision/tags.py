"""Fiducial tag detection (AprilTag 36h11 by default, any OpenCV ArUco dictionary by name) with
sub-pixel corners, tuned for small (~20 px), tilted and unevenly lit tags."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from armlab.vision.config import PerceptionConfig


@dataclass(frozen=True)
class Tag:
    """One detected tag: corners (4, 2) in OpenCV order (the marker's TL, TR, BR, BL) and their mean."""

    id: int
    corners_px: np.ndarray
    center_px: np.ndarray

    def to_dict(self) -> dict:
        return {"id": self.id, "corners_px": self.corners_px.tolist(), "center_px": self.center_px.tolist()}


def check_color_image(color_bgr: np.ndarray, name: str = "color_bgr") -> np.ndarray:
    """Return the image if it is a non-empty uint8 (H, W, 3) or (H, W) array, else a ValueError saying why."""
    if not isinstance(color_bgr, np.ndarray):
        raise ValueError(f"{name} must be a numpy array, got {type(color_bgr).__name__}")
    if color_bgr.size == 0:
        raise ValueError(f"{name} is empty (shape {color_bgr.shape})")
    if color_bgr.dtype != np.uint8:
        raise ValueError(f"{name} must be uint8, got {color_bgr.dtype}")
    if color_bgr.ndim not in (2, 3) or (color_bgr.ndim == 3 and color_bgr.shape[2] != 3):
        raise ValueError(f"{name} must be (H, W, 3) BGR or (H, W) grey, got shape {color_bgr.shape}")
    if min(color_bgr.shape[:2]) < 16:
        raise ValueError(f"{name} is too small to hold a tag: shape {color_bgr.shape}")
    return color_bgr


def make_detector(dictionary: str) -> cv2.aruco.ArucoDetector:
    """An ArucoDetector for a dictionary name, with parameters for small tags and sub-pixel corners."""
    if not dictionary.startswith("DICT_") or not hasattr(cv2.aruco, dictionary):
        raise ValueError(f"unknown OpenCV ArUco dictionary '{dictionary}'")
    params = cv2.aruco.DetectorParameters()
    params.minMarkerPerimeterRate = 0.01
    params.adaptiveThreshWinSizeMin = 7  # two threshold scales: small tags and shaded ones
    params.adaptiveThreshWinSizeMax = 23
    params.adaptiveThreshWinSizeStep = 16
    params.polygonalApproxAccuracyRate = 0.03  # 0.05 lets many non-square blobs through: ~10x slower
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_NONE  # refined in detect_tags, sized to the tag
    params.perspectiveRemovePixelPerCell = 8
    params.perspectiveRemoveIgnoredMarginPerCell = 0.2
    return cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)), params)


def _log_grey(grey: np.ndarray) -> np.ndarray:
    """Log-scaled grey: a shadow (a multiplicative dimming) becomes an offset, so a tag half in shadow
    still thresholds into the right black and white cells."""
    lut = np.round(255.0 * np.log1p(np.arange(256)) / np.log(256.0)).astype(np.uint8)
    return lut[grey]


def _markers(detector: cv2.aruco.ArucoDetector, grey: np.ndarray) -> dict[int, np.ndarray]:
    corners, ids, _ = detector.detectMarkers(grey)
    found: dict[int, np.ndarray] = {}
    if ids is not None:
        for tag_corners, tag_id in zip(corners, ids.ravel()):
            found.setdefault(int(tag_id), np.asarray(tag_corners, dtype=np.float32).reshape(4, 1, 2))
    return found


def detect_tags(
    color_bgr: np.ndarray,
    cfg: PerceptionConfig | None = None,
    dictionary: str | None = None,
    detector: cv2.aruco.ArucoDetector | None = None,
    expected_ids: set[int] | None = None,
) -> list[Tag]:
    """All tags in the image (one per id), sorted by id. The dictionary comes from `dictionary`, else
    cfg, else 36h11. If some expected tag (default: cfg's board tags) is missing, or nothing was found,
    the search is repeated on a log-scaled image, which reads tags that lie partly in shadow.

    Pass a prebuilt `detector` (make_detector) to save its construction in a per-frame loop.
    """
    check_color_image(color_bgr)
    if detector is None:
        name = dictionary or (cfg.tags.dictionary if cfg is not None else "DICT_APRILTAG_36h11")
        detector = make_detector(name)
    if expected_ids is None and cfg is not None and dictionary in (None, cfg.tags.dictionary):
        expected_ids = set(cfg.tags.board_tags)
    grey = color_bgr if color_bgr.ndim == 2 else cv2.cvtColor(color_bgr, cv2.COLOR_BGR2GRAY)
    found = _markers(detector, grey)
    if not found or (expected_ids and not expected_ids <= set(found)):
        for tag_id, pts in _markers(detector, _log_grey(grey)).items():
            found.setdefault(tag_id, pts)
    tags = []
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 0.001)
    for tag_id, pts in sorted(found.items()):
        sides = pts[:, 0] - pts[[3, 0, 1, 2], 0]
        side_px = float(np.sqrt((sides * sides).sum(axis=1)).min())
        half_window = int(min(max(side_px / 10.0, 2), 5))  # ~1/10 of the tag: on the corner, off the code cells
        refined = cv2.cornerSubPix(grey, pts.copy(), (half_window, half_window), (-1, -1), criteria)
        refined = refined.reshape(4, 2).astype(np.float64)
        tags.append(Tag(id=tag_id, corners_px=refined, center_px=refined.mean(axis=0)))
    return tags


def detect_tags_near(
    color_bgr: np.ndarray, centers_px: np.ndarray, half_size_px: int, detector: cv2.aruco.ArucoDetector
) -> list[Tag]:
    """Tags searched only in square windows around expected centres (tracking known tags cheaply).

    Each window is searched separately; a tag is kept once (the first window that sees it).
    """
    check_color_image(color_bgr)
    h, w = color_bgr.shape[:2]
    found: dict[int, Tag] = {}
    for u, v in np.asarray(centers_px, dtype=np.float64).reshape(-1, 2):
        if not (np.isfinite(u) and np.isfinite(v)):
            continue
        x0, y0 = max(0, int(u) - half_size_px), max(0, int(v) - half_size_px)
        x1, y1 = min(w, int(u) + half_size_px), min(h, int(v) + half_size_px)
        if x1 - x0 < 16 or y1 - y0 < 16:
            continue
        for tag in detect_tags(color_bgr[y0:y1, x0:x1], detector=detector):
            if tag.id not in found:
                offset = np.array([x0, y0], dtype=np.float64)
                found[tag.id] = Tag(tag.id, tag.corners_px + offset, tag.center_px + offset)
    return sorted(found.values(), key=lambda tag: tag.id)
