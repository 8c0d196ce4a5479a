"""Live Foxglove benchmark (issue 23 item 1): what `armlab serve --foxglove` costs the station.

1. CPU with bench/recording.py's replay station (the simulated camera's frames at --fps with their depth, the RX200
   in a sine at 100 Hz readings) and a LiveServer attached with the product's foxglove: config: (a) no client, (b) one
   client in another process subscribed to every channel (tests/server/foxglove_ws.py's client). Figures: the live
   sampler threads' CPU (% of one core), the station process's CPU against the same seconds without a live server
   (the SDK's own sending threads included), a 1 ms Python ticker's lateness (a thread kept from the GIL), and at the
   client: messages per second per topic and the stream latency (receive time - the message's log time, taken when
   it was sampled, before its JPEG encode), p50 / p95 / max ms.
2. E-stop latency (bench/estop.py's rig and press, as bench/recording.py): no live server, then a live server with
   one client subscribed to every channel; answer and halt ms, p50 / p95 / max.

    PYTHONPATH=$PWD .venv/bin/python bench/foxglove_live.py [--seconds 20] [--trials 10]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "server"))

import psutil  # noqa: E402

from armlab.recording import TOPICS  # noqa: E402
from armlab.recording.live import LiveServer  # noqa: E402
from armlab.station.config import FoxgloveConfig  # noqa: E402
from recording import ReplayStation, Ticker, estop_rig, figures, rendered_frames, thread_cpu_s  # noqa: E402

LIVE_THREADS = {"foxglove-sampler", "foxglove-images"}


def run_client(url: str, seconds: float) -> None:
    """In its own process: subscribe to every channel for `seconds`; print per-topic counts and latencies (JSON)."""
    from foxglove_ws import FoxgloveClient

    with FoxgloveClient(url) as client:
        client.subscribe(sorted(TOPICS))
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                client._read(max(0.01, end - time.monotonic()))
            except TimeoutError:
                pass
        topics = {channel["id"]: channel["topic"] for channel in client.channels.values()}
        result: dict[str, dict] = {}
        for channel_id, log_ns, payload, received_s in client.messages:
            entry = result.setdefault(topics[channel_id], {"count": 0, "bytes": 0, "latency_ms": []})
            entry["count"] += 1
            entry["bytes"] += len(payload)
            entry["latency_ms"].append((received_s * 1e9 - log_ns) / 1e6)
        received = [message[3] for message in client.messages]
        span_s = max(received) - min(received) if received else 0.0
    print(json.dumps({"span_s": span_s, "topics": result}), flush=True)


def start_client(url: str, seconds: float) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, __file__, "--client", url, "--seconds", str(seconds)], env=env,
                            stdout=subprocess.PIPE, text=True)


def wait_subscribed(server: LiveServer, timeout_s: float = 120.0) -> None:
    """Until the client process has subscribed to every channel (a loaded machine starts it slowly)."""
    deadline = time.monotonic() + timeout_s
    while not all(channel.has_sinks() for channel in vars(server.channels).values()):
        if time.monotonic() > deadline:
            raise RuntimeError("the client did not subscribe")
        time.sleep(0.05)


def process_cpu_s() -> float:
    times = psutil.Process().cpu_times()
    return times.user + times.system


def cpu_case(frames: list, seconds: float, fps: float, with_client: bool) -> dict:
    """The replay station alone for `seconds`, then with a live server (and a client) for as long."""
    with ReplayStation(frames, fps) as station:
        time.sleep(0.5)
        cpu0 = process_cpu_s()
        with Ticker() as idle_ticker:
            time.sleep(seconds)
        baseline_s = process_cpu_s() - cpu0
        server = LiveServer("127.0.0.1", free_port(), FoxgloveConfig()).start()
        client = None
        try:
            server.attach(station)
            if with_client:
                client = start_client(server.url, seconds + 1.0)
                wait_subscribed(server)
            time.sleep(0.5)
            threads0, cpu1, wall0 = thread_cpu_s(LIVE_THREADS), process_cpu_s(), time.monotonic()
            with Ticker() as ticker:
                time.sleep(seconds)
            threads1, cpu2, wall = thread_cpu_s(LIVE_THREADS), process_cpu_s(), time.monotonic() - wall0
            received = json.loads(client.communicate(timeout=60)[0]) if client is not None else {}
            counts = dict(server.sampler.counts)
        finally:
            if client is not None and client.poll() is None:
                client.kill()
            server.stop()
    return {"sampler_percent": 100 * (threads1 - threads0) / wall, "process_percent_added": 100 * ((cpu2 - cpu1) / wall - baseline_s / seconds),
            "late_without": idle_ticker.figures(), "late_with": ticker.figures(), "received": received, "logged": counts}


def free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def estop_latency(trials: int, with_live: bool, camera_fps: float) -> tuple[list[float], list[float], list[float], int]:
    """(answers, halts (wall), halts on the simulation's clock (request to the control tick that applied it), messages)."""
    from estop import moving_presses

    answers, halts, halts_sim, messages = [], [], [], 0
    with tempfile.TemporaryDirectory(prefix="armlab-bench-fox-") as tmp:
        rig = estop_rig(Path(tmp), camera_fps)
        server = client = None
        try:
            if with_live:
                server = LiveServer("127.0.0.1", free_port(), FoxgloveConfig()).start()
                server.attach(rig.station)
                client = start_client(server.url, 3600)
                wait_subscribed(server)
            answers, halts, halts_sim = moving_presses(rig, trials)
            if server is not None:
                messages = sum(server.sampler.counts.values())
        finally:
            if client is not None:
                client.kill()
            if server is not None:
                server.stop()
            rig.close()
    return answers, halts, halts_sim, messages


def latency_text(entry: dict) -> str:
    ordered = sorted(entry["latency_ms"])
    if not ordered:
        return "none"
    p95 = ordered[min(len(ordered) - 1, math.ceil(0.95 * (len(ordered) - 1)))]
    return f"p50 {ordered[len(ordered) // 2]:.1f} p95 {p95:.1f} max {ordered[-1]:.1f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--fps", type=float, default=30.0, help="colour frames per second replayed")
    parser.add_argument("--trials", type=int, default=10, help="e-stop presses without and with a live client")
    parser.add_argument("--estop-camera-fps", type=float, default=30.0)
    parser.add_argument("--no-estop", action="store_true")
    parser.add_argument("--estop-only", action="store_true")
    parser.add_argument("--live-first", action="store_true", help="the e-stop presses with the live server first")
    parser.add_argument("--client", default=None, help=argparse.SUPPRESS)  # the client process
    args = parser.parse_args()
    if args.client:
        run_client(args.client, args.seconds)
        return
    print(f"bench/foxglove_live.py on {os.cpu_count()} CPUs (load average {os.getloadavg()[0]:.2f})", flush=True)
    frames = rendered_frames(12)
    config = FoxgloveConfig()
    print(f"replay: {frames[0].color_bgr.shape[1]}x{frames[0].color_bgr.shape[0]} colour + depth at {args.fps:g} fps, joints 100 Hz; "
          f"foxglove: camera {config.camera_rate_hz:g} fps x{config.camera_scale:g} q{config.jpeg_quality}, depth {config.depth_rate_hz:g} Hz, "
          f"joints {config.joint_rate_hz:g} Hz, transforms {config.transforms_rate_hz:g} Hz", flush=True)
    for with_client in () if args.estop_only else (False, True):
        result = cpu_case(frames, args.seconds, args.fps, with_client)
        label = "one client subscribed to every channel" if with_client else "no client"
        print(f"live server, {label}: sampler threads {result['sampler_percent']:.1f} % of one core; the process "
              f"{result['process_percent_added']:+.1f} % of one core against the replay alone; 1 ms ticker late by "
              f"{result['late_with']} (without the server: {result['late_without']}); messages logged "
              f"{sum(result['logged'].values())}", flush=True)
        span_s = result["received"].get("span_s") or 1.0
        for topic, entry in sorted(result["received"].get("topics", {}).items()):
            print(f"    {topic}: {entry['count'] / span_s:.1f} msg/s, {entry['bytes'] / span_s / 1e6:.2f} MB/s, "
                  f"latency {latency_text(entry)}", flush=True)
    order = (True, False) if args.live_first else (False, True)
    for with_live in () if args.no_estop else order:
        answers, halts, halts_sim, messages = estop_latency(args.trials, with_live, args.estop_camera_fps)
        label = f"live server + 1 client ({messages} messages)" if with_live else "no live server"
        print(f"e-stop, {label}, {args.trials} presses (ms): answer {figures(answers)} | halt {figures(halts)} | "
              f"halt on the sim clock {figures(halts_sim)} (load average {os.getloadavg()[0]:.1f})", flush=True)


if __name__ == "__main__":
    main()
