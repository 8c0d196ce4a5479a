"""Is the calibration still right? What the station does with the perception thread's camera-moved
check (armlab.vision.drift): a calibration restored at start is held back until the board tags confirm
it (status calibration_state 'checking' -> 'trusted', or 'rejected' with the camera-moved warning),
the calibration in use is 'untrusted' while the check does not confirm it (the camera moved, or too few
board tags are where it puts them): grabs, drops and autonomous jobs are then refused with the reason
until the check confirms it again or the operator recalibrates (issue 18 item 3); and, when the operator
enabled it, a calibration the camera has moved away from is redone from the
board tags while the station is idle (never while a job runs, the arm moves or the latch is set; never
with too few board tags in view: the warning then stays).

Owned by core.Station (station.trust): CalibrationTrust holds the calibration in use and the restored candidate
under its own lock, so a candidate is judged and installed in one step; what it needs of the station comes in as
callables (the perception config, publishing, whether the station is idle, starting the self-recalibration job).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from armlab.errors import CalibrationUntrusted, InvalidInput
from armlab.station.jobs import JobContext
from armlab.station.perception import Perception
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
    """The calibration in use and its info, a restored candidate being checked, the check's doubt about the one in use,
    and the operator's self-recalibration setting (see the module doc).

    events: the station's EventLog; publish(info): the calibration's wire summary, each time one is installed;
    get_perception_config(): armlab.vision's config (board tags, drift threshold); config: the StationConfig
    (self_recalibrate default, its minimum board tags and retry); why_not_idle(): None when the station may
    recalibrate itself now, else why not; start_self_recalibration(): starts that job (raises when it cannot);
    check_control(source, command): the lease's check (NotController naming the holder)."""

    def __init__(
        self,
        events: Any,
        publish: Callable[[dict], None],
        get_perception_config: Callable[[], Any],
        config: Any,
        why_not_idle: Callable[[], str | None] = lambda: "no station",
        start_self_recalibration: Callable[[], None] = lambda: None,
        check_control: Callable[[str | None, str], None] = lambda source, command: None,
    ) -> None:
        self._events, self._publish, self._perception_config, self._config = events, publish, get_perception_config, config
        self._why_not_idle, self._start_self_recalibration, self._check_control = why_not_idle, start_self_recalibration, check_control
        self._lock = threading.RLock()
        self._calibration: Any = None  # the calibration in use (armlab.vision Calibration)
        self._info: dict | None = None  # its wire summary
        self._restored: Any = None  # a calibration loaded at start, not used until the board tags confirm it
        self._restored_info: dict | None = None
        self._restored_rejected = False
        self._restored_at_s = math.inf  # when it was restored (wall time): only frames captured after that vouch for it
        self._doubt: tuple[Any, str] | None = None  # (calibration, the check's warning) from the last check of the one in use
        self._self_recalibrate: bool | None = None  # the operator's setting (None: the config's)
        self._self_recal_tried_s = -math.inf
        self._self_recal_waiting: str | None = None  # why self-recalibration waits (logged once per reason)

    # In use ------------------------------------------------------------------------------------

    @property
    def calibration(self) -> Any:
        with self._lock:
            return self._calibration

    @property
    def info(self) -> dict:
        """The wire summary of the calibration in use ({"calibrated": False} without one)."""
        with self._lock:
            return dict(self._info) if self._info else {"calibrated": False}

    @property
    def checked(self) -> bool:
        """True when there is a calibration for the camera-moved check to judge (in use, or restored)."""
        with self._lock:
            return self._calibration is not None or self._restored is not None

    def install(self, calibration: Any, info: dict) -> None:
        """Use `calibration` (with its wire summary) from now on and publish it; a restored candidate still being
        checked is superseded."""
        with self._lock:
            self._calibration = calibration
            self._info = {"calibrated": True, **info}
            self._restored = None
            published = dict(self._info)
        self._publish(published)

    def to_check(self) -> Any:
        """The calibration the camera-moved check compares with: the one in use, else the restored one."""
        with self._lock:
            return self._calibration if self._calibration is not None else self._restored

    # Restore -----------------------------------------------------------------------------------

    def restore(self, data: dict | None, one_look: Callable[[], Sequence] | None = None) -> None:
        """A saved calibration (the store's {"calibration", "info"}) becomes the candidate, checked against the board tags
        before use. one_look() (a station with no perception thread): the board tags seen now, judged at once."""
        if data is None:
            return
        try:
            calibration = Calibration.from_dict(data["calibration"])
            info = dict(data["info"])
        except (KeyError, ValueError, TypeError) as error:
            self._events.add("warn", f"saved calibration not restored: {error}")
            return
        self.restore_candidate(calibration, info, time.time())
        self._events.add("info", "saved calibration restored, checking it against the board tags before use")
        if one_look is None:
            return
        config = self._perception_config()
        tags = tuple(one_look())
        drift_px = board_tag_drift_px(list(tags), calibration, config)
        over = drift_px is not None and drift_px > config.calibration.drift_threshold_px
        if drift_px is None:  # nothing later will check it: not trusted
            warning = "cannot be checked: fewer than two board tags in view: recalibrate"
        else:
            warning = f"{CAMERA_MOVED} (board tags {drift_px:.1f} px from where it puts them)" if over else None
        self.on_check(calibration, drift_px, warning, Perception(tags=tags, capture_time_s=time.time()), final=True)

    def restore_candidate(self, calibration: Any, info: dict, restored_at_s: float) -> None:
        """`calibration` is the candidate from now on (restored at wall time restored_at_s); nothing is in use until it
        is trusted."""
        with self._lock:
            self._restored, self._restored_info, self._restored_rejected = calibration, info, False
            self._restored_at_s = restored_at_s

    @property
    def state(self) -> str | None:
        """'trusted' (in use), 'untrusted' (in use, but the camera-moved check does not confirm it: see doubt),
        'checking' (restored, being checked), 'rejected' (restored, the camera moved since: not used) or None."""
        with self._lock:
            if self._calibration is not None:
                return UNTRUSTED if self._doubt_locked() is not None else TRUSTED
            if self._restored is not None:
                return REJECTED if self._restored_rejected else CHECKING
            return None

    @property
    def doubt(self) -> str | None:
        """Why the calibration in use is not trusted (the camera-moved check's warning), else None."""
        with self._lock:
            return self._doubt_locked()

    def _doubt_locked(self) -> str | None:
        doubt = self._doubt
        return doubt[1] if doubt is not None and self._calibration is not None and doubt[0] is self._calibration else None

    def require_trusted(self, what: str) -> None:
        """CalibrationUntrusted (the reason) while the calibration in use is not trusted; no calibration is
        the caller's matter (NotCalibrated where one is needed)."""
        reason = self.doubt
        if reason is not None:
            raise CalibrationUntrusted(
                f"{what} refused: the calibration is not trusted ({reason}); recalibrate, or wait until the board tags confirm it"
            )

    # The perception thread's check ---------------------------------------------------------------

    def on_check(self, calibration: Any, drift_px: float | None, warning: str | None, perception: Any, final: bool = False) -> None:
        """After each camera-moved check of `calibration` on `perception`'s frame (the perception thread).
        final: no later check will come (a station with no perception thread): a candidate too few tags confirm is rejected."""
        with self._lock:
            judging_restored = calibration is not None and calibration is self._restored and not self._restored_rejected
            info = self._restored_info
            if judging_restored and perception.capture_time_s < self._restored_at_s:
                return  # a frame from before the restore (a camera's buffered frame) proves nothing
        if judging_restored:
            threshold_px = self._perception_config().calibration.drift_threshold_px
            # Moved: rejected. Too few tags: not used, checked again later (unless final: rejected).
            if warning is not None and (drift_px is not None or final):
                with self._lock:
                    self._restored_rejected = True
                self._events.add("warn", f"restored calibration not trusted: {warning}")
            elif drift_px is not None and drift_px <= threshold_px and self._trust_restored(calibration, {**(info or {}), "restored": True}):
                self._events.add("info", f"restored calibration trusted: the board tags are {drift_px:.2f} px from where it puts them")
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
            self._events.add("warn", f"calibration not trusted: {warning}; grabs, drops and jobs are refused until "
                                     "the board tags confirm it or it is redone")
        elif warning is None and before is not None:
            self._events.add("info", "calibration trusted again: the board tags confirm the camera")

    def _trust_restored(self, calibration: Any, info: dict) -> bool:
        """Install the restored `calibration` if it is still the candidate (checked and installed under one
        lock: a calibration the operator installed meanwhile is kept). False when superseded."""
        with self._lock:
            if calibration is not self._restored or self._restored_rejected:
                return False
            self.install(calibration, info)  # the lock is re-entrant; install clears the candidate
        return True

    # Self-recalibration --------------------------------------------------------------------------

    @property
    def self_recalibrate(self) -> bool:
        """Whether the station recalibrates itself when idle once the camera moved (the operator's setting)."""
        with self._lock:
            return self._config.self_recalibrate if self._self_recalibrate is None else self._self_recalibrate

    def set_self_recalibrate(self, enabled: bool, source: str | None = None) -> bool:
        """The operator's setting (InvalidInput unless a bool; the lease holder's, like any command that changes the
        station); the event log says when it changes. Returns it."""
        if not isinstance(enabled, bool):
            raise InvalidInput(f"self_recalibrate must be true or false, got {enabled!r}")
        self._check_control(source, "calibrate")
        with self._lock:
            changed = enabled != self.self_recalibrate
            self._self_recalibrate = enabled
        if changed:
            who = f" by '{source}'" if source else ""
            self._events.add("info", f"self-recalibration when idle turned {'on' if enabled else 'off'}{who}")
        return enabled

    def _self_recalibrate_if_idle(self, tags: Sequence) -> None:
        board = self._perception_config().tags.board_tags
        seen = sorted({tag.id for tag in tags if tag.id in board})
        least = min(self._config.self_recalibrate_min_board_tags, len(board))
        why_not = self._why_not_idle()
        if why_not is None and len(seen) < least:
            why_not = f"only {len(seen)} of the {len(board)} board tags are in view ({least} needed)"
        if why_not is None and time.monotonic() - self._self_recal_tried_s < self._config.self_recalibrate_retry_s:
            why_not = "it was tried moments ago"
        if why_not is not None:
            if why_not != self._self_recal_waiting:
                self._self_recal_waiting = why_not
                log.info("camera moved; self-recalibration waits: %s", why_not)
                if "board tags" in why_not:
                    self._events.add("warn", f"camera moved; not recalibrating itself: {why_not}")
            return
        self._self_recal_waiting = None
        self._self_recal_tried_s = time.monotonic()
        try:
            self._start_self_recalibration()
        except Exception as error:  # noqa: BLE001 - a command raced in: the next check tries again
            log.info("self-recalibration not started: %s", error)


def self_recalibration_job(station: Any, ctx: JobContext) -> dict:
    """The self-recalibration job: a frame taken now, the arm still, a calibration from the board tags saved and installed."""
    before = station.trust.to_check()
    ctx.progress(0.2, "finding the board tags")
    frame = station.frame_after(time.time())
    if station.arm_moving() is not None:
        raise RuntimeError("the arm moved during self-recalibration: abandoned, the old calibration kept")
    calibration, info = calibrate_from_board_tags(station, frame)
    ctx.check()
    info = {**info, "method": "self"}
    station.store.save_calibration({"calibration": calibration.to_dict(), "info": info})
    station.set_calibration(calibration, info)
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
