"""Calibration trust on its own (armlab.station.calibration_trust.CalibrationTrust), without a station or a simulation:
what is in use and published, a restored candidate judged by the camera-moved check (trusted, rejected, ignored when
the frame predates the restore), the operator's calibration kept when it lands during that check, doubt about the one
in use refusing work with the reason, and when self-recalibration starts. Calibrations are stand-in objects: the trust
compares them by identity only."""

from __future__ import annotations

import time
from types import SimpleNamespace

import pytest

from armlab.errors import CalibrationUntrusted, InvalidInput, NotController
from armlab.station.calibration_trust import CalibrationTrust

THRESHOLD_PX = 2.0
BOARD = (0, 1, 2, 3, 4, 5)


class Events:
    def __init__(self) -> None:
        self.items: list[tuple[str, str]] = []

    def add(self, level: str, message: str) -> None:
        self.items.append((level, message))


class Harness:
    """A CalibrationTrust with recorded events, publications and self-recalibration starts; `idle` is what
    why_not_idle answers; `on_config_read` runs at the next read of the perception config."""

    def __init__(self, self_recalibrate: bool = False, retry_s: float = 10.0) -> None:
        self.events, self.published, self.started = Events(), [], 0
        self.idle: str | None = None
        self.on_config_read = None
        self.perception_config = SimpleNamespace(calibration=SimpleNamespace(drift_threshold_px=THRESHOLD_PX),
                                                 tags=SimpleNamespace(board_tags=BOARD))
        config = SimpleNamespace(self_recalibrate=self_recalibrate, self_recalibrate_min_board_tags=4,
                                 self_recalibrate_retry_s=retry_s)
        self.trust = CalibrationTrust(self.events, self.published.append, self._config, config, lambda: self.idle, self._start,
                                      self._check_control)

    @staticmethod
    def _check_control(source, command) -> None:
        if source not in (None, "page"):
            raise NotController(command, "page")

    def _config(self):
        if self.on_config_read is not None:
            on_read, self.on_config_read = self.on_config_read, None
            on_read()
        return self.perception_config

    def _start(self) -> None:
        self.started += 1


def seen(*tag_ids: int, captured_s: float | None = None):
    """A perception of a frame captured at captured_s (now by default) showing these tags."""
    return SimpleNamespace(capture_time_s=time.time() if captured_s is None else captured_s,
                           tags=[SimpleNamespace(id=tag_id) for tag_id in tag_ids])


def test_nothing_in_use_at_first():
    trust = Harness().trust
    assert trust.state is None and trust.calibration is None and trust.to_check() is None
    assert trust.info == {"calibrated": False} and not trust.checked


def test_an_installed_calibration_is_in_use_trusted_and_published():
    harness = Harness()
    calibration = object()
    harness.trust.install(calibration, {"method": "tags"})
    assert harness.trust.calibration is calibration and harness.trust.state == "trusted"
    assert harness.trust.info == {"calibrated": True, "method": "tags"}
    assert harness.published == [{"calibrated": True, "method": "tags"}]


def test_a_restored_calibration_is_used_only_once_a_later_frame_confirms_it():
    harness = Harness()
    trust, restored = harness.trust, object()
    trust.restore_candidate(restored, {"method": "tags"}, restored_at_s=100.0)
    assert trust.state == "checking" and trust.calibration is None and trust.to_check() is restored and trust.checked
    trust.on_check(restored, 0.5, None, seen(*BOARD, captured_s=99.0))  # a buffered frame from before the restore
    assert trust.state == "checking" and trust.calibration is None
    trust.on_check(restored, 0.5, None, seen(*BOARD, captured_s=101.0))
    assert trust.state == "trusted" and trust.calibration is restored
    assert trust.info == {"calibrated": True, "method": "tags", "restored": True}


def test_a_restored_calibration_the_camera_moved_from_is_rejected_and_never_used():
    harness = Harness()
    trust, restored = harness.trust, object()
    trust.restore_candidate(restored, {}, restored_at_s=0.0)
    trust.on_check(restored, 9.0, "camera moved", seen(*BOARD))
    assert trust.state == "rejected" and trust.calibration is None
    trust.on_check(restored, 0.5, None, seen(*BOARD))  # a rejected candidate is not judged again
    assert trust.state == "rejected" and trust.calibration is None
    assert ("warn", "restored calibration not trusted: camera moved") in harness.events.items


def test_too_few_tags_leave_a_candidate_waiting_unless_no_check_follows():
    harness = Harness()
    trust, restored = harness.trust, object()
    trust.restore_candidate(restored, {}, restored_at_s=0.0)
    trust.on_check(restored, None, "too few board tags", seen(1))
    assert trust.state == "checking"
    trust.on_check(restored, None, "too few board tags", seen(1), final=True)
    assert trust.state == "rejected"


def test_the_operators_calibration_landing_during_the_check_stays_in_use():
    harness = Harness()
    trust, restored, operators = harness.trust, object(), object()
    trust.restore_candidate(restored, {}, restored_at_s=0.0)
    harness.on_config_read = lambda: trust.install(operators, {"method": "operator"})  # between judging and installing
    trust.on_check(restored, 0.5, None, seen(*BOARD))
    assert trust.calibration is operators and trust.info["method"] == "operator" and trust.state == "trusted"


def test_doubt_about_the_calibration_in_use_refuses_work_until_the_tags_confirm_it():
    harness = Harness()
    trust, calibration = harness.trust, object()
    trust.install(calibration, {})
    trust.require_trusted("grab")  # trusted: nothing raised
    trust.on_check(calibration, 6.0, "camera moved (board tags 6.0 px from where it puts them)", seen(*BOARD))
    assert trust.state == "untrusted" and trust.doubt.startswith("camera moved")
    with pytest.raises(CalibrationUntrusted, match="grab refused: .*camera moved"):
        trust.require_trusted("grab")
    trust.on_check(calibration, 0.4, None, seen(*BOARD))
    assert trust.state == "trusted" and trust.doubt is None
    levels = [level for level, message in harness.events.items if "trusted" in message]
    assert levels == ["warn", "info"]  # said once each way


def test_doubt_about_an_older_calibration_does_not_stick_to_a_new_one():
    harness = Harness()
    trust, old, new = harness.trust, object(), object()
    trust.install(old, {})
    trust.on_check(old, 6.0, "camera moved", seen(*BOARD))
    trust.install(new, {})
    assert trust.state == "trusted" and trust.doubt is None
    trust.on_check(old, 6.0, "camera moved", seen(*BOARD))  # a late check of the old one
    assert trust.state == "trusted"


def test_the_self_recalibration_setting():
    harness = Harness(self_recalibrate=True)
    trust = harness.trust
    assert trust.self_recalibrate is True  # the config's
    with pytest.raises(InvalidInput):
        trust.set_self_recalibrate("yes")
    assert trust.set_self_recalibrate(False, source="page") is False and trust.self_recalibrate is False
    trust.set_self_recalibrate(False)
    with pytest.raises(NotController):
        trust.set_self_recalibrate(True, source="another page")  # not the lease holder: nothing changes
    assert trust.self_recalibrate is False
    assert [message for _, message in harness.events.items] == ["self-recalibration when idle turned off by 'page'"]


def test_self_recalibration_starts_when_idle_with_the_board_in_view_and_not_again_at_once():
    harness = Harness(self_recalibrate=True, retry_s=60.0)
    trust, calibration = harness.trust, object()
    trust.install(calibration, {})
    harness.idle = "a job or a jog is running"
    trust.on_check(calibration, 6.0, "camera moved", seen(*BOARD))
    assert harness.started == 0
    harness.idle = None
    trust.on_check(calibration, 6.0, "camera moved", seen(0, 1, 2))  # 3 of 6 board tags, 4 needed
    assert harness.started == 0
    assert any("only 3 of the 6 board tags" in message for _, message in harness.events.items)
    trust.on_check(calibration, 6.0, "camera moved", seen(0, 1, 2, 3, 99))  # tag 99 is not a board tag
    assert harness.started == 1
    trust.on_check(calibration, 6.0, "camera moved", seen(*BOARD))  # tried moments ago
    assert harness.started == 1


def test_no_self_recalibration_when_it_is_off_or_the_camera_did_not_move():
    harness = Harness(self_recalibrate=False)
    trust, calibration = harness.trust, object()
    trust.install(calibration, {})
    trust.on_check(calibration, 6.0, "camera moved", seen(*BOARD))
    trust.set_self_recalibrate(True)
    trust.on_check(calibration, 0.5, None, seen(*BOARD))
    assert harness.started == 0


def test_a_damaged_saved_calibration_is_not_restored():
    harness = Harness()
    harness.trust.restore({"calibration": {"K": "not a matrix"}, "info": {}})
    assert harness.trust.state is None
    assert harness.events.items and harness.events.items[0][0] == "warn"
    harness.trust.restore(None)  # nothing saved: nothing happens
    assert harness.trust.state is None
