"""The camera knows it moved (issue 11 item 5), seen from the page: a calibrated station whose simulated
camera mount is knocked shows 'camera moved: recalibrate' on the live view; recalibrating clears it."""

from __future__ import annotations

import pytest

from browser_helpers import open_page, wait_frames
from conftest import running_server

pytestmark = pytest.mark.browser

WARNING = "#camera-warning"


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    with running_server(tmp_path_factory.mktemp("camera_warning")) as srv:
        yield srv


def calibrate_from_the_page(page, server) -> None:
    page.click("#btn-calibrate")
    server.wait_status(lambda s: s["calibrated"] and s["state"] == "idle" and s["job"]["name"] == "calibrate", 60.0,
                       "calibrated")


def test_a_knocked_camera_warns_on_the_page_until_recalibrated(browser, fresh):
    page = open_page(browser, f"{fresh.base_url}/?token={fresh.token}")
    wait_frames(page, 2)
    calibrate_from_the_page(page, fresh)
    assert page.is_hidden(WARNING)
    refused = fresh.request("POST", "/api/sim/camera/bump", json={"translation_m": [0.2, 0, 0], "rotation_rad": [0, 0, 0]})
    assert refused.status_code == 422  # 200 mm is no knock: bounded to 50 mm
    assert page.is_hidden(WARNING)
    fresh.post("/api/sim/camera/bump", json={"translation_m": [0.005, 0.0, 0.0], "rotation_rad": [0.0, 0.0, 0.0175]})
    status = fresh.wait_status(lambda s: s["camera_warning"], 60.0, "the camera-moved warning")
    assert "camera moved" in status["camera_warning"]
    page.wait_for_function(f"!document.querySelector('{WARNING}').hidden", timeout=10_000)
    assert "recalibrate" in page.text_content(WARNING).lower()
    calibrate_from_the_page(page, fresh)
    fresh.wait_status(lambda s: s["camera_warning"] is None, 30.0, "the warning to clear")
    page.wait_for_function(f"document.querySelector('{WARNING}').hidden", timeout=10_000)
    assert page.errors == []
    page.close()
