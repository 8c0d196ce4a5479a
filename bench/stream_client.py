"""A browser's stream in another process, for benches that run the station in their own (bench/recording.py):
StreamReader(ws_url) reads the station's /ws stream while its with block runs (bench/stream.py's view: colour with
its layers, every frame acked) and keeps the capture-to-client latency of every frame (ms; the two processes share
the machine's clock).

    python bench/stream_client.py ws://127.0.0.1:PORT/ws   (prints "connected", reads until a line on stdin)
"""

from __future__ import annotations

import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def stream_client(url: str) -> None:
    """Read the station's /ws stream (bench/stream.py's view), ack every frame, until a line on stdin; then print
    {"latency_ms": [...], "seconds": s} (capture-to-client, this process's clock)."""
    import asyncio
    import json

    from stream import LAYERS
    from websockets.asyncio.client import connect

    async def run() -> dict:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        threading.Thread(target=lambda: (sys.stdin.readline(), loop.call_soon_threadsafe(stop.set)), daemon=True).start()
        latency_ms = []
        async with connect(url, compression=None, max_size=None) as ws:
            await ws.send(json.dumps({"type": "view", "view": "color", "layers": LAYERS}))
            print("connected", flush=True)
            start = time.monotonic()
            while not stop.is_set():
                try:
                    message = await asyncio.wait_for(ws.recv(), timeout=0.5)
                except TimeoutError:
                    continue
                if isinstance(message, bytes):
                    now = time.time()
                    length = int.from_bytes(message[:4], "little")
                    header = json.loads(message[4: 4 + length])
                    latency_ms.append((now - header["capture_time_s"]) * 1000)
                    await ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
        return {"latency_ms": latency_ms, "seconds": time.monotonic() - start}

    print(json.dumps(asyncio.run(run())), flush=True)


class StreamReader:
    """This module in another process, reading the station's stream at `url` while the with block runs."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.result: dict = {"latency_ms": [], "seconds": 0.0}

    def __enter__(self):
        import subprocess

        self._process = subprocess.Popen([sys.executable, __file__, self.url], stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, text=True)
        assert self._process.stdout.readline().strip() == "connected"
        time.sleep(1.0)  # the first frames' queue drained
        return self

    def __exit__(self, *exc) -> None:
        import json

        out, _ = self._process.communicate("stop\n", timeout=60)
        self.result = json.loads(out.strip().splitlines()[-1])


if __name__ == "__main__":
    stream_client(sys.argv[1])
