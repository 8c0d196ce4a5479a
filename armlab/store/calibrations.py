"""Calibrations (the camera's and the arm's), camera intrinsics and colour calibrations: JSON documents, newest first; a damaged row is
logged and skipped for the newest one that reads back. Each save is one INSERT in one transaction."""

from __future__ import annotations

import json
import time

from armlab.store.database import ROW_ERRORS, Database


class CalibrationTables(Database):
    """The calibrations, arm_calibrations, intrinsics and color_calibrations tables of the station's database."""

    def save_calibration(self, data: dict) -> int:
        """Save a calibration (its JSON dict); returns its id."""
        connection = self._connect()
        try:
            with connection:
                cursor = connection.execute(
                    "INSERT INTO calibrations (created_s, data_json) VALUES (?, ?)", (time.time(), json.dumps(data))
                )
                return int(cursor.lastrowid)
        finally:
            connection.close()

    def latest_calibration(self) -> dict | None:
        """The newest calibration that reads back (damaged rows are logged and skipped), else None."""
        rows = self._run("SELECT id, data_json FROM calibrations ORDER BY id DESC LIMIT 20", raw_text=True)
        for calibration_id, data in rows:
            try:
                value = json.loads(data.decode("utf-8"))
                if not isinstance(value, dict):
                    raise ValueError("not a JSON object")
                return value
            except ROW_ERRORS as error:
                self._skip(f"calibration {calibration_id}", error)
        return None

    # The arm's calibration -----------------------------------------------------------------------

    def save_arm_calibration(self, data: dict) -> int:
        """Save the arm's calibration (its JSON dict: {"calibration", "info"}); returns the row id."""
        rows = self._run("INSERT INTO arm_calibrations (created_s, data_json) VALUES (?, ?) RETURNING id",
                         (time.time(), json.dumps(data)))
        return int(rows[0][0])

    def latest_arm_calibration(self) -> dict | None:
        """The newest arm calibration that reads back ({"created_s", **data}; damaged rows skipped), else None."""
        rows = self._run("SELECT id, created_s, data_json FROM arm_calibrations ORDER BY id DESC LIMIT 20", raw_text=True)
        return self._newest_json_object(rows, "arm calibration")

    # Intrinsics ----------------------------------------------------------------------------------

    def save_intrinsics(self, camera: str, data: dict) -> int:
        """Save measured intrinsics (their JSON dict) for a camera key; returns the row id."""
        rows = self._run("INSERT INTO intrinsics (camera, created_s, data_json) VALUES (?, ?, ?) RETURNING id",
                         (camera, time.time(), json.dumps(data)))
        return int(rows[0][0])

    def latest_intrinsics(self, camera: str) -> dict | None:
        """The newest intrinsics of a camera key that read back ({"created_s", **data}; damaged rows are
        logged and skipped), else None."""
        rows = self._run("SELECT id, created_s, data_json FROM intrinsics WHERE camera = ? ORDER BY id DESC LIMIT 20",
                         (camera,), raw_text=True)
        return self._newest_json_object(rows, "intrinsics")

    # Colour calibration ---------------------------------------------------------------------------

    def save_color_calibration(self, data: dict) -> int:
        """Save the station's colour calibration (its JSON dict: {"samples": [...]}); returns the row id."""
        rows = self._run("INSERT INTO color_calibrations (created_s, data_json) VALUES (?, ?) RETURNING id",
                         (time.time(), json.dumps(data)))
        return int(rows[0][0])

    def latest_color_calibration(self) -> dict | None:
        """The newest colour calibration that reads back ({"created_s", **data}; damaged rows are logged
        and skipped), else None."""
        rows = self._run("SELECT id, created_s, data_json FROM color_calibrations ORDER BY id DESC LIMIT 20", raw_text=True)
        return self._newest_json_object(rows, "colour calibration")

    def _newest_json_object(self, rows, what: str) -> dict | None:
        """The first of (id, created_s, data_json) rows whose data reads back as a JSON object ({"created_s",
        **data}); damaged rows are logged and skipped. None when none does."""
        for row_id, created_s, data in rows:
            try:
                value = json.loads(data.decode("utf-8"))
                if not isinstance(value, dict):
                    raise ValueError("not a JSON object")
                return {**value, "created_s": float(created_s)}
            except ROW_ERRORS as error:
                self._skip(f"{what} {row_id}", error)
        return None
