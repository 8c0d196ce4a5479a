"""Offscreen rendering of the workcell camera: one GL context in one thread (EGL on a CPU-only machine),
one render pass per frame whose colour and depth buffers are read together. The scene geometry is
copied from MjData under the simulation lock (cheap); the expensive rasterisation runs outside it."""

from __future__ import annotations

import logging
import os
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import mujoco
import numpy as np

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class RawImages:
    """One render: rgb (H, W, 3) uint8 in RGB order, depth_m (H, W) float32 along the optical axis;
    arm_joints_rad and gripper_closed: the arm's joint positions and whether the gripper was commanded
    closed in the rendered state (None if the snapshot gave none). wall_time_s: time.time() just before
    the state was copied (the capture time: the drawing takes a while after it)."""

    rgb: np.ndarray
    depth_m: np.ndarray
    sim_time_s: float
    arm_joints_rad: np.ndarray | None = None
    gripper_closed: bool | None = None
    wall_time_s: float | None = None


def depth_from_buffer(buffer: np.ndarray, znear_m: float, zfar_m: float) -> np.ndarray:
    """Metric depth from MuJoCo's reversed-Z depth buffer (mjDEPTH_ZEROFAR), as mujoco.Renderer does."""
    zfar = np.float32(zfar_m)
    znear = np.float32(znear_m)
    c_coef = -(zfar + znear) / (zfar - znear)
    d_coef = -(np.float32(2) * zfar * znear) / (zfar - znear)
    c_coef = np.float32(-0.5) * c_coef - np.float32(0.5)
    d_coef = np.float32(-0.5) * d_coef
    return (d_coef / (buffer + c_coef)).astype(np.float32)


# Poses in the scene signature are compared in steps of this size (metres, and unit-vector components): a settled
# scene's contact jitter stays below it, and a change below it moves no point by 0.01 px at the camera's distance.
SCENE_QUANTUM = 1e-5


def scene_signature(model: mujoco.MjModel, data: mujoco.MjData) -> bytes:
    """Everything the camera draws, as bytes: where each geom, site, light and camera is (quantised by
    SCENE_QUANTUM) and how each looks. Two states with the same signature give the same picture, so a still
    scene is rasterised once instead of at every frame (a 1280x720 render costs ~50 ms of CPU on llvmpipe)."""
    poses = np.concatenate([
        data.geom_xpos.ravel(), data.geom_xmat.ravel(), data.site_xpos.ravel(), data.site_xmat.ravel(),
        data.cam_xpos.ravel(), data.cam_xmat.ravel(), data.light_xpos.ravel(), data.light_xdir.ravel(),
    ])
    looks = (model.geom_rgba, model.geom_size, model.geom_matid, model.geom_group, model.site_rgba, model.site_size,
             model.mat_rgba, model.light_diffuse, model.light_ambient, model.light_specular, model.light_active,
             model.cam_pos, model.cam_quat, model.cam_fovy, model.cam_intrinsic, model.cam_sensorsize)
    return np.rint(poses / SCENE_QUANTUM).astype(np.int64).tobytes() + b"".join(np.ascontiguousarray(a).tobytes() for a in looks)


def _gl_context_class(backend: str):
    """The GL context class for a backend, chosen explicitly (headless EGL by default) so that it works
    even if MuJoCo was imported before MUJOCO_GL was set."""
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.gl_context import GLContext
    return GLContext


class _GLRenderer:
    """Owns the GL and MuJoCo render contexts; used only from the render thread."""

    def __init__(self, model: mujoco.MjModel, camera_name: str, width: int, height: int, shadows: bool = False) -> None:
        self.width, self.height = width, height
        self.shadows = shadows  # the realistic workcell's second light casts shadows (one more pass per frame)
        self.backend = os.environ.get("MUJOCO_GL", "egl")
        self._gl = _gl_context_class(self.backend)(width, height)
        self._gl.make_current()
        try:
            from OpenGL import GL

            vendor = GL.glGetString(GL.GL_RENDERER)
            self.gl_renderer = vendor.decode() if isinstance(vendor, bytes) else str(vendor)
        except Exception:  # noqa: BLE001 - only for the log line
            self.gl_renderer = "unknown"
        self._context = None
        self._model = None
        self.rasterised_count = 0  # frames drawn by GL
        self.reused_count = 0  # frames copied from the last drawing (the scene had not changed)
        self.set_model(model, camera_name)

    def set_model(self, model: mujoco.MjModel, camera_name: str) -> None:
        self._gl.make_current()
        if self._context is not None:
            self._context.free()
        self._model = model
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        for flag in (mujoco.mjtRndFlag.mjRND_SKYBOX, mujoco.mjtRndFlag.mjRND_REFLECTION,
                     mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_HAZE, mujoco.mjtRndFlag.mjRND_FOG):
            self._scene.flags[flag] = 0  # none of them is in the ideal workcell; each costs a pass on a CPU
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = int(self.shadows)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._camera.fixedcamid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name)
        self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_50)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._rect = mujoco.MjrRect(0, 0, self.width, self.height)
        extent = model.stat.extent
        self._znear_m = model.vis.map.znear * extent
        self._zfar_m = model.vis.map.zfar * extent
        self._rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        self._depth = np.empty((self.height, self.width), dtype=np.float32)
        self._scene_key: bytes | None = None  # the signature of the scene last updated
        self._drawn: tuple[bytes, np.ndarray, np.ndarray] | None = None  # (signature, rgb, depth_m) of the last draw, this model

    @property
    def model(self) -> mujoco.MjModel:
        return self._model

    def update_scene(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Copy the geometry to draw (call under the simulation lock)."""
        mujoco.mjv_updateScene(model, data, self._option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL, self._scene)
        self._scene_key = scene_signature(model, data)

    def draw(self) -> tuple[np.ndarray, np.ndarray]:
        """Rasterise the last updated scene; returns (rgb, depth_m), top row first (new arrays, the caller's own).
        A scene whose signature equals the last drawn one is not rasterised again: its picture is copied."""
        if self._drawn is not None and self._scene_key is not None and self._drawn[0] == self._scene_key:
            self.reused_count += 1
            return self._drawn[1].copy(), self._drawn[2].copy()
        self.rasterised_count += 1
        self._gl.make_current()
        mujoco.mjr_render(self._rect, self._scene, self._context)
        mujoco.mjr_readPixels(self._rgb, self._depth, self._rect, self._context)
        rgb = cv2.flip(self._rgb, 0)  # OpenGL rows start at the bottom
        depth = depth_from_buffer(cv2.flip(self._depth, 0), self._znear_m, self._zfar_m)
        self._drawn = (self._scene_key, rgb.copy(), depth.copy()) if self._scene_key is not None else None
        return rgb, depth

    def close(self) -> None:
        if self._context is not None:
            self._gl.make_current()
            self._context.free()
            self._context = None
        self._gl.free()


class RenderThread:
    """A thread that owns the GL context and renders on request (fast mode) or on a period (real time).

    snapshot(renderer) is called in the render thread and must lock the simulation, switch the renderer
    to the current model if it changed (renderer.model / renderer.set_model), call
    renderer.update_scene(model, data) and return (simulation time, arm joint positions or None,
    gripper commanded closed or None) of that state; publish(RawImages) receives each periodic frame.
    """

    def __init__(self, model: mujoco.MjModel, camera_name: str, width: int, height: int,
                 snapshot: Callable[[_GLRenderer], tuple[float, np.ndarray | None, bool | None]], shadows: bool = False) -> None:
        self._snapshot = snapshot
        self._requests: queue.Queue = queue.Queue()
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._period_s: float | None = None
        self._publish: Callable[[RawImages], None] | None = None
        self._args = (model, camera_name, width, height, shadows)
        self._gl_renderer: _GLRenderer | None = None
        self._thread = threading.Thread(target=self._run, name="sim-render", daemon=True)
        self._thread.start()
        self._ready.wait(30.0)
        if self._error is not None:
            raise RuntimeError(f"sim camera: cannot create an offscreen GL context: {self._error}") from self._error

    def start_periodic(self, period_s: float, publish: Callable[[RawImages], None]) -> None:
        self._publish = publish
        self._period_s = period_s
        self._requests.put(("wake", None, None))

    def render(self, timeout_s: float = 30.0) -> RawImages:
        """Render one frame now (blocks the caller, not the physics)."""
        done = threading.Event()
        box: dict = {}
        self._requests.put(("render", done, box))
        if not done.wait(timeout_s):
            raise TimeoutError("sim camera: render timed out")
        if "error" in box:
            raise RuntimeError(f"sim camera: render failed: {box['error']}") from box["error"]
        return box["images"]

    @property
    def draw_counts(self) -> tuple[int, int]:
        """(frames rasterised, frames reused from the last drawing because the scene was unchanged) so far."""
        renderer = self._gl_renderer
        return (renderer.rasterised_count, renderer.reused_count) if renderer is not None else (0, 0)

    def close(self) -> None:
        self._stop.set()
        self._requests.put(("stop", None, None))
        self._thread.join(timeout=10.0)

    def _render_once(self, renderer: _GLRenderer) -> RawImages:
        # Stamped before the snapshot, never after: a thread preempted between the two on a loaded machine
        # stamped a state from before a scene change with a time after it, and a request that asked for a frame
        # taken after its arrival (frame_after) got the old scene.
        captured_s = time.time()
        sim_time_s, arm_joints_rad, gripper_closed = self._snapshot(renderer)
        rgb, depth = renderer.draw()
        return RawImages(rgb=rgb, depth_m=depth, sim_time_s=sim_time_s, arm_joints_rad=arm_joints_rad,
                         gripper_closed=gripper_closed, wall_time_s=captured_s)

    def _run(self) -> None:
        try:
            renderer = _GLRenderer(*self._args)
        except BaseException as error:  # noqa: BLE001 - reported to the constructor
            self._error = error
            self._ready.set()
            return
        self._gl_renderer = renderer
        logger.info("sim camera: rendering offscreen with MUJOCO_GL=%s (%s)", renderer.backend, renderer.gl_renderer)
        self._ready.set()
        next_due = time.monotonic()
        try:
            while not self._stop.is_set():
                timeout = None
                if self._period_s is not None:
                    timeout = max(0.0, next_due - time.monotonic())
                try:
                    request = self._requests.get(timeout=timeout)
                except queue.Empty:
                    request = None
                if request is None:  # a periodic frame is due
                    next_due = max(next_due + self._period_s, time.monotonic() - self._period_s)
                    try:
                        self._publish(self._render_once(renderer))
                    except Exception:  # noqa: BLE001 - keep the camera alive, log the failure
                        logger.exception("sim camera: periodic render failed")
                    continue
                kind = request[0]
                if kind == "stop":
                    break
                if kind == "wake":
                    next_due = time.monotonic()
                    continue
                done, box = request[1], request[2]
                try:
                    box["images"] = self._render_once(renderer)
                except Exception as error:  # noqa: BLE001 - handed to the caller
                    box["error"] = error
                done.set()
        finally:
            renderer.close()
