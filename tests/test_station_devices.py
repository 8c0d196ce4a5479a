"""A station on real devices: without the hardware SDK, start-up fails with the device's clear error."""

import pytest

from armlab.station.factory import make_device_station


def test_real_backend_without_ros_fails_clearly(tmp_path):
    with pytest.raises(ImportError) as caught:
        make_device_station(arm="interbotix_arm", gripper="interbotix_gripper", camera="webcam", db_path=tmp_path / "db.sqlite3")
    message = str(caught.value)
    assert "interbotix_xs_modules" in message and "install" in message.lower()
