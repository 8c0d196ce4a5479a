"""Soak benchmark: 20 websocket viewers (5 slow, 2 that never read) and autonomous jobs running back to
back for --duration seconds (default 300) against a real `armlab serve` on the simulation.

Figures: the server's resident memory over time and its growth from the first sample taken with every
client connected and the first job running (target <= 10 %); the controller's frame rate and
capture-to-client latency (the controller is a page-like session: token, controller name, reads and
acks every frame, sends a heartbeat every 0.1 s, polls GET /api/status once a second); the telemetry
rate; every error seen (websocket sessions ended by the server, HTTP 5xx, error lines in the server's
log; target zero). Jobs: POST /api/auto {job: pick_sort, level: 3} on a fresh scene each time, so one
is always running; their outcomes are reported, not counted as errors (that is the task's quality).

    .venv/bin/python bench/soak.py [--duration 300] [--job pick_sort] [--level 3]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np
import psutil
from served import free_port, start_server
from websockets.asyncio.client import connect
from websockets.exceptions import ConnectionClosed

TOKEN = "soak-token"
CONTROLLER = "soak-controller"
HEADERS = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": CONTROLLER}
LAYERS = ["tags", "detections", "grid"]
NORMAL, SLOW, STALLED = 13, 5, 2  # + the controller = 20 sessions
SLOW_ACK_S = 0.5


def new_stats() -> dict:
    return {"frames": 0, "latency_s": [], "telemetry": 0, "errors": [], "ended_by_server": False}


async def viewer(url: str, end: float, stats: dict, ack_delay_s: float = 0.0, read: bool = True,
                 heartbeat_s: float | None = None) -> None:
    """A websocket session until `end` (monotonic): reads and acks frames (after ack_delay_s), or (read=False)
    never reads at all; heartbeat_s: also send a heartbeat this often."""
    try:
        async with connect(url, compression=None, max_size=None, max_queue=None if read else 1) as ws:
            await ws.send(json.dumps({"type": "view", "view": "color", "layers": LAYERS}))
            if not read:
                await asyncio.sleep(max(0.0, end - time.monotonic()))
                return
            next_beat = time.monotonic()
            while time.monotonic() < end:
                if heartbeat_s is not None and time.monotonic() >= next_beat:
                    await ws.send(json.dumps({"type": "heartbeat"}))
                    next_beat += heartbeat_s
                try:
                    timeout = max(0.005, min(end - time.monotonic(), 0.05 if heartbeat_s else 1.0))
                    message = await asyncio.wait_for(ws.recv(), timeout=timeout)
                except TimeoutError:
                    continue
                now = time.time()
                if isinstance(message, bytes):
                    length = int.from_bytes(message[:4], "little")
                    header = json.loads(message[4 : 4 + length])
                    stats["frames"] += 1
                    stats["latency_s"].append(now - header["capture_time_s"])
                    if ack_delay_s:
                        await asyncio.sleep(ack_delay_s)
                    await ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
                else:
                    parsed = json.loads(message)
                    if parsed["type"] == "telemetry":
                        stats["telemetry"] += 1
    except ConnectionClosed as closed:
        stats["ended_by_server"] = True
        stats["errors"].append(f"session closed by the server: {closed}")
    except Exception as error:  # noqa: BLE001 - every failure is an error of the run
        stats["errors"].append(f"{type(error).__name__}: {error}")


async def jobs_back_to_back(base: str, end: float, job: str, level: int, outcomes: list, errors: list) -> None:
    """Keep an autonomous job running: when one ends, set a fresh scene and start the next."""
    async with httpx.AsyncClient(base_url=base, timeout=60) as http:
        seed = 1
        while time.monotonic() < end:
            status = (await http.get("/api/status")).json()
            if status["state"] == "idle":
                previous = status.get("job")
                if previous and previous.get("name") == job and previous.get("id") not in {o["id"] for o in outcomes}:
                    outcomes.append({"id": previous["id"], "state": previous["state"], "message": previous["message"]})
                seed += 1
                scene = await http.post("/api/sim/scene", json={"event": job, "level": level, "seed": seed}, headers=HEADERS)
                started = await http.post("/api/auto", json={"job": job, "level": level}, headers=HEADERS)
                for response in (scene, started):
                    if response.status_code >= 500:
                        errors.append(f"{response.request.url.path}: {response.status_code} {response.text[:200]}")
            elif status["state"] in ("estop", "fault"):
                errors.append(f"station in {status['state']}: {status['detail']}")
                await http.post("/api/reset", headers=HEADERS)
            await asyncio.sleep(1.0)


async def poll_status(base: str, end: float, errors: list, samples: list) -> None:
    """The controller's status poll (once a second): every 5xx is an error; answer times are kept."""
    async with httpx.AsyncClient(base_url=base, timeout=30) as http:
        while time.monotonic() < end:
            start = time.perf_counter()
            response = await http.get("/api/status")
            samples.append(time.perf_counter() - start)
            if response.status_code >= 500:
                errors.append(f"GET /api/status: {response.status_code}")
            await asyncio.sleep(1.0)


async def sample_memory(pid: int, end: float, period_s: float, samples: list) -> None:
    process = psutil.Process(pid)
    start = time.monotonic()
    while True:
        samples.append((time.monotonic() - start, process.memory_info().rss / 2**20))
        if time.monotonic() >= end:
            return
        await asyncio.sleep(min(period_s, max(0.0, end - time.monotonic())))


async def run(args) -> None:
    port = free_port()
    base, url = f"http://127.0.0.1:{port}", f"ws://127.0.0.1:{port}/ws"
    with tempfile.TemporaryDirectory() as tmp:
        log_path = Path(args.log) if args.log else Path(tmp) / "serve.log"
        server = start_server(port, TOKEN, Path(tmp) / "soak.sqlite3", log_path, level=3, extra_args=("--log-level", "warning"))
        try:
            calibrated = httpx.post(f"{base}/api/calibrate", params={"wait": "true"}, headers=HEADERS, timeout=120).json()
            print(f"soak: armlab serve (sim, 30 fps camera), calibration {calibrated['job']['state']}; "
                  f"{NORMAL} viewers + {SLOW} slow (ack after {SLOW_ACK_S} s) + {STALLED} never reading + the controller; "
                  f"jobs: {args.job} L{args.level} back to back; {args.duration:.0f} s; {os.cpu_count()} CPUs (shared)", flush=True)
            end = time.monotonic() + args.duration
            controller = new_stats()
            normal = [new_stats() for _ in range(NORMAL)]
            slow = [new_stats() for _ in range(SLOW)]
            stalled = [new_stats() for _ in range(STALLED)]
            outcomes, job_errors, http_errors, status_s, memory = [], [], [], [], []
            server_process = psutil.Process(server.pid)
            server_process.cpu_percent()
            tasks = [
                viewer(f"{url}?token={TOKEN}&controller={CONTROLLER}", end, controller, heartbeat_s=0.1),
                *(viewer(url, end, stats) for stats in normal),
                *(viewer(url, end, stats, ack_delay_s=SLOW_ACK_S) for stats in slow),
                *(viewer(url, end, stats, read=False) for stats in stalled),
                jobs_back_to_back(base, end, args.job, args.level, outcomes, job_errors),
                poll_status(base, end, http_errors, status_s),
            ]

            async def memory_after_setup() -> None:
                await asyncio.sleep(min(20.0, args.duration / 4))  # every client connected, the first job running
                await sample_memory(server.pid, end, 15.0, memory)

            await asyncio.gather(*tasks, memory_after_setup())
            cpu_cores = server_process.cpu_percent() / 100
            final = httpx.get(f"{base}/api/status", timeout=30).json()
            if final.get("job") and final["job"]["id"] not in {o["id"] for o in outcomes}:
                outcomes.append({"id": final["job"]["id"], "state": final["job"]["state"], "message": final["job"]["message"]})
        finally:
            server.send_signal(2)
            try:
                server.wait(15)
            except subprocess.TimeoutExpired:
                server.kill()
        log_text = log_path.read_text(errors="replace")

    span = args.duration
    latency_ms = np.array(controller["latency_s"]) * 1000
    print(f"controller: {controller['frames'] / span:.1f} fps, capture-to-client latency p50 {np.percentile(latency_ms, 50):.1f} ms, "
          f"p95 {np.percentile(latency_ms, 95):.1f} ms, max {latency_ms.max():.1f} ms; telemetry {controller['telemetry'] / span:.1f} Hz")
    for name, group in (("viewers", normal), ("slow viewers", slow)):
        fps = np.array([stats["frames"] / span for stats in group])
        print(f"{name}: {fps.min():.1f}..{fps.max():.1f} fps (mean {fps.mean():.1f})")
    status_ms = np.array(status_s) * 1000
    print(f"GET /api/status from the controller: p50 {np.percentile(status_ms, 50):.1f} ms, p95 {np.percentile(status_ms, 95):.1f} ms, "
          f"max {status_ms.max():.1f} ms ({len(status_ms)} polls)")
    print(f"server CPU {cpu_cores:.2f} cores on average; load average {os.getloadavg()[0]:.1f}")
    print("server RSS: " + ", ".join(f"{t:.0f} s {mb:.0f} MB" for t, mb in memory))
    growth = (memory[-1][1] - memory[0][1]) / memory[0][1] * 100
    peak = (max(mb for _, mb in memory) - memory[0][1]) / memory[0][1] * 100
    print(f"memory growth from {memory[0][1]:.0f} MB: {growth:+.1f} % at the end, {peak:+.1f} % at the peak (target <= 10 %)")
    states = {}
    for outcome in outcomes:
        states[outcome["state"]] = states.get(outcome["state"], 0) + 1
    print(f"jobs: {len(outcomes)} ({', '.join(f'{n} {s}' for s, n in sorted(states.items()))})")
    for outcome in outcomes:
        if outcome["state"] != "succeeded":
            print(f"  {outcome['state']}: {outcome['message'][:160]}")
    lines = log_text.splitlines()
    log_errors = ["server log: " + " | ".join(lines[i : i + 12]) for i, line in enumerate(lines)
                  if "Traceback" in line or " ERROR" in line or line.startswith("ERROR")]
    errors = [*controller["errors"], *(e for s in normal + slow + stalled for e in s["errors"]), *http_errors, *job_errors, *log_errors]
    print(f"errors: {len(errors)} (target 0)")
    for error in errors[:20]:
        print(f"  {error[:1500]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=300.0, help="seconds (default 300)")
    parser.add_argument("--job", default="pick_sort")
    parser.add_argument("--level", type=int, default=3)
    parser.add_argument("--log", default=None, help="keep the server's log in this file")
    asyncio.run(run(parser.parse_args()))


if __name__ == "__main__":
    main()
