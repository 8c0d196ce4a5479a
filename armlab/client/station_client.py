"""StationClient: typed Python methods over the station's REST API and websocket stream.

    from armlab.client import StationClient
    station = StationClient("http://127.0.0.1:8000", token="...")
    station.home(); station.calibrate(); station.grab(position_m=[0.1, 0.2, 0.038]); station.drop(u=640, v=400)

Errors come back as StationError with the server's code ('wrong_state', 'unreachable', ...), message
and, for a wrong state, the allowed commands.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from urllib.parse import urlencode, urlsplit, urlunsplit

import httpx


class StationError(RuntimeError):
    """An error answer of the station: HTTP status, wire code, the human sentence, allowed commands."""

    def __init__(self, status_code: int, code: str, message: str, allowed: list[str] | None = None) -> None:
        super().__init__(f"{code}: {message}")
        self.status_code, self.code, self.message, self.allowed = status_code, code, message, allowed or []


@dataclass(frozen=True)
class StreamFrame:
    """One streamed frame: its header (seq, capture_time_s, width, height, view) and JPEG bytes."""

    header: dict
    jpeg: bytes
    received_time_s: float = field(default_factory=time.time)

    @property
    def seq(self) -> int:
        return int(self.header["seq"])

    @property
    def capture_time_s(self) -> float:
        return float(self.header["capture_time_s"])

    def decode(self):
        """The image as a BGR numpy array (needs OpenCV)."""
        import cv2
        import numpy as np

        return cv2.imdecode(np.frombuffer(self.jpeg, np.uint8), cv2.IMREAD_COLOR)


def unpack_frame(message: bytes) -> tuple[dict, bytes]:
    """[uint32 LE header length N][N bytes JSON header][JPEG] → (header, jpeg)."""
    length = int.from_bytes(message[:4], "little")
    return json.loads(message[4 : 4 + length]), message[4 + length :]


def _floats(values: Sequence[float], name: str) -> list[float]:
    try:
        return [float(value) for value in values]
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be a list of numbers, got {values!r}") from error


class StationClient:
    """A script's handle on a running station. token: the control token (default $ARMLAB_TOKEN)."""

    def __init__(self, url: str = "http://127.0.0.1:8000", token: str | None = None, timeout_s: float = 30.0) -> None:
        self.url = url.rstrip("/")
        self.token = token if token is not None else os.environ.get("ARMLAB_TOKEN")
        headers = {"Authorization": f"Bearer {self.token}"} if self.token else {}
        self._http = httpx.Client(base_url=self.url, headers=headers, timeout=timeout_s)

    def close(self) -> None:
        self._http.close()

    def __enter__(self) -> StationClient:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # Transport ------------------------------------------------------------------------------------

    def _request(self, method: str, path: str, body: dict | None = None, params: dict | None = None, timeout_s=None):
        kwargs = {"params": params}
        if body is not None:
            kwargs["json"] = body
        if timeout_s is not None:
            kwargs["timeout"] = timeout_s
        return self._checked(self._http.request(method, path, **kwargs))

    def _checked(self, response: httpx.Response, raw: bool = False):
        """The answer's JSON (its bytes when raw or not JSON); StationError for an error status."""
        if response.status_code >= 400:
            try:
                error = response.json()["error"]
            except (ValueError, KeyError, TypeError):
                raise StationError(response.status_code, "http", response.text[:200]) from None
            raise StationError(response.status_code, error.get("code", "error"), error.get("message", ""), error.get("allowed"))
        if not raw and response.headers.get("content-type", "").startswith("application/json"):
            return response.json()
        return response.content

    def _get(self, path: str, params: dict | None = None):
        return self._request("GET", path, params=params)

    def _post(self, path: str, body: dict | None = None, wait: bool | None = None, timeout_s: float | None = None):
        params = {"wait": "true"} if wait else None
        return self._request("POST", path, body, params, timeout_s=timeout_s if wait else None)

    # Status and safety ----------------------------------------------------------------------------

    def health(self) -> dict:
        return self._get("/api/health")

    def status(self) -> dict:
        return self._get("/api/status")

    def arm(self) -> dict:
        """The arm and gripper the station runs: name, vendor, joint_names, joint_limits_rad, gripper_type, ..."""
        return self._get("/api/arm")

    def estop(self) -> dict:
        return self._post("/api/estop")

    def reset(self) -> dict:
        return self._post("/api/reset")

    # Arm and gripper ------------------------------------------------------------------------------

    def home(self, wait: bool = True, moving_time_s: float | None = None) -> dict:
        return self._post("/api/arm/home", {"moving_time_s": moving_time_s}, wait=wait, timeout_s=60.0)

    def sleep(self, wait: bool = True, moving_time_s: float | None = None) -> dict:
        return self._post("/api/arm/sleep", {"moving_time_s": moving_time_s}, wait=wait, timeout_s=60.0)

    def move_joints(self, q_rad: Sequence[float], moving_time_s: float | None = None, wait: bool = True) -> dict:
        body = {"q_rad": _floats(q_rad, "q_rad"), "moving_time_s": moving_time_s}
        return self._post("/api/arm/joints", body, wait=wait, timeout_s=60.0)

    def move_to(
        self,
        position_m: Sequence[float],
        pitch_rad: float | None = None,
        yaw_rad: float | None = None,
        moving_time_s: float | None = None,
        wait: bool = True,
    ) -> dict:
        body = {"position_m": _floats(position_m, "position_m"), "pitch_rad": pitch_rad, "yaw_rad": yaw_rad, "moving_time_s": moving_time_s}
        return self._post("/api/arm/pose", body, wait=wait, timeout_s=60.0)

    def torque(self, enabled: bool) -> dict:
        return self._post("/api/arm/torque", {"enabled": bool(enabled)})

    def jog_step(self, axis: str, amount: float, speed_percent: float = 100.0, wait: bool = True) -> dict:
        """One jog step of the gripper: `amount` metres along world x|y|z (pitch and yaw kept) or radians of
        pitch|roll; a step that cannot keep them raises StationError 422 with the reason (nothing moves)."""
        key = "distance_m" if axis in ("x", "y", "z") else "angle_rad"
        return self._post("/api/arm/step", {"axis": axis, key: float(amount), "speed_percent": float(speed_percent)}, wait=wait)

    def jog(self, velocity_rad_s: Sequence[float], speed_percent: float = 100.0) -> dict:
        """Hold-to-run joint jog: runs jog_hold_s after this call or the last heartbeat, then ramps to rest."""
        return self._post("/api/arm/jog", {"velocity_rad_s": _floats(velocity_rad_s, "velocity_rad_s"), "speed_percent": float(speed_percent)})

    def grasp(self) -> dict:
        return self._post("/api/gripper", {"action": "grasp"})

    def release(self) -> dict:
        return self._post("/api/gripper", {"action": "release"})

    # Perception -----------------------------------------------------------------------------------

    def calibrate(self, wait: bool = True) -> dict:
        """Run the calibration job; with wait, the finished job (check job['state'] == 'succeeded')."""
        return self._post("/api/calibrate", wait=wait, timeout_s=120.0)["job"]

    def calibrate_arm(self, wait: bool = True) -> dict:
        """Calibrate the arm from the camera (POST /api/calibrate/arm); with wait, the finished job (its result:
        residual before/after, the fitted offsets). Status carries arm_calibration {calibrated, residual_mm, at}."""
        return self._post("/api/calibrate/arm", wait=wait, timeout_s=600.0)["job"]

    def calibration(self) -> dict:
        return self._get("/api/calibration")

    def detections(self) -> list[dict]:
        return self._get("/api/detections")["data"]

    def pixel_to_world(self, u: float, v: float) -> dict:
        return self._post("/api/pixel-to-world", {"u": float(u), "v": float(v)})

    def frame_jpeg(self, view: str = "color", layers: Sequence[str] = ()) -> bytes:
        return self._get("/api/frame.jpg", {"view": view, "layers": ",".join(layers)})

    # Jobs -----------------------------------------------------------------------------------------

    @staticmethod
    def _target(position_m, u, v) -> dict:
        if position_m is not None:
            return {"position_m": _floats(position_m, "position_m")}
        return {"u": u, "v": v}

    def grab(self, position_m: Sequence[float] | None = None, u: float | None = None, v: float | None = None, wait: bool = True) -> dict:
        """Grab the block at a world point or under a pixel; returns the job (final with wait)."""
        return self._post("/api/grab", self._target(position_m, u, v), wait=wait, timeout_s=120.0)["job"]

    def drop(self, position_m: Sequence[float] | None = None, u: float | None = None, v: float | None = None, wait: bool = True) -> dict:
        return self._post("/api/drop", self._target(position_m, u, v), wait=wait, timeout_s=120.0)["job"]

    def current_job(self) -> dict | None:
        return self._get("/api/jobs/current")["job"]

    def cancel_job(self) -> dict:
        return self._post("/api/jobs/cancel")["job"]

    def wait_job(self, timeout_s: float = 120.0, poll_s: float = 0.1) -> dict | None:
        """Poll until the current job has ended; TimeoutError after timeout_s."""
        deadline = time.monotonic() + timeout_s
        while True:
            job = self.current_job()
            if job is None or job["state"] != "running":
                return job
            if time.monotonic() > deadline:
                raise TimeoutError(f"job {job['name']} still running after {timeout_s} s")
            time.sleep(poll_s)

    # Autonomous jobs ------------------------------------------------------------------------------

    def auto_jobs(self) -> list[dict]:
        """The autonomous jobs: name, levels, summary, params [{name, type}], judged, scene, time_limit_s."""
        return self._get("/api/auto/jobs")["data"]

    def auto(self, job: str, level: int | None = None, params: dict | None = None, wait: bool = False,
             timeout_s: float = 900.0) -> dict:
        """Start autonomous job `job` (at `level`, with `params`); returns the job (with wait, once it has
        ended: check job['state'] and job['extra']['task']). Values go as given: the server refuses wrong types."""
        body: dict = {"job": job}
        if level is not None:
            body["level"] = level
        if params is not None:
            body["params"] = params
        return self._post("/api/auto", body, wait=wait, timeout_s=timeout_s)["job"]

    def auto_score(self) -> dict:
        """Simulation: the judge's score of the last autonomous job started on the server
        ({job_id, job, level, state, final, sim_time_s, score: {points, max_points, breakdown, ...}, note})."""
        return self._get("/api/auto/score")

    # Teach and repeat -----------------------------------------------------------------------------

    def teach_start(self, discard_draft: bool = False) -> dict:
        """Enter teach (the status); an unsaved draft left by a stopped station is resumed unless discard_draft."""
        return self._post("/api/teach/start", {"discard_draft": True} if discard_draft else None)

    def teach_record(self, dwell_s: float = 0.0, moving_time_s: float | None = None) -> dict:
        """Record the current pose and gripper (on disk before this returns): the waypoint and the draft's count."""
        return self._post("/api/teach/record", {"dwell_s": float(dwell_s), "moving_time_s": moving_time_s})

    def teach_continuous(self, rate_hz: float, min_change_rad: float = 0.01) -> dict:
        """Trajectory mode: record the pose at rate_hz while it changes, until teach_continuous_stop()."""
        return self._post("/api/teach/continuous", {"rate_hz": float(rate_hz), "min_change_rad": float(min_change_rad)})

    def teach_continuous_stop(self) -> dict:
        """End trajectory mode: {recording: false, recorded, count}."""
        return self._post("/api/teach/continuous/stop")

    def teach_undo(self) -> dict:
        """Remove the last recorded waypoint: {removed, count}."""
        return self._post("/api/teach/undo")

    def teach_draft(self) -> dict:
        """The recorded, unsaved waypoints: {waypoints, count, skipped}."""
        return self._get("/api/teach/draft")

    def teach_stop(self, name: str) -> dict:
        """Save the draft as a program named `name` (returned) and return to idle."""
        return self._post("/api/teach/stop", {"name": name})

    def programs(self) -> list[dict]:
        return self._get("/api/programs")["data"]

    def program(self, program_id: int) -> dict:
        return self._get(f"/api/programs/{int(program_id)}")

    def update_program(self, program_id: int, name: str | None = None, waypoints: list[dict] | None = None) -> dict:
        """Rename and/or replace the waypoint list ({joints_rad, gripper, dwell_s?, moving_time_s?} each)."""
        body: dict = {}
        if name is not None:
            body["name"] = name
        if waypoints is not None:
            body["waypoints"] = waypoints
        return self._request("PATCH", f"/api/programs/{int(program_id)}", body)

    def duplicate_program(self, program_id: int, name: str | None = None) -> dict:
        return self._post(f"/api/programs/{int(program_id)}/duplicate", {"name": name} if name else None)

    def delete_program(self, program_id: int) -> dict:
        return self._request("DELETE", f"/api/programs/{int(program_id)}")

    def export_program(self, program_id: int, format: str = "json") -> str:
        """The program file's text: JSON, or CSV `t_s, q1..qn, gripper`."""
        response = self._http.get(f"/api/programs/{int(program_id)}/export", params={"format": format})
        if response.status_code >= 400:
            self._request("GET", f"/api/programs/{int(program_id)}/export", params={"format": format})
        return response.text

    def import_program(self, content: str, format: str = "json", name: str | None = None) -> dict:
        """Store a program from a file's text (the new program); StationError naming the line if malformed."""
        body = {"format": format, "content": content}
        if name is not None:
            body["name"] = name
        return self._post("/api/programs/import", body)

    def export_program_file(self, program_id: int, format: str = "rosbag2") -> bytes:
        """The program file's bytes: a ROS 2 bag (one MCAP file of sensor_msgs/JointState), CSV or JSON."""
        return self._checked(self._http.get(f"/api/programs/{int(program_id)}/export", params={"format": format}), raw=True)

    def import_program_file(self, data: bytes, format: str = "rosbag2", name: str | None = None, mode: str = "waypoints",
                            clamp_rad: float = 0.0, topic: str | None = None) -> dict:
        """Store a file's bytes as a new program: a ROS 2 bag (.mcap, .db3 or a .zip of the bag folder), the course's
        joint text (jointdata), CSV or JSON; the program with notes, clamped_rad, clamped_samples, samples.
        StationError (422) saying why a file is refused; nothing is stored then."""
        params = {"format": format, "mode": mode, "clamp_rad": clamp_rad}
        params.update({key: value for key, value in (("name", name), ("topic", topic)) if value is not None})
        response = self._http.post("/api/programs/import/file", params=params, content=bytes(data),
                                   headers={"Content-Type": "application/octet-stream"})
        return self._checked(response)

    def repeat(self, program_id: int, cycles: int | None = 1, speed_percent: float = 100.0, wait: bool = True,
               timeout_s: float = 3600.0) -> dict:
        """Repeat a program `cycles` times (None: until cancel_job()) at `speed_percent` (10-100); the job."""
        body = {"cycles": None if cycles is None else int(cycles), "speed_percent": float(speed_percent)}
        return self._post(f"/api/programs/{int(program_id)}/repeat", body, wait=wait, timeout_s=timeout_s)["job"]

    def pause_job(self) -> dict:
        return self._post("/api/jobs/pause")["job"]

    def resume_job(self) -> dict:
        return self._post("/api/jobs/resume")["job"]

    def step_job(self) -> dict:
        return self._post("/api/jobs/step")["job"]

    def set_job_speed(self, speed_percent: float) -> dict:
        return self._request("PATCH", "/api/jobs/current", {"speed_percent": float(speed_percent)})["job"]

    def job_trace(self, format: str = "json"):
        """Commanded and measured joints over the last complete repeat cycle: a dict, or the CSV text."""
        result = self._get("/api/jobs/current/trace", {"format": format})
        return result.decode() if isinstance(result, bytes) else result

    # Simulation -----------------------------------------------------------------------------------

    def set_scene(self, event: str | None = None, level: int = 1, seed: int = 0, objects: list[dict] | None = None) -> dict:
        body = {"objects": objects} if objects is not None else {"event": event, "level": level, "seed": seed}
        return self._post("/api/sim/scene", body)

    def truth(self) -> dict:
        return self._get("/api/sim/truth")

    # Stream ---------------------------------------------------------------------------------------

    def ws_url(self, control: bool = False) -> str:
        parts = urlsplit(self.url)
        scheme = "wss" if parts.scheme == "https" else "ws"
        query = urlencode({"token": self.token}) if control and self.token else ""
        return urlunsplit((scheme, parts.netloc, "/ws", query, ""))

    def frames(
        self, view: str = "color", layers: Sequence[str] = (), max_frames: int | None = None, timeout_s: float = 10.0
    ) -> Iterator[StreamFrame]:
        """Frames from the websocket, newest first-come: each is acknowledged when the caller asks for the next.

        Telemetry and events arriving in between are skipped (read status() for state).
        """
        from websockets.sync.client import connect

        with connect(self.ws_url(), compression=None, max_size=None, open_timeout=timeout_s) as websocket:
            websocket.send(json.dumps({"type": "view", "view": view, "layers": list(layers)}))
            count = 0
            while max_frames is None or count < max_frames:
                message = websocket.recv(timeout=timeout_s)
                if isinstance(message, str):
                    continue
                header, jpeg = unpack_frame(message)
                yield StreamFrame(header, jpeg)
                count += 1
                websocket.send(json.dumps({"type": "ack", "seq": header["seq"]}))
