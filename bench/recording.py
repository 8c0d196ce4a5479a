"""Recording benchmark (issue 23 item 2): what an MCAP recording costs the station.

1. CPU and size at 30 fps colour + 100 Hz joints: a replay station publishes the simulated camera's own frames
   (REPLAY_FRAMES of them rendered once, each with its own sensor noise, replayed in a loop at --fps with their
   depth) and an arm moving in a sine at 100 Hz readings (the RX200 model, so the transforms are real); the recorder
   records it for --seconds with the product's config (recording: JPEG quality 80, depth 5 Hz, transforms 30 Hz).
   Each frame is published as a fresh copy, as a camera writes it into new arrays (ReplayStation._camera; until
   2026-12-04 the stored frames themselves, read cold from memory by the recorder).
   Figures: the recording's CPU (% of one core; target <= 10 %), MB per minute, sustained write throughput,
   messages per second, and the rates actually recorded (a saturated machine can starve the replay or the sampler,
   and a recording that keeps fewer samples costs less: read the CPU with them).
   The recording's CPU is every thread of the process except the replay station's camera, the ticker and the main
   thread (psutil per-thread times over the same seconds): the recorder's two threads and the helper threads their
   work wakes. Until 2026-12-04 it counted the two named threads only, and missed OpenCV's worker thread: a
   cv2.resize of a 640x360 output is split across OpenCV's pool, whose worker then spins waiting for more work
   (measured: 2.3 % of one core at 30 fps, as much as the resize itself). The recorder threads' own figure is
   printed too. And the replay looped 12 frames until then: a 1 MB MCAP chunk of colour alone holds ~36 JPEGs, so
   zstd found each frame three times over and MB/min (and the compression's CPU) were those of a repeating video,
   not of a camera.
2. Peak write throughput: the same messages logged back to back (no rate limit) on one thread: MB/s and colour
   frames/s the encoder and writer keep up with.
4. LeRobot export (--lerobot; --lerobot-only skips 1-3): a --lerobot-seconds recording of the replay station (its
   real sampler: joints and commands at 100 Hz, camera at --fps) exported as a LeRobot v3.0 dataset at 30 fps, timed
   (--lerobot-runs exports, each a new folder); then, with --lerobot-python (a Python with LeRobot and torch, e.g.
   /work/lerobot-venv/bin/python), bench/lerobot_load_check.py loads it with LeRobot's LeRobotDataset and compares every
   frame with the recording (read here by armlab's reader: the joints, gripper and commands newest at or before each
   frame time; the colour frame shown then, as 8x8-px block means).
3. E-stop and stream latency with and without a recording running: bench/estop.py's rig (a real-time simulated
   workcell, the station, the REST server in this process; here the camera watchdog at 10 s, so a loaded machine
   does not fault the station) and its press(): the arm set moving, the e-stop pressed by Station.estop(); answer
   and halt times (ms), p50 / p95 / max, --trials each. Meanwhile a websocket client in another process (as a
   browser, bench/stream.py's view: colour with its layers) reads the station's /ws stream and acks every frame:
   capture-to-client latency (ms) and frames per second over the same presses.

    PYTHONPATH=$PWD .venv/bin/python bench/recording.py [--seconds 30] [--trials 15] [--defaults-only] [--no-estop]
    PYTHONPATH=$PWD .venv/bin/python bench/recording.py --lerobot-only [--lerobot-python /work/lerobot-venv/bin/python]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
import psutil  # noqa: E402

from armlab.devices.arm import JointState  # noqa: E402
from armlab.recording import RecordingLibrary, summarize  # noqa: E402
from armlab.station.config import RecordingConfig  # noqa: E402
from armlab.station.slots import EventLog, NewestSlot  # noqa: E402
from armlab.station.states import State  # noqa: E402


class ReplayStation:
    """What the recorder reads of a station: the RX200's model, an arm in a sine, frames replayed at `fps`."""

    has_arm = True
    backend = "bench"
    calibration = None

    class config:  # noqa: N801
        workcell = "rx200_armlab"

    class gripper:  # noqa: N801
        class _State:
            width_m, holding, command = 0.03, False, "release"

        @classmethod
        def read_state(cls):
            return cls._State()

    def __init__(self, frames: list, fps: float) -> None:
        from armlab.kinematics import load_arm

        self.model = load_arm("rx200")
        self.events, self.frames, self.perception = EventLog(), NewestSlot(), NewestSlot()
        self.state = State.IDLE
        self.arm = self
        self.intrinsics = self
        self._frames, self._period_s = frames, 1.0 / fps
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._camera, name="replay-camera", daemon=True)
        self._start_s = time.time()

    def current(self):
        return self._frames[0].intrinsics

    def current_job(self):
        return None

    def commanded_joints_rad(self):
        return self._q(time.time())

    def _q(self, t_s: float) -> np.ndarray:
        return np.asarray(self.model.home_rad) + 0.3 * math.sin(t_s - self._start_s)

    def read_joint_state(self) -> JointState:
        now = time.time()
        return JointState(self._q(now), np.full(self.model.dof, 0.3 * math.cos(now - self._start_s)), now)

    def _camera(self) -> None:
        """Each frame published as a fresh copy: a camera writes every frame into new arrays just before it publishes
        it (SimCamera.publish adds its noise into new ones, the threaded cameras copy the driver's buffer), so the
        recorder reads it from the cache; the stored frames themselves (rendered long ago, 220 MB) would be read from
        memory, a cost no station has (measured: +0.5 % of one core on the image thread)."""
        from dataclasses import replace

        index, next_s = 0, time.monotonic()
        while not self._stop.is_set():
            frame = self._frames[index % len(self._frames)]
            self.frames.publish(replace(frame, color_bgr=frame.color_bgr.copy(), depth_mm=None if frame.depth_mm is None else frame.depth_mm.copy(),
                                        timestamp_s=time.time(), sequence=index))
            index += 1
            next_s += self._period_s
            self._stop.wait(max(0.0, next_s - time.monotonic()))

    @property
    def camera_thread_id(self) -> int | None:
        return self._thread.native_id

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5)


def rendered_frames(count: int) -> list:
    """`count` frames of the simulated camera (fast mode: the arm still, the pick_sort L2 scene)."""
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.scene import generate_scene

    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=1), scene=generate_scene("pick_sort", level=2, seed=1)) as cell:
        return [cell.capture_next_frame() for _ in range(count)]


REPLAY_FRAMES = 48  # 1.6 s at 30 fps: more than any 1 MB chunk holds (~36 640x360 JPEGs), so no chunk repeats a frame


def thread_cpu_s(names: set[str]) -> float:
    """CPU seconds (user + system) of this process's threads with those names."""
    ids = {thread.native_id for thread in threading.enumerate() if thread.name in names}
    return sum(t.user_time + t.system_time for t in psutil.Process().threads() if t.id in ids)


def cpu_by_thread_s() -> dict[int, float]:
    """CPU seconds (user + system) of every thread of this process, by native thread id."""
    return {t.id: t.user_time + t.system_time for t in psutil.Process().threads()}


def cpu_except_s(before: dict[int, float], after: dict[int, float], excluded: set[int]) -> float:
    """CPU seconds between two cpu_by_thread_s() of the threads not in `excluded` (a thread started in between
    counts from 0)."""
    return sum(cpu - before.get(tid, 0.0) for tid, cpu in after.items() if tid not in excluded)


def cpu_and_size(frames: list, seconds: float, fps: float, **config) -> dict:
    with tempfile.TemporaryDirectory(prefix="armlab-bench-rec-") as tmp, ReplayStation(frames, fps) as station:
        library = RecordingLibrary(tmp, RecordingConfig(**{"min_free_mb": 0, **config}))
        names = {"recording-sampler", "recording-images"}
        process = psutil.Process()
        time.sleep(0.5)
        before = process.cpu_times()
        with Ticker() as idle_ticker:
            time.sleep(seconds)  # the replay station alone: the process's CPU without a recording
        after = process.cpu_times()
        idle_cpu_s = (after.user + after.system) - (before.user + before.system)
        info = library.start(station)
        time.sleep(0.5)  # the threads exist; measured from here
        with Ticker() as ticker:
            not_recording = {threading.main_thread().native_id, station.camera_thread_id, ticker.thread_id}
            cpu0, wall0, size0, process0 = thread_cpu_s(names), time.monotonic(), library.active()["size_bytes"], process.cpu_times()
            threads0 = cpu_by_thread_s()
            time.sleep(seconds)
            threads1 = cpu_by_thread_s()
            cpu1, wall1, size1, process1 = thread_cpu_s(names), time.monotonic(), library.active()["size_bytes"], process.cpu_times()
        ended = library.stop()
        summary = summarize(Path(tmp) / f"{info['id']}.mcap")
    wall = wall1 - wall0
    return {
        "cpu_percent_of_one_core": 100 * cpu_except_s(threads0, threads1, not_recording) / wall,
        "recorder_threads_percent": 100 * (cpu1 - cpu0) / wall,
        "process_percent_added": 100 * ((process1.user + process1.system - process0.user - process0.system) / wall - idle_cpu_s / seconds),
        "mb_per_minute": (size1 - size0) / 1e6 / wall * 60,
        "write_mb_s": (size1 - size0) / 1e6 / wall, "messages_per_s": summary.message_count / summary.duration_s,
        "colour_fps": summary.topics.get("/camera/color/compressed", {"count": 0})["count"] / summary.duration_s,
        "joint_hz": summary.topics["/joint_states"]["count"] / summary.duration_s,
        "depth_fps": summary.topics.get("/camera/depth", {"count": 0})["count"] / summary.duration_s, "file_mb": ended["size_bytes"] / 1e6,
        "duration_s": summary.duration_s, "complete": summary.complete,
        "late_without": idle_ticker.figures(), "late_with": ticker.figures(),
    }


def peak_throughput(frames: list, count: int) -> dict:
    """Colour frames (JPEG-encoded) and depth images logged back to back on one thread, as the recorder writes them."""
    import cv2

    from armlab.recording import StationChannels
    from armlab.recording import channels as ch
    from armlab.recording.mcap_file import McapFile

    with tempfile.TemporaryDirectory(prefix="armlab-bench-peak-") as tmp:
        path = Path(tmp) / "peak.mcap"
        file = McapFile(path, 1024 * 1024)
        channels = StationChannels.on_file(file)
        start_cpu, start = time.process_time(), time.monotonic()
        for index in range(count):
            frame = frames[index % len(frames)]
            now = time.time_ns()
            ok, jpeg = cv2.imencode(".jpg", frame.color_bgr, [int(cv2.IMWRITE_JPEG_QUALITY), 80])
            channels.color.log(ch.compressed_image(now, jpeg.tobytes()), log_time=now)
            if index % 6 == 0:  # depth at a sixth of the colour rate, as 5 Hz to 30 fps
                channels.depth.log(ch.depth_image(now, frame.depth_mm), log_time=now)
        file.close()
        wall, cpu = time.monotonic() - start, time.process_time() - start_cpu
        size = path.stat().st_size
    return {"mb_s": size / 1e6 / wall, "colour_fps": count / wall, "cpu_s_per_frame": cpu / count}


class Ticker:
    """A Python thread that sleeps 1 ms at a time, as the station's threads wait and wake: how late it wakes (ms)
    says how long other threads (a recorder holding the GIL) kept it from running."""

    def __init__(self) -> None:
        self.late_ms: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        last = time.perf_counter()
        while not self._stop.is_set():
            time.sleep(0.001)
            now = time.perf_counter()
            self.late_ms.append((now - last - 0.001) * 1000)
            last = now

    @property
    def thread_id(self) -> int | None:
        return self._thread.native_id

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5)

    def figures(self) -> str:
        ordered = sorted(self.late_ms)
        return f"p50 {ordered[len(ordered) // 2]:.2f} p99 {ordered[int(0.99 * (len(ordered) - 1))]:.2f} max {ordered[-1]:.2f} ms"


def recorded_camera(folder: Path, frames: list, fps: float):
    """A RecordedCamera playing `frames` (written to `folder` as PNG pairs with their intrinsics) at `fps`, each pair
    held for a second: frames that cost the CPU only their copy, as a real camera's arrive, unlike the simulated
    camera's renders (~55 ms of CPU each here), which the recorder's CPU would be taken from."""
    import json

    import cv2

    from armlab.devices.recorded.camera_recorded import RecordedCamera
    from armlab.devices.recorded.configuration_recorded import RecordedCameraConfig

    folder.mkdir(parents=True, exist_ok=True)
    for index, frame in enumerate(frames):
        cv2.imwrite(str(folder / f"image_{index:03d}.png"), frame.color_bgr)
        cv2.imwrite(str(folder / f"depth_{index:03d}.png"), frame.depth_mm)
    intr = frames[0].intrinsics
    (folder / "intrinsics.json").write_text(json.dumps({"K": intr.K.tolist(), "dist": list(intr.dist), "image_size": [intr.width, intr.height]}))
    camera = RecordedCamera(RecordedCameraConfig(source=str(folder), fps=fps, seconds_per_pair=1.0))
    camera.connect()
    return camera


def estop_rig(tmp: Path, camera_fps: float, stream_frames: list | None = None):
    """bench/estop.py's Rig (cell, station, REST server; its idle() and press()), the camera at camera_fps and the camera
    watchdog at 10 s: a 30 fps render on a loaded 2-core machine starves and faults the station (camera lost).
    stream_frames: the station's camera plays these instead (recorded_camera, at camera_fps) and the simulated one
    renders at 1 fps for nobody."""
    import uvicorn
    from estop import Rig, free_port, wait_for

    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.kinematics import load_arm
    from armlab.station import Station, StationConfig
    from server.app import create_app

    rig = Rig.__new__(Rig)
    rig.db = tmp / "bench.sqlite3"
    rig.cell = SimWorkcell(SimWorkcellConfig(realtime=True, seed=2, camera_fps=1.0 if stream_frames else camera_fps))
    rig.cell.start()
    camera = recorded_camera(tmp / "camera", stream_frames, camera_fps) if stream_frames else rig.cell.camera

    def factory():
        rig.station = Station(rig.cell.arm, rig.cell.gripper, camera, model=load_arm("rx200"),
                              config=StationConfig(database_path=str(rig.db), camera_timeout_s=10.0), sim=rig.cell)
        rig.station.start()
        return rig.station

    rig.app = create_app(station_factory=factory, token="bench-recording", recordings_dir=tmp / "recordings")
    port = free_port()
    rig.server = uvicorn.Server(uvicorn.Config(rig.app, host="127.0.0.1", port=port, log_level="error", lifespan="on"))
    rig.thread = threading.Thread(target=rig.server.run, daemon=True)
    rig.thread.start()
    wait_for(lambda: rig.server.started, 60, 0.05)
    rig.http = None
    rig.ws_url = f"ws://127.0.0.1:{port}/ws"
    rig.close = lambda: (setattr(rig.server, "should_exit", True), rig.thread.join(20), rig.cell.close(),
                         camera.close() if stream_frames else None)
    return rig


def estop_latency(trials: int, record: bool, camera_fps: float, replay: list, recorded_stream: bool = False) -> tuple[list[float], list[float], int, dict]:
    """bench/estop.py's press (Station.estop()), the arm moving (its load_idle), with or without a recording running
    (started through the app's library, as POST /api/recordings/start does). The simulated camera of a loaded 2-core
    machine renders a few frames a second, so with `replay` frames a second recorder records a replay station at
    30 fps in the same process too: the recorder's full load. Returns answers, halts (ms), colour frames recorded,
    and the stream client's {"latency_ms", "seconds"} over the presses."""
    import contextlib

    from estop import moving_presses
    from stream_client import StreamReader

    answers, halts, frames, stream = [], [], 0, {}
    with tempfile.TemporaryDirectory(prefix="armlab-bench-estop-") as tmp, contextlib.ExitStack() as stack:
        rig = estop_rig(Path(tmp), camera_fps, replay if recorded_stream else None)
        library = rig.app.state.recordings
        full = RecordingLibrary(Path(tmp) / "replay", RecordingConfig(min_free_mb=0))
        second = bool(replay) and not recorded_stream  # the station's own camera at 30 fps is the recorder's full load
        try:
            if record:
                library.start(rig.station)
                if second:
                    full.start(stack.enter_context(ReplayStation(replay, 30.0)))
            with StreamReader(rig.ws_url) as reader:
                answers, halts, _ = moving_presses(rig, trials)
            stream = reader.result
            if record:
                frames = library.stop()["topics"].get("/camera/color/compressed", 0)
                if second:
                    frames += full.stop()["topics"].get("/camera/color/compressed", 0)
        finally:
            full.close()
            rig.close()
    return answers, halts, frames, stream


def lerobot_expected(path: Path, fps: int, block: int = 8) -> dict:
    """What a LeRobot export of `path` must hold, from the MCAP by armlab's reader (not the exporter's resampling): per
    frame time t0 + k / fps (t0: every channel has a value) the newest joints, gripper, command at or before it (a
    command older than 1.5 s: the measured joints at the next frame) and the colour frame shown, as block means."""
    import cv2

    from armlab.recording import iter_messages

    def ns(message) -> int:
        return message.timestamp.seconds * 10**9 + message.timestamp.nanos

    joints, grippers, commands, colours = [], [], [], []
    for topic, _, _, message in iter_messages(path, {"/joint_states", "/gripper", "/joint_commands", "/camera/color/compressed"}):
        if topic == "/joint_states":
            joints.append((ns(message), [joint.position for joint in message.joints]))
        elif topic == "/gripper":
            grippers.append((round(message["time_s"] * 1e9), message["width_m"], 1.0 if message["command"] == "grasp" else 0.0))
        elif topic == "/joint_commands":
            commands.append((ns(message), [joint.position for joint in message.joints]))
        else:
            colours.append((ns(message), bytes(message.data)))
    t0 = max(joints[0][0], grippers[0][0], colours[0][0])
    end = min(joints[-1][0], grippers[-1][0], colours[-1][0])
    count = (end - t0) * fps // 10**9 + 1
    times = [t0 + k * 10**9 // fps for k in range(count)]

    joint_ns, command_ns, gripper_ns, colour_ns = ([s[0] for s in x] for x in (joints, commands, grippers, colours))
    state, action, grids = [], [], []
    for k, t in enumerate(times):
        q = joints[int(np.searchsorted(joint_ns, t, side="right")) - 1][1]
        g = grippers[int(np.searchsorted(gripper_ns, t, side="right")) - 1]
        state.append([*q, g[1]])
        c = int(np.searchsorted(command_ns, t, side="right")) - 1 if commands else -1
        if c >= 0 and t - command_ns[c] <= 1_500_000_000:
            commanded = commands[c][1]
        else:
            commanded = joints[int(np.searchsorted(joint_ns, times[min(k + 1, count - 1)], side="right")) - 1][1]
        action.append([*commanded, g[2]])
        jpeg = colours[int(np.searchsorted(colour_ns, t, side="right")) - 1][1]
        rgb = cv2.cvtColor(cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
        h, w = rgb.shape[0] - rgb.shape[0] % 2, rgb.shape[1] - rgb.shape[1] % 2
        image = rgb[: h - h % block, : w - w % block].transpose(2, 0, 1).astype(np.float32) / 255.0
        grids.append(image.reshape(3, image.shape[1] // block, block, image.shape[2] // block, block).mean(axis=(2, 4)))
    return {"state": np.float32(state), "action": np.float32(action), "image_grid": np.stack(grids), "block": np.int64(block)}


def lerobot_export(frames: list, seconds: float, fps: float, runs: int, python: str | None) -> None:
    """Part 4 of the module docstring."""
    import subprocess

    from armlab.recording.lerobot import export_lerobot

    with tempfile.TemporaryDirectory(prefix="armlab-bench-lerobot-") as tmp, ReplayStation(frames, fps) as station:
        library = RecordingLibrary(Path(tmp) / "recordings", RecordingConfig(min_free_mb=0))
        info = library.start(station, label="bench: the replay station's sine")
        time.sleep(seconds)
        info = library.stop()
        path = library.path(info["id"])
        print(f"lerobot: recorded {info['duration_s']:.1f} s ({info['size_bytes'] / 1e6:.1f} MB; colour "
              f"{info['topics'].get('/camera/color/compressed', 0)}, joints {info['topics'].get('/joint_states', 0)}, "
              f"commands {info['topics'].get('/joint_commands', 0)} messages)", flush=True)
        times = []
        for run in range(runs):
            result = export_lerobot([path], Path(tmp) / f"dataset-{run}", fps=30)
            times.append(result.seconds)
            sizes = {part: sum(f.stat().st_size for f in (result.out / part).rglob("*") if f.is_file()) / 1e6
                     for part in ("data", "videos", "meta")}
            print(f"lerobot: export {run + 1}/{runs} of the {info['duration_s']:.1f} s episode: {result.seconds:.2f} s "
                  f"({result.frames} frames at {result.fps} fps, camera {result.video_size_px[0]}x{result.video_size_px[1]} "
                  f"{result.video_codec}; data {sizes['data']:.2f} MB, video {sizes['videos']:.2f} MB, meta {sizes['meta']:.2f} MB; "
                  f"{result.action_from_measured_frames} frames' action from the measured joints)", flush=True)
        print(f"lerobot: export time for a {info['duration_s']:.0f} s episode: median {statistics.median(times):.2f} s "
              f"(min {min(times):.2f}, max {max(times):.2f}) over {runs} run(s)", flush=True)
        if python:
            expected = Path(tmp) / "expected.npz"
            np.savez(expected, **lerobot_expected(path, 30))
            check = subprocess.run([python, str(Path(__file__).with_name("lerobot_load_check.py")), str(Path(tmp) / "dataset-0"),
                                    str(expected)], capture_output=True, text=True, timeout=1800)
            print("\n".join("lerobot load check: " + line for line in check.stdout.splitlines()), flush=True)
            if check.returncode != 0:
                print(f"lerobot load check exited {check.returncode}:\n{check.stderr[-3000:]}", flush=True)


def figures(values: list[float]) -> str:
    ordered = sorted(values)
    p95 = ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))]
    return f"p50 {statistics.median(ordered):6.2f}  p95 {p95:6.2f}  max {ordered[-1]:6.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=30.0, help="recording length for the CPU and size figures")
    parser.add_argument("--fps", type=float, default=30.0, help="colour frames per second replayed")
    parser.add_argument("--trials", type=int, default=15, help="e-stop presses with and without a recording")
    parser.add_argument("--peak-frames", type=int, default=150)
    parser.add_argument("--estop-only", action="store_true", help="only the e-stop comparison")
    parser.add_argument("--no-estop", action="store_true", help="no e-stop comparison")
    parser.add_argument("--defaults-only", action="store_true", help="part 1 at the config's defaults only (no other cases)")
    parser.add_argument("--estop-camera-fps", type=float, default=30.0, help="the station's camera rate in the e-stop rig")
    parser.add_argument("--stream-camera", choices=("sim", "recorded"), default="sim",
                        help="the e-stop rig's camera: the simulated one (renders cost ~55 ms of CPU each) or the rendered "
                             "frames played as a recorded camera (a frame costs its copy, as a real camera's)")
    parser.add_argument("--lerobot", action="store_true", help="also the LeRobot export (part 4)")
    parser.add_argument("--lerobot-only", action="store_true", help="only the LeRobot export (part 4)")
    parser.add_argument("--lerobot-seconds", type=float, default=60.0, help="the exported recording's length")
    parser.add_argument("--lerobot-runs", type=int, default=3, help="exports timed")
    parser.add_argument("--lerobot-python", default=None, help="a Python with LeRobot: load the export with LeRobotDataset")
    args = parser.parse_args()
    print(f"bench/recording.py on {os.cpu_count()} CPUs (load average {os.getloadavg()[0]:.2f})", flush=True)
    frames = rendered_frames(REPLAY_FRAMES)
    if frames:
        height, width = frames[0].color_bgr.shape[:2]
        print(f"frames: {width}x{height} colour + depth from the simulated camera, replayed at {args.fps:g} fps; joints at 100 Hz")

    if args.lerobot or args.lerobot_only:
        lerobot_export(frames, args.lerobot_seconds, args.fps, args.lerobot_runs, args.lerobot_python)
        if args.lerobot_only:
            return
    default = RecordingConfig()
    cases = [("the config's defaults", {}), ("colour and joints (no depth)", {"depth_rate_hz": 0.0}),
             ("full size (camera_scale 1)", {"camera_scale": 1.0}),
             ("joints, gripper, transforms only (no camera)", {"camera_rate_hz": 0.0, "depth_rate_hz": 0.0})]
    for name, config in [] if args.estop_only else cases[:1] if args.defaults_only else cases:
        settings = {**default.model_dump(), **config}
        result = cpu_and_size(frames, args.seconds, args.fps, **config)
        print(f"{name}: camera {settings['camera_rate_hz']:g} fps x{settings['camera_scale']:g} JPEG q{settings['jpeg_quality']}, depth "
              f"{settings['depth_rate_hz']:g} Hz, joints {settings['joint_rate_hz']:g} Hz; {result['duration_s']:.1f} s "
              f"({'complete' if result['complete'] else 'NOT complete'}): recording {result['cpu_percent_of_one_core']:.1f} % "
              f"of one core (target <= 10 %; its two threads {result['recorder_threads_percent']:.1f} %), the process "
              f"{result['process_percent_added']:+.1f} % against the same seconds without recording; {result['mb_per_minute']:.1f} MB/min; "
              f"sustained write {result['write_mb_s']:.2f} MB/s; "
              f"{result['messages_per_s']:.0f} messages/s (colour {result['colour_fps']:.1f} fps, depth {result['depth_fps']:.1f} fps, "
              f"joints {result['joint_hz']:.1f} Hz); a 1 ms Python ticker woke late by {result['late_with']} "
              f"(without recording: {result['late_without']})", flush=True)

    peak = None if args.estop_only else peak_throughput(frames, args.peak_frames)
    if peak is not None:
        print(f"peak (one thread, back to back): {peak['mb_s']:.1f} MB/s, {peak['colour_fps']:.0f} colour frames/s "
              f"({1000 * peak['cpu_s_per_frame']:.1f} ms CPU per frame with its JPEG encode)", flush=True)

    for record in () if args.no_estop else (False, True):
        answers, halts, recorded, stream = estop_latency(args.trials, record, args.estop_camera_fps, frames,
                                                         recorded_stream=args.stream_camera == "recorded")
        label = f"recording ({recorded} colour frames)" if record else "no recording"
        print(f"e-stop, {label}, {args.trials} presses, {args.stream_camera} camera {args.estop_camera_fps:g} fps (ms): answer {figures(answers)} | "
              f"halt {figures(halts)}", flush=True)
        if stream.get("latency_ms"):
            print(f"stream, {label}: {len(stream['latency_ms']) / stream['seconds']:.1f} fps to the client, capture-to-client "
                  f"latency (ms) {figures(stream['latency_ms'])}", flush=True)


if __name__ == "__main__":
    main()
