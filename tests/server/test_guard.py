"""Host and Origin checks over real HTTP (issue 10, item 1): a DNS-rebinding Host or a foreign page's
Origin gets 403 with the API's JSON error body on every REST call and on the websocket handshake;
same-origin pages and scripts without Origin work; CORS stays closed."""

from __future__ import annotations

import json

import httpx
import numpy as np
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

import live

TOKEN = "guard-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


cell, url = live.module_fixtures(seed=2, token=TOKEN, allowed_hosts=["armlab.lab"])


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=30.0) as client:
        yield client


def _port(url: str) -> int:
    return int(url.rsplit(":", 1)[1])


def _refused(response: httpx.Response, fragment: str) -> None:
    assert response.status_code == 403, response.text
    assert response.headers["content-type"].startswith("application/json")
    error = response.json()["error"]
    assert error["code"] == "forbidden" and fragment in error["message"], error
    assert "access-control-allow-origin" not in response.headers


@pytest.mark.parametrize("host", ["evil.example", "evil.example:{port}", "127.0.0.1.nip.io:{port}", "localhost.evil.example", ""])
def test_a_foreign_host_cannot_read_the_camera_or_status(http, url, host):
    headers = {"Host": host.format(port=_port(url))}
    for path in ("/api/frame.jpg", "/api/status", "/", "/openapi.json"):
        _refused(http.get(path, headers=headers), "Host")


@pytest.mark.parametrize(
    "host", ["127.0.0.1", "127.0.0.1:{port}", "localhost:{port}", "LOCALHOST:{port}", "[::1]:{port}", "[::1]", "armlab.lab:{port}"]
)
def test_the_hosts_the_station_serves_are_accepted(http, url, host):
    response = http.get("/api/status", headers={"Host": host.format(port=_port(url))})
    assert response.status_code == 200, response.text


@pytest.mark.parametrize("origin", ["http://evil.example", "null", "http://127.0.0.1:1", "https://127.0.0.1:{port}", "http://localhost:{port}"])
def test_a_foreign_origin_is_refused_on_reads_and_commands_and_moves_nothing(http, url, origin):
    origin = origin.format(port=_port(url))
    q_before = np.array(http.get("/api/status").json()["joints_rad"])
    _refused(http.get("/api/frame.jpg", headers={"Origin": origin}), "Origin")
    _refused(http.get("/api/status", headers={"Origin": origin}), "Origin")
    _refused(http.post("/api/arm/joints", json={"q_rad": [0.6, 0, 0, 0, 0]}, headers={**AUTH, "Origin": origin}), "Origin")
    _refused(http.options("/api/arm/joints", headers={"Origin": origin, "Access-Control-Request-Method": "POST"}), "Origin")
    status = http.get("/api/status").json()
    assert not status["moving"] and np.allclose(status["joints_rad"], q_before, atol=2e-3)


def test_same_origin_pages_and_scripts_without_origin_work(http, url):
    page_origin = url  # http://127.0.0.1:<port>, what the browser sends from the served page
    assert http.get("/api/frame.jpg", headers={"Origin": page_origin}).status_code == 200
    assert http.post("/api/estop", headers={**AUTH, "Origin": page_origin}).json()["state"] == "estop"
    assert http.post("/api/reset", headers=AUTH).json()["state"] == "idle"  # a script: no Origin
    localhost = f"http://localhost:{_port(url)}"
    response = http.get("/api/status", headers={"Host": f"localhost:{_port(url)}", "Origin": localhost})
    assert response.status_code == 200
    assert "access-control-allow-origin" not in response.headers  # CORS stays closed


def test_the_websocket_handshake_checks_origin_and_host(url):
    ws_url = url.replace("http://", "ws://") + "/ws"
    for kwargs in ({"origin": "http://evil.example"}, {"additional_headers": {"Host": "evil.example"}}):
        with pytest.raises(InvalidStatus) as refused:
            connect(ws_url, open_timeout=10, **kwargs)
        response = refused.value.response
        assert response.status_code == 403
        assert json.loads(response.body)["error"]["code"] == "forbidden"
    with connect(ws_url, origin=url, open_timeout=10, close_timeout=2) as ws:  # the page's own origin
        assert json.loads(ws.recv(timeout=10))["type"] == "hello"


def _scope(host: str | None, origin: str | None = None, server=("127.0.0.1", 8000), kind: str = "http") -> dict:
    headers = [(b"host", host.encode())] if host is not None else []
    if origin is not None:
        headers.append((b"origin", origin.encode()))
    return {"type": kind, "scheme": "http" if kind == "http" else "ws", "headers": headers, "server": server}


def test_an_ip_literal_host_is_served_only_when_it_is_the_address_the_connection_arrived_on():
    from server.guard import HostOriginGuard

    guard = HostOriginGuard(app=None, allowed_hosts=["0.0.0.0"])  # --host 0.0.0.0 is no name: not added
    lan = ("192.168.1.5", 8000)
    assert guard.refusal(_scope("192.168.1.5:8000", server=lan)) is None  # a LAN browser at the bound address
    assert guard.refusal(_scope("192.168.1.5:8000", "http://192.168.1.5:8000", server=lan, kind="websocket")) is None
    assert "Host" in guard.refusal(_scope("192.168.1.6:8000", server=lan))
    assert "Host" in guard.refusal(_scope("0.0.0.0:8000", server=lan))
    assert "Host" in guard.refusal(_scope(None))  # no Host header at all
    assert "Origin" in guard.refusal(_scope("127.0.0.1:8000", "http://127.0.0.1:8000/evil"))  # not an origin
    assert "Origin" in guard.refusal(_scope("127.0.0.1:8000", "http://user@127.0.0.1:8000"))
    doubled = _scope("127.0.0.1:8000")
    doubled["headers"].append((b"host", b"evil.example"))
    assert "Host" in guard.refusal(doubled)  # a repeated Host is malformed


@pytest.mark.parametrize("name", ["http://armlab.lab", "armlab.lab:8000", "a b", "", "lab/x"])
def test_config_allowed_hosts_are_bare_names(name):
    from pydantic import ValidationError

    from armlab.station import StationConfig

    with pytest.raises(ValidationError, match="allowed_hosts"):
        StationConfig(allowed_hosts=[name])
    assert StationConfig(allowed_hosts=["armlab.lab", "10.0.0.7", "fe80::1"]).allowed_hosts == ("armlab.lab", "10.0.0.7", "fe80::1")
