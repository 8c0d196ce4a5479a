"""The colour calibration's table (schema version 4): a version-3 file is migrated and keeps its
intrinsics; the newest colour calibration row is the one read back; a damaged row is skipped."""

import sqlite3

from armlab.store import Store
from armlab.store_schema import MIGRATIONS


def test_a_version_3_file_gains_the_colour_table_and_keeps_its_rows(tmp_path):
    path = tmp_path / "v3.sqlite3"
    connection = sqlite3.connect(path)
    for version, script in enumerate(MIGRATIONS[:3], start=1):
        connection.executescript(f"BEGIN; {script} PRAGMA user_version = {version}; COMMIT;")
    with connection:
        connection.execute("INSERT INTO intrinsics (camera, created_s, data_json) VALUES ('cam 1280x720', 1.0, '{\"fx\": 900}')")
    connection.close()
    store = Store(path)
    assert store.latest_intrinsics("cam 1280x720")["fx"] == 900
    assert store.latest_color_calibration() is None
    store.save_color_calibration({"samples": [{"name": "pink", "lab": [60.0, 60.0, 9.0]}]})
    store.save_color_calibration({"samples": []})
    assert Store(path).latest_color_calibration()["samples"] == []  # the newest row: a reset


def test_a_damaged_colour_row_is_skipped_for_the_one_before(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    store.save_color_calibration({"samples": [{"name": "pink", "lab": [60.0, 60.0, 9.0]}]})
    connection = sqlite3.connect(tmp_path / "db.sqlite3")
    with connection:
        connection.execute("INSERT INTO color_calibrations (created_s, data_json) VALUES (2.0, 'not json')")
    connection.close()
    assert store.latest_color_calibration()["samples"][0]["name"] == "pink"
