"""Stream benchmark: capture-to-client latency, frame rate under load, server memory over time.

Starts `armlab serve` (simulation at 30 fps) as a subprocess on a free 127.0.0.1 port, calibrates it,
then measures with real websocket clients:
  1. one client: capture-to-client latency p50/p95 (target p95 ≤ 50 ms) and the telemetry rate;
  2. 10 clients of which 2 never read: the 8 readers' frame rates (target ≥ 25 fps) and the server's
     resident memory at the start and every 20 s until the end (target: flat).

    .venv/bin/python bench/stream.py [--duration 120] [--latency-duration 20]
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

LAYERS = ["tags", "detections", "grid"]


async def reader(url: str, duration_s: float, stats: dict) -> None:
    """Read and ack every frame; record latency (receive time - capture time) and telemetry count."""
    async with connect(url, compression=None, max_size=None) as ws:
        await ws.send(json.dumps({"type": "view", "view": "color", "layers": LAYERS}))
        end = time.monotonic() + duration_s
        while time.monotonic() < end:
            try:
                message = await asyncio.wait_for(ws.recv(), timeout=max(0.01, end - time.monotonic()))
            except TimeoutError:
                break
            now = time.time()
            if isinstance(message, bytes):
                length = int.from_bytes(message[:4], "little")
                header = json.loads(message[4 : 4 + length])
                stats["latency_s"].append(now - header["capture_time_s"])
                stats["seqs"].append(header["seq"])
                stats["frames"] += 1
                await ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
            elif json.loads(message)["type"] == "telemetry":
                stats["telemetry"] += 1


async def stalled(url: str, duration_s: float, stats: dict) -> None:
    """Connect, ask for the same view, never read or ack (the library's queue holds at most one message)."""
    async with connect(url, compression=None, max_size=None, max_queue=1) as ws:
        await ws.send(json.dumps({"type": "view", "view": "color", "layers": LAYERS}))
        await asyncio.sleep(duration_s)
        stats["connected"] = True


async def sample_memory(pid: int, duration_s: float, period_s: float, samples: list) -> None:
    process = psutil.Process(pid)
    start = time.monotonic()
    while True:
        elapsed = time.monotonic() - start
        samples.append((elapsed, process.memory_info().rss / 2**20))
        if elapsed >= duration_s:
            return
        await asyncio.sleep(min(period_s, max(0.0, duration_s - elapsed)))


def new_stats() -> dict:
    return {"latency_s": [], "frames": 0, "telemetry": 0, "seqs": []}


def camera_fps(stats: dict, duration_s: float) -> float:
    """The rate the camera produced frames at, from the sequence numbers the client saw."""
    seqs = stats["seqs"]
    return (seqs[-1] - seqs[0]) / duration_s if len(seqs) > 1 else 0.0


async def run(args) -> None:
    port, token = free_port(), "bench-token"
    with tempfile.TemporaryDirectory() as tmp:
        server = start_server(port, token, Path(tmp) / "bench.sqlite3", Path(tmp) / "serve.log")
        try:
            base = f"http://127.0.0.1:{port}"
            job = httpx.post(f"{base}/api/calibrate", params={"wait": "true"}, headers={"Authorization": f"Bearer {token}"}, timeout=60).json()
            count, deadline = 0, time.monotonic() + 10
            while count == 0 and time.monotonic() < deadline:
                time.sleep(0.2)
                count = httpx.get(f"{base}/api/detections").json()["count"]
            url = f"ws://127.0.0.1:{port}/ws"
            print(f"stream bench: armlab serve (sim 30 fps, 1280x720, pick_sort L2 scene), calibration {job['job']['state']}, "
                  f"{count} blocks detected; view color + {','.join(LAYERS)}")
            print(f"cpu: {os.cpu_count()} cores (shared)")

            one = new_stats()
            await reader(url, args.latency_duration, one)
            latency_ms = np.array(one["latency_s"]) * 1000
            print(f"1 client, {args.latency_duration:.0f} s: {one['frames']} frames ({one['frames'] / args.latency_duration:.1f} fps; "
                  f"the camera produced {camera_fps(one, args.latency_duration):.1f} fps), telemetry {one['telemetry'] / args.latency_duration:.1f} Hz")
            print(f"  capture-to-client latency: p50 {np.percentile(latency_ms, 50):.1f} ms, p95 {np.percentile(latency_ms, 95):.1f} ms, "
                  f"max {latency_ms.max():.1f} ms (target p95 <= 50 ms)")

            readers = [new_stats() for _ in range(8)]
            stalls = [{"connected": False} for _ in range(2)]
            memory: list = []
            server_process = psutil.Process(server.pid)
            server_process.cpu_percent()
            await asyncio.gather(
                *(reader(url, args.duration, stats) for stats in readers),
                *(stalled(url, args.duration, stats) for stats in stalls),
                sample_memory(server.pid, args.duration, 20.0, memory),
            )
            fps = np.array([stats["frames"] / args.duration for stats in readers])
            latency_ms = np.concatenate([np.array(stats["latency_s"]) for stats in readers]) * 1000
            print(f"10 clients (8 reading, 2 never reading), {args.duration:.0f} s:")
            produced = max(camera_fps(stats, args.duration) for stats in readers)
            print(f"  readers' frame rate: min {fps.min():.1f}, mean {fps.mean():.1f}, max {fps.max():.1f} fps (target >= 25 fps); "
                  f"the camera produced {produced:.1f} fps, so readers got {100 * fps.mean() / max(produced, 1e-9):.0f}% of its frames")
            print(f"  server process CPU: {server_process.cpu_percent() / 100:.2f} cores on average; machine load average "
                  f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
            print(f"  readers' latency: p50 {np.percentile(latency_ms, 50):.1f} ms, p95 {np.percentile(latency_ms, 95):.1f} ms; "
                  f"telemetry {np.mean([s['telemetry'] for s in readers]) / args.duration:.1f} Hz per reader")
            print("  server RSS: " + ", ".join(f"{t:.0f} s {mb:.1f} MB" for t, mb in memory))
            print(f"  memory change start -> end: {memory[-1][1] - memory[0][1]:+.1f} MB (target: flat)")
        finally:
            server.terminate()
            try:
                server.wait(15)
            except subprocess.TimeoutExpired:
                server.kill()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=120.0, help="10-client phase length in seconds (default 120)")
    parser.add_argument("--latency-duration", type=float, default=20.0, help="1-client phase length in seconds (default 20)")
    asyncio.run(run(parser.parse_args()))


if __name__ == "__main__":
    main()
