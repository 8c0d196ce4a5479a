"""The board tags of the current calibration, one row each: id, where it is on the board (world, metres), where the
calibration puts it in the image, its reprojection error (the tag's four corners as detected when the calibration was
made against where the calibration projects them, RMS px) and its drift now (the newest frame's detection against the
projection; None when the tag is not seen now). Pure: calibration, detections and config in, rows out."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from armlab.vision.geometry import project_points


def _corners_by_id(tags: Sequence) -> dict[int, np.ndarray]:
    """{id: corners (4, 2) px} of the first detection of each id (Tag objects or their wire dicts)."""
    found: dict[int, np.ndarray] = {}
    for tag in tags or ():
        tag_id = int(tag["id"] if isinstance(tag, dict) else tag.id)
        corners = tag["corners_px"] if isinstance(tag, dict) else tag.corners_px
        found.setdefault(tag_id, np.asarray(corners, float).reshape(4, 2))
    return found


def board_tag_rows(calibration: Any, calibration_tags: Sequence, live_tags: Sequence, perception_config: Any) -> list[dict]:
    """One row per board tag of the workcell, by id (see the module's doc); calibration None: no projection."""
    board = perception_config.tags.board_tags
    at_calibration, now = _corners_by_id(calibration_tags), _corners_by_id(live_tags)
    used = set(getattr(calibration, "tag_ids", ()) or ())
    rows = []
    for tag_id in sorted(board):
        corners_m = perception_config.board_tag_corners_m(tag_id)
        centre_m = corners_m.mean(axis=0)
        row = {"id": int(tag_id), "position_m": [float(v) for v in centre_m], "size_m": float(perception_config.tags.board_tag_size_m),
               "used_in_calibration": tag_id in used, "projected_px": None, "reprojection_error_px": None,
               "seen_now": tag_id in now, "drift_px": None}
        if calibration is not None:
            projected = project_points(calibration.T_world_camera, calibration.K, calibration.dist, corners_m)
            row["projected_px"] = [float(v) for v in projected.mean(axis=0).round(2)]
            if tag_id in at_calibration:
                error = np.sqrt(np.mean(np.sum((at_calibration[tag_id] - projected) ** 2, axis=1)))
                row["reprojection_error_px"] = round(float(error), 3)
            if tag_id in now:
                row["drift_px"] = round(float(np.linalg.norm(now[tag_id].mean(axis=0) - projected.mean(axis=0))), 3)
        rows.append(row)
    return rows
