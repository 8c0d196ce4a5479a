"""Fiducial tag detection: AprilTag families (tag36h11, tagStandard41h12, ...) through the AprilTag 3
library (pupil-apriltags, the detector apriltag_ros uses), OpenCV ArUco dictionaries (DICT_..., e.g.
DICT_APRILTAG_36h11) through OpenCV. Every instance is reported (many blocks may carry one id), with
sub-pixel corners, the decoder's hamming distance and, for AprilTag, its decision margin."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from armlab.vision.config import PerceptionConfig, TagDetectionConfig, is_apriltag_family

# AprilTag corners run counter-clockwise from the tag's bottom-left (image y down); OpenCV's run
# TL, TR, BR, BL. This reorders the first into the second for an upright tag.
_APRILTAG_TO_OPENCV = [3, 2, 1, 0]


@dataclass(frozen=True, eq=False)
class Tag:
    """One detected tag: corners (4, 2) in OpenCV order (the marker's TL, TR, BR, BL) and their mean;
    hamming: bits the decoder corrected (None: ArUco does not say); decision_margin: AprilTag's
    confidence (higher is surer; None for ArUco)."""

    id: int
    corners_px: np.ndarray
    center_px: np.ndarray
    hamming: int | None = None
    decision_margin: float | None = None

    def to_dict(self) -> dict:
        return {"id": self.id, "corners_px": self.corners_px.tolist(), "center_px": self.center_px.tolist(),
                "hamming": self.hamming, "decision_margin": self.decision_margin}

    def corners_apriltag_px(self) -> np.ndarray:
        """Corners (4, 2) in the AprilTag library's convention (counter-clockwise from the tag's
        bottom-left, pixel centres at +0.5), to compare with the library's or apriltag_ros' output."""
        return self.corners_px[_APRILTAG_TO_OPENCV] + 0.5  # the reordering is its own inverse

    def shifted(self, offset_px: np.ndarray) -> Tag:
        """The same tag with its pixels moved by offset_px (a crop's origin)."""
        return Tag(self.id, self.corners_px + offset_px, self.center_px + offset_px, self.hamming, self.decision_margin)


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


class AprilTagDetector:
    """The AprilTag 3 library's detector for one family, with the config's thresholds applied."""

    def __init__(self, family: str, settings: TagDetectionConfig | None = None) -> None:
        import ctypes

        from pupil_apriltags import Detector
        from pupil_apriltags.bindings import _ApriltagFamily

        self.family = family
        self.settings = settings or TagDetectionConfig()
        s = self.settings
        # pupil-apriltags always builds its decode table for 2 corrected bits; built here for max_hamming
        # bits instead (tagStandard41h12: 0.2 s at 2 bits, 6 ms at 1; tag36h11: 35 ms at 2, 4 ms at 1).
        self._detector = Detector(families="tag16h5", nthreads=1, quad_decimate=s.quad_decimate,
                                  quad_sigma=s.quad_sigma, refine_edges=1)
        libc, pointer = self._detector.libc, self._detector.tag_detector_ptr
        libc.apriltag_detector_clear_families.restype = None
        libc.apriltag_detector_clear_families(pointer)
        libc.tag16h5_destroy.restype = None
        libc.tag16h5_destroy(self._detector.tag_families.pop("tag16h5"))
        create = getattr(libc, f"{family}_create")
        create.restype = ctypes.POINTER(_ApriltagFamily)
        self._detector.tag_families[family] = create()
        libc.apriltag_detector_add_family_bits(pointer, self._detector.tag_families[family], s.max_hamming)
        pointer.contents.decode_sharpening = float(s.decode_sharpening)  # the wrapper truncates it to an int

    def __del__(self) -> None:
        free_library_detector(getattr(self, "_detector", None))

    def detect(self, grey: np.ndarray) -> list[tuple[int, np.ndarray, int | None, float | None]]:
        """(id, corners (4, 1, 2) float32 in OpenCV order, hamming, decision margin) per instance."""
        found = []
        for det in self._detector.detect(np.ascontiguousarray(grey)):
            if det.hamming > self.settings.max_hamming or det.decision_margin < self.settings.min_decision_margin:
                continue
            # The library puts pixel centres at +0.5 (image corner = 0, 0); OpenCV at integers.
            corners = (np.asarray(det.corners, dtype=np.float32)[_APRILTAG_TO_OPENCV] - 0.5).reshape(4, 1, 2)
            found.append((int(det.tag_id), corners, int(det.hamming), float(det.decision_margin)))
        return found


def free_library_detector(detector) -> None:
    """Free a pupil_apriltags.Detector's C detector before its families: pupil-apriltags' own __del__
    frees the families first, and the detector's teardown then reads them (an intermittent segfault,
    pupil-labs/apriltags#46, duckietown/lib-dt-apriltags#33). Its own __del__ then does nothing."""
    if detector is None or getattr(detector, "tag_detector_ptr", None) is None:
        return
    libc = detector.libc
    libc.apriltag_detector_destroy.restype = None
    libc.apriltag_detector_destroy(detector.tag_detector_ptr)
    detector.tag_detector_ptr = None
    for family, pointer in detector.tag_families.items():
        destroy = getattr(libc, f"{family}_destroy")
        destroy.restype = None
        destroy(pointer)
    detector.tag_families = {}


def make_detector(name: str, settings: TagDetectionConfig | None = None):
    """A detector for an AprilTag family name (AprilTagDetector) or an OpenCV dictionary name
    (cv2.aruco.ArucoDetector, parameters for small tags; corners refined in detect_tags)."""
    if is_apriltag_family(name):
        return AprilTagDetector(name, settings)
    if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
        raise ValueError(f"unknown tag family '{name}' (AprilTag: tag36h11, tagStandard41h12, ...; "
                         f"OpenCV ArUco: DICT_APRILTAG_36h11, DICT_4X4_50, ...)")
    params = cv2.aruco.DetectorParameters()
    params.minMarkerPerimeterRate = 0.01
    params.adaptiveThreshWinSizeMin = 7  # two threshold scales: small tags and shaded ones
    params.adaptiveThreshWinSizeMax = 23
    params.adaptiveThreshWinSizeStep = 16
    params.polygonalApproxAccuracyRate = 0.03  # 0.05 lets many non-square blobs through: ~10x slower
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_NONE  # refined in detect_tags, sized to the tag
    params.perspectiveRemovePixelPerCell = 8
    params.perspectiveRemoveIgnoredMarginPerCell = 0.2
    if settings is not None:
        params.errorCorrectionRate = settings.aruco_error_correction_rate
    return cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name)), params)


def _log_grey(grey: np.ndarray) -> np.ndarray:
    """Log-scaled grey: a shadow (a multiplicative dimming) becomes an offset, so a tag half in shadow
    still thresholds into the right black and white cells."""
    lut = np.round(255.0 * np.log1p(np.arange(256)) / np.log(256.0)).astype(np.uint8)
    return lut[grey]


def _markers(detector, grey: np.ndarray) -> list[tuple[int, np.ndarray, int | None, float | None]]:
    """Every instance the detector finds: (id, corners (4, 1, 2), hamming, decision margin)."""
    if isinstance(detector, AprilTagDetector):
        return detector.detect(grey)
    corners, ids, _ = detector.detectMarkers(grey)
    if ids is None:
        return []
    return [(int(i), np.asarray(c, dtype=np.float32).reshape(4, 1, 2), None, None) for c, i in zip(corners, ids.ravel())]


def _same_instance(a: np.ndarray, b: np.ndarray) -> bool:
    """Two detections of one printed tag: centres closer than a quarter of the smaller tag's side."""
    side = min(np.linalg.norm(a[0, 0] - a[1, 0]), np.linalg.norm(b[0, 0] - b[1, 0]))
    return float(np.linalg.norm(a[:, 0].mean(axis=0) - b[:, 0].mean(axis=0))) < 0.25 * side


def _refine(grey: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Corners refined to sub-pixel with a window ~1/10 of the tag (on the corner, off the code cells)."""
    sides = pts[:, 0] - pts[[3, 0, 1, 2], 0]
    side_px = float(np.sqrt((sides * sides).sum(axis=1)).min())
    half_window = int(min(max(side_px / 10.0, 2), 5))
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 0.001)
    return cv2.cornerSubPix(grey, pts.copy(), (half_window, half_window), (-1, -1), criteria)


def detect_tags(
    color_bgr: np.ndarray,
    cfg: PerceptionConfig | None = None,
    dictionary: str | None = None,
    detector=None,
    expected_ids: set[int] | None = None,
) -> list[Tag]:
    """Every tag instance in the image, sorted by id then image position (row, column). The family
    comes from `dictionary` (an AprilTag family or OpenCV DICT_ name), else cfg, else
    DICT_APRILTAG_36h11. If some expected tag (default: cfg's board tags) is missing, or nothing was
    found, the search is repeated on a log-scaled image, which reads tags partly in shadow.

    Pass a prebuilt `detector` (make_detector) to save its construction in a per-frame loop.
    """
    check_color_image(color_bgr)
    if detector is None:
        name = dictionary or (cfg.tags.dictionary if cfg is not None else "DICT_APRILTAG_36h11")
        detector = make_detector(name, cfg.tag_detection if cfg is not None else None)
    if expected_ids is None and cfg is not None and dictionary in (None, cfg.tags.dictionary):
        expected_ids = set(cfg.tags.board_tags)
    grey = color_bgr if color_bgr.ndim == 2 else cv2.cvtColor(color_bgr, cv2.COLOR_BGR2GRAY)
    found = _markers(detector, grey)
    if not found or (expected_ids and not expected_ids <= {f[0] for f in found}):
        for extra in _markers(detector, _log_grey(grey)):
            if not any(f[0] == extra[0] and _same_instance(f[1], extra[1]) for f in found):
                found.append(extra)
    apriltag = isinstance(detector, AprilTagDetector)
    tags = []
    for tag_id, pts, hamming, margin in found:
        refined = (pts if apriltag else _refine(grey, pts)).reshape(4, 2).astype(np.float64)  # AprilTag: edges refined
        tags.append(Tag(tag_id, refined, refined.mean(axis=0), hamming, margin))
    return sorted(tags, key=lambda t: (t.id, round(float(t.center_px[1])), float(t.center_px[0])))


def detect_tags_near(color_bgr: np.ndarray, centers_px: np.ndarray, half_size_px: int, detector) -> list[Tag]:
    """Tags searched only in square windows around expected centres (tracking known tags cheaply).

    Each window is searched separately; a tag seen by two overlapping windows is kept once.
    """
    check_color_image(color_bgr)
    h, w = color_bgr.shape[:2]
    found: list[Tag] = []
    for u, v in np.asarray(centers_px, dtype=np.float64).reshape(-1, 2):
        if not (np.isfinite(u) and np.isfinite(v)):
            continue
        x0, y0 = max(0, int(u) - half_size_px), max(0, int(v) - half_size_px)
        x1, y1 = min(w, int(u) + half_size_px), min(h, int(v) + half_size_px)
        if x1 - x0 < 16 or y1 - y0 < 16:
            continue
        for tag in detect_tags(color_bgr[y0:y1, x0:x1], detector=detector):
            tag = tag.shifted(np.array([x0, y0], dtype=np.float64))
            if not any(t.id == tag.id and _same_instance(t.corners_px[:, None], tag.corners_px[:, None]) for t in found):
                found.append(tag)
    return sorted(found, key=lambda t: (t.id, round(float(t.center_px[1])), float(t.center_px[0])))
