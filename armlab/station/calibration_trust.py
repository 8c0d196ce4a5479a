"""Is the calibration still right? What the station does with the perception thread's camera-moved
check (armlab.vision.drift): a calibration restored at start is held back until the board tags confirm
it (status calibration_state 'checking' -> 'trusted', or 'rejected' with the camera-moved warning),
the calibration in use is 'untrusted' while the check does not confirm it (the camera moved, or too few
board tags are where it puts them): grabs, drops and autonomous jobs are then refused with the reason
until the check confirms it again or the operator recalibrates (issue 18 item 3); and, when the operator
enabled it, a calibration the camera has moved away from is redone from the
board tags while the station is idle (never while a job runs, the arm moves or the latch is set; never
with too few board tags in view: the warning then stays).

A mixin of core.Station.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from armlab.errors import CalibrationUntrusted, InvalidInput
from armlab.station.jobs import JobContext
from armlab.station.perception import Perception
from armlab.station.states import State
from armlab.station.telemetry import tag_to_dict
from armlab.vision import Calibration, calibrate_extrinsics, detect_tags
from armlab.vision.calibration import project_grid
from armlab.vision.drift import CAMERA_MOVED, board_tag_drift_px

log = logging.getLogger(__name__)

CHECKING, TRUSTED, UNTRUSTED, REJECTED = "checking", "trusted", "untrusted", "rejected"
SELF_RECALIBRATE_JOB = "self-recalibrate"


def calibration_summary(calibration: Any, tags: Sequence, grid_px: np.ndarray) -> dict:
    """The wire dict of GET /api/calibration (without 'calibrated')."""
    depth_error = calibration.depth_check_error_m
    return {
        "reprojection_error_px": float(calibration.reprojection_error_px),
        "camera_position_m": [float(x) for x in calibration.camera_position_m],
        "T_world_camera": np.asarray(calibration.T_world_camera, dtype=float).tolist(),
        "K": np.asarray(calibration.K, dtype=float).tolist(),
        "dist": np.asarray(calibration.dist, dtype=float).ravel().tolist(),
        "width": int(calibration.width),
        "height": int(calibration.height),
        "depth_check_error_m": None if depth_error is None else float(depth_error),
        # The depth camera against the tags' plane (vision.board_plane), applied to every depth -> world.
        "depth_offset_m": getattr(calibration, "depth_offset_m", None),
        "depth_tilt_deg": getattr(calibration, "depth_tilt_deg", None),
        "depth_model": None if getattr(calibration, "depth_correction", None) is None else calibration.depth_correction.describe(),
        "grid_points_px": np.asarray(grid_px, dtype=float).round(2).tolist(),
        "tags": [tag_to_dict(tag) for tag in tags],
        "time": time.time(),
    }


def calibrate_from_board_tags(station: Any, frame: Any) -> tuple[Any, dict]:
    """A new Calibration from the board tags of `frame` (cross-checked with its depth) and its wire summary;
    CalibrationError saying why when the tags cannot give one."""
    intrinsics = station.intrinsics.current()  # measured for this camera, else its own (as the operator's calibration)
    tags = detect_tags(frame.color_bgr, station.perception_config)
    calibration = calibrate_extrinsics(frame.color_bgr, intrinsics, station.perception_config, frame.depth_mm, tags=tags)
    return calibration, calibration_summary(calibration, tags, project_grid(calibration, station.perception_config))


class CalibrationTrust:
    """Restored calibrations checked before use; self-recalibration when idle (see the module doc)."""

    _restored: Any = None  # a calibration loaded at start, not used until the board tags confirm it
    _restored_info: dict | None = None
    _restored_rejected = False
    _restored_at_s = math.inf  # when it was restored: only frames captured after that can vouch for it
    _self_recalibrate: bool | None = None  # the operator's setting (None: the config's)
    _self_recal_tried_s = -math.inf
    _self_recal_waiting: str | None = None  # why self-recalibration waits (logged once per reason)
    _doubt: tuple[Any, str] | None = None  # (calibration, the check's warning) from the last check of the one in use

    # Restore -----------------------------------------------------------------------------------

    def _restore_calibration(self) -> None:
        """Load the newest saved calibration as a candidate: checked against the board tags before use."""
        data = self.store.latest_calibration()
        if data is None:
            return
        try:
            calibration = Calibration.from_dict(data["calibration"])
            info = dict(data["info"])
        except (KeyError, ValueError, TypeError) as error:
            self.events.add("warn", f"saved calibration not restored: {error}")
            return
        with self._lock:
            self._restored, self._restored_info, self._restored_rejected = calibration, info, False
            self._restored_at_s = time.time()
        self.events.add("info", "saved calibration restored, checking it against the board tags before use")
        if self.synchronous:  # no perception thread: one look now
            frame = self.sim.capture_next_frame()
            tags = tuple(detect_tags(frame.color_bgr, self.perception_config))
            drift_px = board_tag_drift_px(list(tags), calibration, self.perception_config)
            over = drift_px is not None and drift_px > self.perception_config.calibration.drift_threshold_px
            if drift_px is None:  # nothing later will check it: not trusted
                warning = "cannot be checked: fewer than two board tags in view: recalibrate"
            else:
                warning = f"{CAMERA_MOVED} (board tags {drift_px:.1f} px from where it puts them)" if over else None
            self._on_calibration_check(calibration, drift_px, warning, Perception(tags=tags, capture_time_s=time.time()))

    @property
    def calibration_state(self) -> str | None:
        """'trusted' (in use), 'untrusted' (in use, but the camera-moved check does not confirm it: see
        calibration_doubt), 'checking' (restored, being checked), 'rejected' (restored, the camera moved
        since: not used) or None (no calibration)."""
        with self._lock:
            if self._calibration is not None:
                return UNTRUSTED if self._doubt_locked() is not None else TRUSTED
            if self._restored is not None:
                return REJECTED if self._restored_rejected else CHECKING
            return None

    @property
    def calibration_doubt(self) -> str | None:
        """Why the calibration in use is not trusted (the camera-moved check's warning), else None."""
        with self._lock:
            return self._doubt_locked()

    def _doubt_locked(self) -> str | None:
        doubt = self._doubt
        return doubt[1] if doubt is not None and self._calibration is not None and doubt[0] is self._calibration else None

    def require_trusted_calibration(self, what: str) -> None:
        """CalibrationUntrusted (the reason) while the calibration in use is not trusted; no calibration is
        the caller's matter (NotCalibrated where one is needed)."""
        reason = self.calibration_doubt
        if reason is not None:
            raise CalibrationUntrusted(
                f"{what} refused: the calibration is not trusted ({reason}); recalibrate, or wait until the board tags confirm it"
            )

    def _calibration_to_check(self) -> Any:
        """The calibration the camera-moved check compares with: the one in use, else the restored one."""
        with self._lock:
            return self._calibration if self._calibration is not None else self._restored

    # The perception thread's check ---------------------------------------------------------------

    def _on_calibration_check(self, calibration: Any, drift_px: float | None, warning: str | None, perception: Any) -> None:
        """Called by the perception thread after each camera-moved check of `calibration` on `perception`'s frame."""
        with self._lock:
            judging_restored = calibration is not None and calibration is self._restored and not self._restored_rejected
            info = self._restored_info
            if judging_restored and perception.capture_time_s < self._restored_at_s:
                return  # a frame from before the restore (a camera's buffered frame) proves nothing
        if judging_restored:
            threshold_px = self.perception_config.calibration.drift_threshold_px
            # Moved: rejected. Too few tags: not used, checked again later (synchronous mode looks only once: rejected).
            if warning is not None and (drift_px is not None or self.synchronous):
                with self._lock:
                    self._restored_rejected = True
                self.events.add("warn", f"restored calibration not trusted: {warning}")
            elif drift_px is not None and drift_px <= threshold_px and self._trust_restored(calibration, {**(info or {}), "restored": True}):
                self.events.add("info", f"restored calibration trusted: the board tags are {drift_px:.2f} px from where it puts them")
            return
        self._note_doubt(calibration, warning)
        if warning is not None and self.self_recalibrate:
            self._self_recalibrate_if_idle(perception.tags)

    def _note_doubt(self, calibration: Any, warning: str | None) -> None:
        """Record the check's verdict on the calibration in use; the event log says when trust changes."""
        with self._lock:
            if calibration is None or calibration is not self._calibration:
                return
            before = self._doubt_locked()
            self._doubt = (calibration, warning) if warning is not None else None
        if warning is not None and before is None:
            self.events.add("warn", f"calibration not trusted: {warning}; grabs, drops and jobs are refused until "
                                    "the board tags confirm it or it is redone")
        elif warning is None and before is not None:
            self.events.add("info", "calibration trusted again: the board tags confirm the camera")

    def _trust_restored(self, calibration: Any, info: dict) -> bool:
        """Install the restored `calibration` if it is still the candidate (checked and installed under one
        lock: a calibration the operator installed meanwhile is kept). False when superseded."""
        with self._lock:
            if calibration is not self._restored or self._restored_rejected:
                return False
            self.set_calibration(calibration, info)  # the lock is re-entrant; set_calibration clears _restored
        return True

    # Self-recalibration --------------------------------------------------------------------------

    @property
    def self_recalibrate(self) -> bool:
        """Whether the station recalibrates itself when idle once the camera moved (the operator's setting)."""
        with self._lock:
            return self.config.self_recalibrate if self._self_recalibrate is None else self._self_recalibrate

    def set_self_recalibrate(self, enabled: bool, source: str | None = None) -> bool:
        """The operator's setting (the lease holder's, like any command that changes the station)."""
        if not isinstance(enabled, bool):
            raise InvalidInput(f"self_recalibrate must be true or false, got {enabled!r}")
        with self._lock:
            if source is not None and self._lease.holder not in (None, source):
                self._lease.require(source, "calibrate")  # NotController naming the holder
            changed = enabled != (self.config.self_recalibrate if self._self_recalibrate is None else self._self_recalibrate)
            self._self_recalibrate = enabled
        if changed:
            who = f" by '{source}'" if source else ""
            self.events.add("info", f"self-recalibration when idle turned {'on' if enabled else 'off'}{who}")
        return enabled

    def _idle_for_self_recalibration(self) -> str | None:
        """None when the station may recalibrate itself now, else why not."""
        with self._lock:
            if self.latch.is_set() or self._closing.is_set() or self._state is not State.IDLE:
                return f"the station is {self._effective_state().value}"
            if self._job is not None or self._jog is not None or self._recorder is not None:
                return "a job or a jog is running"
            last_motion_end_s = self._motions[-1][0] if self._motions else -math.inf
        return self._arm_moving(last_motion_end_s)

    def _arm_moving(self, last_motion_end_s: float | None = None) -> str | None:
        """'the arm is moving' (a commanded motion not yet over, or joints turning), else None."""
        if last_motion_end_s is None:
            with self._lock:
                last_motion_end_s = self._motions[-1][0] if self._motions else -math.inf
        if time.time() < last_motion_end_s:
            return "the arm is moving"
        try:
            joint_state = self.arm.read_joint_state()
            speed = np.abs(np.asarray(joint_state.velocity_rad_s, dtype=float))
            if self.arm.is_moving() or (speed.size and speed.max() > self.config.moving_speed_rad_s):
                return "the arm is moving"
        except (ConnectionError, TimeoutError, OSError) as error:
            return f"the arm cannot be read ({error})"
        return None

    def _self_recalibrate_if_idle(self, tags: Sequence) -> None:
        board = self.perception_config.tags.board_tags
        seen = sorted({tag.id for tag in tags if tag.id in board})
        least = min(self.config.self_recalibrate_min_board_tags, len(board))
        why_not = self._idle_for_self_recalibration()
        if why_not is None and len(seen) < least:
            why_not = f"only {len(seen)} of the {len(board)} board tags are in view ({least} needed)"
        if why_not is None and time.monotonic() - self._self_recal_tried_s < self.config.self_recalibrate_retry_s:
            why_not = "it was tried moments ago"
        if why_not is not None:
            if why_not != self._self_recal_waiting:
                self._self_recal_waiting = why_not
                log.info("camera moved; self-recalibration waits: %s", why_not)
                if "board tags" in why_not:
                    self.events.add("warn", f"camera moved; not recalibrating itself: {why_not}")
            return
        self._self_recal_waiting = None
        self._self_recal_tried_s = time.monotonic()
        try:
            self.start_job("calibrate", SELF_RECALIBRATE_JOB, self._self_recalibration_job,
                           detail="camera moved: recalibrating from the board tags")
        except Exception as error:  # noqa: BLE001 - a command raced in: the next check tries again
            log.info("self-recalibration not started: %s", error)

    def _self_recalibration_job(self, ctx: JobContext) -> dict:
        before = self._calibration_to_check()
        ctx.progress(0.2, "finding the board tags")
        frame = self.frame_after(time.time())
        if self._arm_moving() is not None:
            raise RuntimeError("the arm moved during self-recalibration: abandoned, the old calibration kept")
        calibration, info = calibrate_from_board_tags(self, frame)
        ctx.check()
        info = {**info, "method": "self"}
        self.store.save_calibration({"calibration": calibration.to_dict(), "info": info})
        self.set_calibration(calibration, info)
        moved_mm = None
        if before is not None:
            moved_mm = float(np.linalg.norm(calibration.camera_position_m - before.camera_position_m) * 1000.0)
        where = ", ".join(f"{v * 1000:.0f}" for v in calibration.camera_position_m)
        message = (f"recalibrated itself from the board tags: camera at ({where}) mm"
                   + (f", {moved_mm:.1f} mm from the old calibration" if moved_mm is not None else "")
                   + f"; reprojection error {calibration.reprojection_error_px:.2f} px")
        ctx.job.update(message=message)
        return {"reprojection_error_px": float(calibration.reprojection_error_px), "camera_position_m": info["camera_position_m"],
                "moved_mm": moved_mm}
