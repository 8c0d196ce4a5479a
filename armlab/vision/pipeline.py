"""One perception pass per frame for the live stream: board tags tracked near where the calibration
puts them (uncalibrated: near where the last whole-image search found them, searched anew every
UNCALIBRATED_FULL_SEARCH_EVERY frames or when one goes missing), the robot self-filter's mask (given the measured arm
joints), blocks outside that mask, and the overlay. Holds its detectors so a per-frame call builds
nothing."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from armlab.vision.blocks import Block, BlockGeometry, detect_blocks
from armlab.vision.calibration import Calibration
from armlab.vision.config import PerceptionConfig, is_apriltag_family
from armlab.vision.geometry import project_points
from armlab.vision.overlay import OverlayLayers, draw_overlay, grid_pixels
from armlab.vision.self_filter import RobotSelfFilter
from armlab.vision.tags import Tag, detect_tags, detect_tags_near, make_detector

# Uncalibrated, the tags are for the operator's view only (calibration searches its own frame): a whole-image search
# costs ~80 ms of CPU at 1280x720 and tracking the tags it found ~5 ms, so the whole image is searched on this many
# frames' first (1 s at the station's 5 Hz) and whenever a tracked tag is lost.
UNCALIBRATED_FULL_SEARCH_EVERY = 5


@dataclass(frozen=True)
class PerceptionResult:
    """tags, blocks and the overlay of one frame; robot_mask: the (H, W) bool pixels that belong to
    the robot (the self-filter's mask), None when the pass had no arm joints or no calibration."""

    tags: list[Tag]
    blocks: list[Block]
    overlay_bgr: np.ndarray | None
    robot_mask: np.ndarray | None = None


class PerceptionPipeline:
    """Reusable per-frame perception (not thread-safe: one per perception thread).

    arm_model: the armlab.kinematics ArmModel the self-filter needs for process(arm_joints_rad=...).
    """

    def __init__(self, cfg: PerceptionConfig, arm_model=None) -> None:
        self.cfg = cfg
        self.self_filter = RobotSelfFilter(arm_model, cfg.self_filter) if arm_model is not None else None
        self._board_detector = make_detector(cfg.tags.dictionary, cfg.tag_detection)
        self._tracking_detector = make_detector(cfg.tags.dictionary, cfg.tag_detection)
        if not is_apriltag_family(cfg.tags.dictionary):
            # ArUco tracking known tags in small windows: one threshold scale is enough and three times cheaper.
            params = self._tracking_detector.getDetectorParameters()
            params.adaptiveThreshWinSizeMin = params.adaptiveThreshWinSizeMax = 7
            self._tracking_detector.setDetectorParameters(params)
        self._block_detector = make_detector(cfg.tags.block_tag_dictionary, cfg.tag_detection)
        self._grid_m = cfg.board.grid_points_m()
        self._tag_ids = list(cfg.tags.board_tags)
        self._tag_centres_m = np.array([[x, y, 0.0] for x, y in cfg.tags.board_tags.values()])
        # Per-calibration constants, recomputed when another calibration object comes in.
        self._cal: Calibration | None = None
        self._tag_centres_px = np.empty((0, 2))
        self._grid_px: dict[tuple[int, int], np.ndarray] = {}
        self._untracked: list[Tag] = []  # uncalibrated: the tags of the last whole-image search, tracked since
        self._frames_since_full_search = 0
        self.whole_image_searches = 0  # uncalibrated whole-image tag searches so far
        self._block_geometry: BlockGeometry | None = None
        self.color_model = None  # an armlab.vision.colors ColorModel (the station's colour calibration); None: the config's

    def _use_calibration(self, cal: Calibration) -> None:
        if cal is not self._cal:
            self._cal = cal
            self._tag_centres_px = project_points(cal.T_world_camera, cal.K, cal.dist, self._tag_centres_m)
            self._grid_px = {}
            self._block_geometry = None

    def find_tags(self, color_bgr: np.ndarray, cal: Calibration | None) -> list[Tag]:
        """Board tags: searched in windows around their calibrated image positions, else everywhere."""
        if cal is None:
            return self._find_tags_uncalibrated(color_bgr)
        self._use_calibration(cal)
        centres = self._tag_centres_px
        tags = detect_tags_near(color_bgr, centres, 32, self._tracking_detector)
        found = {tag.id for tag in tags}
        missing = [c for tag_id, c in zip(self._tag_ids, centres) if tag_id not in found]
        if missing:  # hidden, moved or shaded: look harder, but only where the missing ones should be
            extra = detect_tags_near(color_bgr, np.array(missing), 48, self._board_detector)
            tags = sorted(tags + [tag for tag in extra if tag.id not in found], key=lambda tag: tag.id)
        return tags

    def _find_tags_uncalibrated(self, color_bgr: np.ndarray) -> list[Tag]:
        """The tags the last whole-image search found, tracked in windows around where they were; the whole image
        is searched again when one is lost, nothing was found, or UNCALIBRATED_FULL_SEARCH_EVERY frames passed."""
        self._frames_since_full_search += 1
        if self._untracked and self._frames_since_full_search < UNCALIBRATED_FULL_SEARCH_EVERY:
            centres = np.array([tag.center_px for tag in self._untracked])
            side_px = max(float(np.ptp(tag.corners_px, axis=0).max()) for tag in self._untracked)
            tracked = detect_tags_near(color_bgr, centres, max(48, int(1.5 * side_px)), self._board_detector)
            if len(tracked) >= len(self._untracked):
                self._untracked = tracked
                return tracked
        self._untracked = detect_tags(color_bgr, detector=self._board_detector)
        self._frames_since_full_search = 0
        self.whole_image_searches += 1
        return self._untracked

    def process(
        self, color_bgr: np.ndarray, depth_mm: np.ndarray | None, cal: Calibration | None,
        layers: OverlayLayers | None = OverlayLayers(),
        arm_joints_rad: np.ndarray | None = None,
        held_block_edge_m: float | None = None,
        frame_time_s: float | None = None,
    ) -> PerceptionResult:
        """Tags, blocks (needs depth and a calibration) and, unless layers is None, the overlay image.

        arm_joints_rad: the arm's measured joints (dof,) when the frame was taken. Given (and
        cfg.self_filter.enabled), pixels of the robot and of a block held between its fingers are
        ignored by block detection; None = no filter. held_block_edge_m: the held block's edge for
        the filter (None: the config's; 0: nothing held). Each block is stamped with frame_time_s
        (seen_time_s) and arm_joints_rad (seen_arm_joints_rad).
        ValueError if joints are given without an arm model, or are malformed.
        """
        tags = self.find_tags(color_bgr, cal)
        blocks = []
        robot_mask = robot_cells = None
        if arm_joints_rad is not None:
            if self.self_filter is None:
                raise ValueError("process: arm_joints_rad needs a PerceptionPipeline built with an arm_model")
            joints = tuple(float(v) for v in np.asarray(arm_joints_rad, dtype=float).ravel())
        if cal is not None and depth_mm is not None:
            self._use_calibration(cal)
            if self._block_geometry is None:
                self._block_geometry = BlockGeometry(cal, self.cfg)
            if arm_joints_rad is not None and self.cfg.self_filter.enabled:
                robot_mask, robot_cells = self.self_filter.mask_and_cells(depth_mm, cal, np.asarray(arm_joints_rad, dtype=float), held_block_edge_m)
            blocks = detect_blocks(
                color_bgr, depth_mm, cal, self.cfg, tag_detector=self._block_detector, geometry=self._block_geometry, ignore_mask=robot_mask,
                color_model=self.color_model, ignore_cells=robot_cells,
            )
            if frame_time_s is not None or arm_joints_rad is not None:
                seen_joints = joints if arm_joints_rad is not None else None
                blocks = [replace(b, seen_time_s=frame_time_s, seen_arm_joints_rad=seen_joints) for b in blocks]
        overlay = None
        if layers is not None:
            grid_px = None
            if cal is not None and layers.grid:
                size = color_bgr.shape[:2]
                grid_px = self._grid_px.get(size)
                if grid_px is None:
                    grid_px = self._grid_px[size] = grid_pixels(cal, self._grid_m, size)
            camera = None if cal is None or self._block_geometry is None else self._block_geometry.camera  # the calibration's
            overlay = draw_overlay(color_bgr, tags=tags, blocks=blocks, calibration=cal, layers=layers, grid_points_m=self._grid_m, grid_px=grid_px,
                                   camera=camera)
        return PerceptionResult(tags, blocks, overlay, robot_mask)
