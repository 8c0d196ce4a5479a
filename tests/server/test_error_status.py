"""Errors over real HTTP (issue 20, item 3): a route whose code raises a bare ValueError (a bug, e.g.
numpy's) answers 500 "internal" with a generic message and its traceback in the server log; the same
route raising InvalidInput answers 422 "invalid" (invalid input, nothing moved), as before."""

from __future__ import annotations

import logging

import httpx
import pytest

import live
from armlab.errors import InvalidInput
from armlab.station.core import Station

TOKEN = "error-status-token"
NUMPY_BUG = "operands could not be broadcast together with shapes (3,) (4,)"

cell, url = live.module_fixtures(seed=4, token=TOKEN)


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=30.0) as client:
        yield client


def _raising(error: Exception):
    def detections(self, *args, **kwargs):
        raise error

    return detections


def test_a_bare_value_error_is_a_500_with_its_traceback_logged(http, monkeypatch, caplog):
    monkeypatch.setattr(Station, "detections", _raising(ValueError(NUMPY_BUG)))
    with caplog.at_level(logging.ERROR, logger="server.errors"):
        response = http.get("/api/detections")
    assert response.status_code == 500, response.text
    error = response.json()["error"]
    assert error["code"] == "internal"
    assert NUMPY_BUG not in error["message"]  # generic: the details are in the log, not sent to the client
    logged = [r for r in caplog.records if r.name == "server.errors" and r.exc_info and NUMPY_BUG in str(r.exc_info[1])]
    assert logged and logged[0].levelno == logging.ERROR, [r.getMessage() for r in caplog.records]
    assert "/api/detections" in logged[0].getMessage()


def test_invalid_input_is_a_422_invalid_with_its_message(http, monkeypatch):
    monkeypatch.setattr(Station, "detections", _raising(InvalidInput("position_m must be 3 finite numbers")))
    response = http.get("/api/detections")
    assert response.status_code == 422, response.text
    assert response.json()["error"] == {"code": "invalid", "message": "position_m must be 3 finite numbers"}


def test_the_station_still_answers_after_a_500(http):
    assert http.get("/api/detections").status_code == 200
