"""The camera intrinsics the station uses, and the guided checkerboard capture that measures them.

In use: the newest intrinsics measured here for this camera (stored in SQLite under the camera's key:
its name/serial and image size), else the device's own (factory: a RealSense reports them; the
simulation's come from its config). A capture session keeps checked views of the printed checkerboard
(config/intrinsics.yaml) taken from the newest frame; solve computes K and distortion with one error
per view; accept stores them and puts them in use. Any refusal (board not found, blurry, duplicate,
too few views, error too high) raises IntrinsicsRejected and leaves the intrinsics in use unchanged.

The extrinsic calibration is not changed by accepting: it was solved with the intrinsics of its time and
stays self-consistent (pixel <-> world works as before), but it is reported as outdated
(`calibration_outdated`) until the camera is calibrated again, which then uses the new intrinsics.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from armlab.devices.camera import Camera, Intrinsics
from armlab.errors import InvalidInput
from armlab.vision.intrinsics_capture import (
    IntrinsicsCapture,
    IntrinsicsConfig,
    IntrinsicsRejected,
    load_intrinsics_config,
)

OUTDATED_NOTE = "the camera calibration was solved with other intrinsics: calibrate again to use these"


def camera_key(camera: Camera, intrinsics: Intrinsics) -> str:
    """The camera's identity for stored intrinsics: its name/serial and image size, e.g. 'SimCamera(sim_l515) 1280x720'."""
    return f"{camera} {intrinsics.width}x{intrinsics.height}"


def intrinsics_dict(intrinsics: Intrinsics) -> dict:
    return {"width": intrinsics.width, "height": intrinsics.height, "fx": intrinsics.fx, "fy": intrinsics.fy,
            "cx": intrinsics.cx, "cy": intrinsics.cy, "dist": list(intrinsics.dist)}


def intrinsics_from_dict(data: dict) -> Intrinsics:
    values = Intrinsics(int(data["width"]), int(data["height"]), float(data["fx"]), float(data["fy"]), float(data["cx"]),
                        float(data["cy"]), tuple(float(x) for x in data["dist"]))
    numbers = [values.fx, values.fy, values.cx, values.cy, *values.dist]
    if not (all(np.isfinite(numbers)) and values.fx > 0 and values.fy > 0 and values.width > 0 and values.height > 0):
        raise InvalidInput("stored intrinsics are not finite and positive")
    return values


class CameraIntrinsics:
    """Owned by the Station (station.intrinsics). Thread-safe; never touches the arm."""

    def __init__(self, camera: Camera, store: Any, events: Any, config: IntrinsicsConfig | None = None) -> None:
        self._camera, self._store, self._events = camera, store, events
        self._config = config
        self._lock = threading.Lock()
        self._measured: Intrinsics | None = None
        self._measured_info: dict = {}
        self._session: IntrinsicsCapture | None = None
        self._solution: Any = None  # the last good solve of the session (IntrinsicCalibration), until accepted

    @property
    def config(self) -> IntrinsicsConfig:
        if self._config is None:
            self._config = load_intrinsics_config()
        return self._config

    def factory(self) -> Intrinsics:
        return self._camera.intrinsics

    def key(self) -> str:
        return camera_key(self._camera, self.factory())

    def current(self) -> Intrinsics:
        """The intrinsics in use: measured for this camera, else the device's own."""
        with self._lock:
            measured = self._measured
        factory = self.factory()
        if measured is not None and (measured.width, measured.height) == (factory.width, factory.height):
            return measured
        return factory

    def restore(self) -> None:
        """At start: the newest stored intrinsics of this camera, if any (a damaged row: a warning, factory kept)."""
        key = self.key()
        data = self._store.latest_intrinsics(key)
        if data is None:
            return
        try:
            measured = intrinsics_from_dict(data["intrinsics"])
        except (KeyError, ValueError, TypeError) as error:
            self._events.add("warn", f"stored intrinsics of {key} not used ({error}): the camera's own are in use")
            return
        with self._lock:
            self._measured = measured
            self._measured_info = {key: data[key] for key in ("rms_px", "views", "created_s") if key in data}
        self._events.add("info", f"intrinsics of {key} restored (measured, RMS {data.get('rms_px', float('nan')):.3f} px)")

    def info(self, calibration: Any = None) -> dict:
        """GET /api/intrinsics: what is in use, where it comes from, the factory values, the session."""
        current, factory = self.current(), self.factory()
        with self._lock:
            measured_info = dict(self._measured_info) if current is self._measured else {}
            session = self._session_dict()
        outdated = calibration is not None and not np.allclose(np.asarray(calibration.K), current.K, atol=1e-6)
        return {"camera": self.key(), "source": "measured" if measured_info else "factory", "intrinsics": intrinsics_dict(current),
                "factory": intrinsics_dict(factory), **measured_info, "calibration_outdated": bool(outdated),
                "note": OUTDATED_NOTE if outdated else None, "session": session}

    # The capture session -------------------------------------------------------------------------

    def start_session(self) -> dict:
        factory = self.factory()
        with self._lock:
            self._session = IntrinsicsCapture(self.config, (factory.width, factory.height))
            self._solution = None
            return self._session_dict()

    def _require_session(self) -> IntrinsicsCapture:
        if self._session is None:
            raise IntrinsicsRejected("no_session", "no intrinsics capture is running: start one first")
        return self._session

    def capture(self, color_bgr: np.ndarray) -> dict:
        """Check and keep one view (IntrinsicsRejected saying why not); returns the session."""
        with self._lock:
            session = self._require_session()
        view = session.measure(color_bgr)  # the slow part (finding the board), outside the lock that GET /api/intrinsics needs
        with self._lock:
            if self._session is not session:
                raise IntrinsicsRejected("no_session", "the capture was cancelled or restarted while this view was measured")
            session.keep(view)
            self._solution = None
            return self._session_dict()

    def delete_view(self, index: int) -> dict:
        with self._lock:
            self._require_session().delete(index)
            self._solution = None
            return self._session_dict()

    def solve(self) -> dict:
        """Calibrate from the kept views; the result waits for accept. Refusals keep the intrinsics in use."""
        with self._lock:
            session = self._require_session()
            self._solution = None
            solution = session.solve()
            self._solution = solution
            return self._session_dict()

    def accept(self) -> dict:
        """Store the solved intrinsics for this camera and use them; ends the session."""
        with self._lock:
            session, solution = self._require_session(), self._solution
            if solution is None:
                raise IntrinsicsRejected("not_solved", "nothing to accept: solve first")
            measured = solution.to_intrinsics()
            data = {"intrinsics": intrinsics_dict(measured), "rms_px": round(solution.rms, 4), "views": len(session.views),
                    "per_view_errors_px": [round(e, 4) for e in solution.per_view_errors]}
        key = self.key()
        row = self._store.save_intrinsics(key, data)  # outside the lock: I/O
        with self._lock:
            self._measured = measured
            self._measured_info = {"rms_px": data["rms_px"], "views": data["views"]}
            self._session, self._solution = None, None
        self._events.add("info", f"intrinsics of {key} measured and in use: fx {measured.fx:.1f} fy {measured.fy:.1f} "
                                 f"cx {measured.cx:.1f} cy {measured.cy:.1f} px, RMS {data['rms_px']:.3f} px (stored as {row})")
        return data

    def cancel(self) -> None:
        with self._lock:
            self._session, self._solution = None, None

    def _session_dict(self) -> dict | None:
        """The session's views, coverage and solve (caller holds the lock); None without a session."""
        if self._session is None:
            return None
        result = self._session.to_dict()
        solution = self._solution
        result["solution"] = None if solution is None else {
            **intrinsics_dict(solution.to_intrinsics()), "rms_px": round(solution.rms, 4),
            "per_view_errors_px": [round(e, 4) for e in solution.per_view_errors]}
        return result
