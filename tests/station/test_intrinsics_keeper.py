"""station.intrinsics with a RealSense (the pyrealsense2 stand-in of tests/devices/test_realsense.py) and a
real SQLite file: the factory intrinsics the device reports are in use when nothing is stored; measured
intrinsics are stored under the camera's serial and image size, come back for that camera after a
restart, and are not used for another camera."""

from __future__ import annotations

import sys
import types
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "devices"))

from test_realsense import _install_fake_pyrealsense2  # noqa: E402

from armlab.devices.factory import make_camera  # noqa: E402
from armlab.station.intrinsics import CameraIntrinsics  # noqa: E402
from armlab.station.slots import EventLog  # noqa: E402
from armlab.store import Store  # noqa: E402
from armlab.vision.intrinsics_capture import IntrinsicsRejected  # noqa: E402


def connected_realsense(monkeypatch, serial: str):
    """A connected RealSenseCamera on the stand-in, whose device reports `serial`."""
    _install_fake_pyrealsense2(monkeypatch, {"ok": True})
    rs = sys.modules["pyrealsense2"]
    rs.camera_info = types.SimpleNamespace(serial_number="serial_number")
    start = rs.pipeline.start

    def start_with_serial(self, cfg):
        profile = start(self, cfg)
        device = profile.get_device()
        profile.get_device = lambda: types.SimpleNamespace(
            first_depth_sensor=device.first_depth_sensor, get_info=lambda what: serial if what == "serial_number" else "")
        return profile

    monkeypatch.setattr(rs.pipeline, "start", start_with_serial)
    camera = make_camera({"type": "realsense"})
    camera.connect()
    return camera


def test_factory_by_default_measured_per_serial_after_restart(monkeypatch, tmp_path):
    db = tmp_path / "station.sqlite3"
    camera = connected_realsense(monkeypatch, "f0220315")
    try:
        keeper = CameraIntrinsics(camera, Store(db), EventLog())
        keeper.restore()
        assert keeper.key() == "RealSenseCamera(f0220315) 8x6"
        assert keeper.current() == camera.intrinsics and keeper.current().fx == 6.0  # the device's own
        assert keeper.info()["source"] == "factory"
        measured = {"width": 8, "height": 6, "fx": 6.2, "fy": 6.3, "cx": 4.0, "cy": 3.0, "dist": [0.01, 0, 0, 0, 0]}
        Store(db).save_intrinsics(keeper.key(), {"intrinsics": measured, "rms_px": 0.1, "views": 12})
    finally:
        camera.close()

    camera = connected_realsense(monkeypatch, "f0220315")  # a restart: a new station on the same file
    try:
        keeper = CameraIntrinsics(camera, Store(db), EventLog())
        keeper.restore()
        assert keeper.current().fx == 6.2 and keeper.current().dist[0] == 0.01
        assert keeper.info()["source"] == "measured" and keeper.info()["views"] == 12
    finally:
        camera.close()

    other = connected_realsense(monkeypatch, "f9999999")  # another RealSense: its own factory intrinsics
    try:
        keeper = CameraIntrinsics(other, Store(db), EventLog())
        keeper.restore()
        assert keeper.current().fx == 6.0 and keeper.info()["source"] == "factory"
    finally:
        other.close()


def test_a_damaged_stored_row_keeps_the_factory_intrinsics(monkeypatch, tmp_path):
    camera = connected_realsense(monkeypatch, "f1")
    try:
        store, events = Store(tmp_path / "s.sqlite3"), EventLog()
        keeper = CameraIntrinsics(camera, store, events)
        store.save_intrinsics(keeper.key(), {"intrinsics": {"width": 8, "height": 6, "fx": -1.0, "fy": 6, "cx": 4, "cy": 3,
                                                            "dist": [0, 0, 0, 0, 0]}})
        keeper.restore()
        assert keeper.current().fx == 6.0
        assert any("not used" in entry["message"] and entry["level"] == "warn" for entry in events.since(0))
    finally:
        camera.close()


def _capture_blocked_in_measure(monkeypatch, keeper):
    """Start keeper.capture in a thread whose measure() waits for `release`; returns (thread, entered, release, out)."""
    import threading

    from armlab.vision import intrinsics_capture

    entered, release, out = threading.Event(), threading.Event(), {}
    measure = intrinsics_capture.IntrinsicsCapture.measure

    def slow_measure(self, image):
        entered.set()
        release.wait(30)
        return measure(self, image)

    monkeypatch.setattr(intrinsics_capture.IntrinsicsCapture, "measure", slow_measure)

    def run():
        try:
            out["result"] = keeper.capture(__import__("numpy").zeros((6, 8, 3), "uint8"))
        except Exception as error:  # noqa: BLE001 - the test looks at which
            out["error"] = error

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    assert entered.wait(10)
    return thread, release, out


def test_the_intrinsics_answer_while_a_view_is_measured(monkeypatch, tmp_path):
    """Finding the board takes seconds on a busy machine: GET /api/intrinsics (the page's refresh) and a
    cancel must not wait behind it (the CI run where the panel's refusal never showed)."""
    import threading

    camera = connected_realsense(monkeypatch, "f0220315")
    try:
        keeper = CameraIntrinsics(camera, Store(tmp_path / "s.sqlite3"), EventLog())
        keeper.restore()
        keeper.start_session()
        thread, release, out = _capture_blocked_in_measure(monkeypatch, keeper)
        answered = {}
        reader = threading.Thread(target=lambda: answered.update(info=keeper.info(), cancel=keeper.cancel()), daemon=True)
        reader.start()
        reader.join(10)
        released_late = reader.is_alive()
        release.set()
        thread.join(10)
        assert not released_late, "info()/cancel() waited for the board search"
        assert answered["info"]["session"] is not None and answered["info"]["session"]["views"] == []
        assert isinstance(out["error"], IntrinsicsRejected)  # no board in the stand-in's image; nothing kept anywhere
        assert keeper.info()["session"] is None
    finally:
        camera.close()
