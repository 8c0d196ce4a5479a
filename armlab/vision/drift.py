"""Does the camera still sit where its calibration says? The board tags' detected image centres
against the calibration's projection of their world centres: a bumped mount shifts them all (1 deg
or 5 mm at 1 m: 5-16 px), an arm or hand over one tag moves only that one or hides it. Fewer than two board
tags where the calibration puts them is no verdict of "fine": a large knock moves them all out of where
the check looks, so that too warns (CAMERA_UNCONFIRMED) once it lasts, until a check confirms the camera."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.vision.calibration import Calibration
from armlab.vision.config import CalibrationLimits, PerceptionConfig
from armlab.vision.geometry import project_points
from armlab.vision.tags import Tag

CAMERA_MOVED = "camera moved: recalibrate"
CAMERA_UNCONFIRMED = "camera not confirmed"
MIN_CONFIRMING_TAGS = 2  # board tags needed to judge the camera (board_tag_drift_px)


def board_tag_drift_px(tags: list[Tag], cal: Calibration, cfg: PerceptionConfig) -> float | None:
    """Median over the board tags found of |detected centre - projected centre| (px); None when fewer
    than two board tags are in view (nothing to judge by). The instance nearest its expected place
    stands for each id."""
    ids = [tag_id for tag_id in cfg.tags.board_tags if any(t.id == tag_id for t in tags)]
    if len(ids) < MIN_CONFIRMING_TAGS:
        return None
    world = np.array([[*cfg.tags.board_tags[tag_id], 0.0] for tag_id in ids])
    expected = project_points(cal.T_world_camera, cal.K, cal.dist, world)
    drifts = [min(float(np.linalg.norm(t.center_px - e)) for t in tags if t.id == tag_id) for tag_id, e in zip(ids, expected)]
    return float(np.median(drifts))


@dataclass
class DriftMonitor:
    """Checks the calibration in use at most every period_s (by the caller's clock) and keeps a
    warning once the drift stayed above threshold_px for confirm_checks checks in a row (CAMERA_MOVED;
    only a new calibration, another object, clears it), or once fewer than two board tags were found for
    confirm_checks checks in a row (CAMERA_UNCONFIRMED; a check that confirms the camera clears it too).
    Not thread-safe: one per perception thread."""

    limits: CalibrationLimits
    warning: str | None = None
    last_drift_px: float | None = None
    checked_now: bool = False  # the last update() made a check (else it returned the standing verdict)
    _last_check_s: float | None = None
    _over: int = 0
    _unconfirmed: int = 0
    _moved: bool = False  # the warning is CAMERA_MOVED (kept until a new calibration)
    _calibration: object = None

    def update(self, now_s: float, tags: list[Tag], cal: Calibration | None, cfg: PerceptionConfig) -> str | None:
        """The current warning (None: none) after looking at this frame's tags if a check is due."""
        self.checked_now = False
        if cal is None:
            self.warning, self._calibration, self._over, self._unconfirmed, self._moved = None, None, 0, 0, False
            return None
        if cal is not self._calibration:
            self.warning, self._calibration, self._over, self._unconfirmed, self._moved = None, cal, 0, 0, False
            self._last_check_s = None
        if self._last_check_s is not None and now_s - self._last_check_s < self.limits.drift_check_period_s - 1e-3:
            return self.warning
        self._last_check_s = now_s
        self.checked_now = True
        drift = board_tag_drift_px(tags, cal, cfg)
        self.last_drift_px = drift
        if drift is None:
            self._unconfirmed += 1
            if self._unconfirmed >= self.limits.drift_confirm_checks and not self._moved:
                board = cfg.tags.board_tags
                seen = len({t.id for t in tags if t.id in board})
                self.warning = (
                    f"{CAMERA_UNCONFIRMED}: only {seen} of the {len(board)} board tags where the calibration puts them "
                    f"({MIN_CONFIRMING_TAGS} needed): recalibrate, or uncover the board tags"
                )
            return self.warning
        self._unconfirmed = 0
        if not self._moved:
            self.warning = None  # confirmed (or judged below): an unconfirmed warning ends here
        self._over = self._over + 1 if drift > self.limits.drift_threshold_px else 0
        if self._over >= self.limits.drift_confirm_checks:
            self._moved = True
            self.warning = f"{CAMERA_MOVED} (board tags {drift:.1f} px from where the calibration puts them)"
        return self.warning

