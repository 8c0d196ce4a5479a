"""SimWorkcell: the MuJoCo workcell that owns the model, its lock, the clock (real-time threads or
deterministic fast stepping: armlab.devices.sim.clock), the camera mount and checkerboard
(armlab.devices.sim.camera_rig) and the ground truth (its queries: armlab.devices.sim.truth), and hands
out the sim Arm, Gripper and Camera.

Fast mode (realtime=False): physics advances only in step() and in blocking device calls, so a seed and
a sequence of calls always give the same result. Real-time mode: a physics thread paced to the wall
clock (servo references updated every control period) and a render thread at the camera rate."""

from __future__ import annotations

import math
import threading

import mujoco
import numpy as np

from armlab.devices.camera import Frame
from armlab.devices.sim.arm import SimArm
from armlab.devices.sim.arm_realism import GEAR_SUFFIX, JointStatePublisher, real_geometry
from armlab.devices.sim.arm_select import select_arm
from armlab.devices.sim.camera import NoiseModel, SimCamera
from armlab.devices.sim.camera_rig import SimCameraRig
from armlab.devices.sim.clock import SimClock
from armlab.devices.sim.config import (
    MountConfig,
    SimWorkcellConfig,
    arm_is_real,
    camera_is_real,
    draw_pose_error,
    load_camera_config,
    load_sim_config,
    nominal_T_world_camera,
    resolve_realism,
)
from armlab.devices.sim.feeder import FeederRuntime, parked_objects
from armlab.devices.sim.gripper import SimGripper
from armlab.devices.sim.mjcf import CAMERA_NAME, GRIPPER_SITE, OBJECT_PREFIX, build_model_xml
from armlab.devices.sim.mjcf_dh import CUP_BODY, LIP_MARGIN_M, LIP_PREFIX, SUCTION_ACTUATOR, DhArmGeometry
from armlab.devices.sim.mjcf_numbers import FEED_FORWARD_SUFFIX
from armlab.devices.sim.path import PathRecorder
from armlab.devices.sim.realism import RealCamera
from armlab.devices.sim.render import RawImages, RenderThread
from armlab.devices.sim.suction import SuctionGripper, seal_object
from armlab.devices.sim.truth import SimTruth
from armlab.errors import InvalidInput
from armlab.scene import Scene
from armlab.workcell import load_workcell

PAD_GEOMS = ("left_pad", "right_pad")


class SimWorkcell(SimClock, SimCameraRig, SimTruth):
    """The simulated workcell (the RX200 with fingers, or a DH arm with a suction cup, per the workcell config).
    See the module docstring for the clock semantics."""

    def __init__(self, config: SimWorkcellConfig | None = None, scene: Scene | None = None) -> None:
        self.config = config or SimWorkcellConfig()
        self.lock = threading.RLock()
        self._workcell = load_workcell(self.config.workcell)
        self._sim = load_sim_config(self.config.sim)
        self._geometry = select_arm(self._workcell, self.config.arm, self._sim, self.config.sim)
        self._suction = isinstance(self._geometry, DhArmGeometry)
        self._camera_config = load_camera_config(self.config.camera or self._workcell.camera.name)
        if self._workcell.camera.mount is not None:  # the workcell's mount replaces the camera file's
            mount = self._workcell.camera.mount
            self._camera_config = self._camera_config.model_copy(
                update={"mount": MountConfig(position_m=list(mount.position_m), tilt_deg=mount.tilt_deg)})
        self.realism = resolve_realism(self.config.realism, self._sim)
        pose_rng, noise_rng, real_rng, rig_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(self.config.seed).spawn(4))
        self._publisher = None  # the real arm's joint-state publisher; None: the ideal arm (readings are the truth)
        self._feed_forward: tuple[np.ndarray, np.ndarray] | None = None  # the ideal servos' (acceleration, velocity) to feed forward
        config = None if not arm_is_real(self.realism) or self._suction else self._sim.servos(self._workcell.arm).realism
        if config is not None:  # the DH arms (the UR3) stay ideal: see config/sim.yaml arms
            self._geometry = real_geometry(self._geometry, config, rig_rng, self.config.arm_rig_error)
            self._publisher = JointStatePublisher(config)
            self._commanded_velocity = np.zeros(len(self._geometry.joint_names))
        T_nominal = nominal_T_world_camera(self._camera_config.mount)
        self._T_world_camera = (
            T_nominal @ draw_pose_error(pose_rng, self._sim.camera_pose_error) if self.config.camera_pose_error else T_nominal
        )
        self._scene = scene or Scene()
        self._model: mujoco.MjModel | None = None
        self._data: mujoco.MjData | None = None
        self._feeder: FeederRuntime | None = None
        self._path: PathRecorder | None = None
        self._build(self._scene, previous=None)
        physics = self._sim.physics
        # The real arm's trajectory is done at its end time, as the Interbotix driver's (the servos' steady error
        # would never settle within the tolerance); the ideal one's once it has settled.
        settle_tolerance_rad = math.inf if self._publisher is not None else physics.settle_tolerance_rad
        self.arm = SimArm(self, self._geometry.joint_names, self._geometry.lower_rad, self._geometry.upper_rad,
                          settle_tolerance_rad, physics.settle_timeout_s)
        if self._suction:
            self.gripper = SuctionGripper(self, self._sim.suction, self._workcell.arm)
        else:
            self.gripper = SimGripper(self, self._geometry.finger_offset_min_m, self._geometry.finger_offset_max_m,
                                      self._geometry.pad_thickness_m, self._sim.gripper.stop_speed_m_s,
                                      self._sim.gripper.stop_time_s, self._sim.gripper.open_preload_m)
        real = None
        if camera_is_real(self.realism) and self._camera_config.realism is not None:
            real = RealCamera(self._camera_config, self._camera_config.realism, real_rng, self.config.depth_noise)
            real.with_depth(self.config.depth_offset_m, self.config.depth_tilt_deg)
        noise = NoiseModel(self._camera_config, noise_rng, self.config.color_noise, self.config.depth_noise, real)
        self.camera = SimCamera(self, self._camera_config, noise, self.config.camera_fps)
        self.camera.set_board(self._T_world_camera, self._depth_pivot_m())
        self._render_thread: RenderThread | None = None
        self._physics_thread: threading.Thread | None = None
        self.physics_fault: str | None = None  # why the real-time physics thread died (devices then raise DeviceLost)
        self._stop_event = threading.Event()
        self._started = False
        self._closed = False

    # ------------------------------------------------------------------ model
    def _build(self, scene: Scene, previous: dict | None) -> None:
        """(Re)build model and data for a scene; `previous` carries the arm/gripper state across."""
        self._install(self._compile(scene), scene, previous)

    def _compile(self, scene: Scene) -> dict:
        """The slow half of a scene change (XML, compile, index look-ups): touches no shared state, so it
        runs outside the lock and the physics, the devices and an e-stop never wait for it."""
        if scene.workcell is not None and scene.workcell != self._workcell.name:
            raise InvalidInput(f"the scene was made for workcell '{scene.workcell}' (its board, reach and sizes); this "
                             f"simulation runs workcell '{self._workcell.name}': generate the scene for it")
        realism_scene = self._sim.realism_scene if camera_is_real(self.realism) else None
        xml, assets = build_model_xml(self._geometry, self._sim, self._camera_config, self._T_world_camera, scene,
                                      self._workcell, realism_scene)
        model = mujoco.MjModel.from_xml_string(xml, assets)
        names = self._geometry.joint_names
        real = self._publisher is not None
        arm_root = model.body("base").id
        pos_act = np.array([model.actuator(f"{n}_pos").id for n in names])
        vel_act = np.array([model.actuator(f"{n}_vel").id for n in names])
        actuator_names = {model.actuator(k).name for k in range(model.nu)}
        ff_act = np.array([model.actuator(n + FEED_FORWARD_SUFFIX).id for n in names if n + FEED_FORWARD_SUFFIX in actuator_names], dtype=int)
        object_bodies = {obj.id: model.body(OBJECT_PREFIX + obj.id).id for obj in scene.objects}
        parked = parked_objects(scene.feeder, self._workcell) if scene.feeder is not None else []
        sides = () if self._suction else ("left", "right")
        lip_points = self._sim.suction.lip_points if self._suction else 0
        return {
            "model": model,
            "data": mujoco.MjData(model),
            "_arm_qpos": np.array([model.jnt_qposadr[model.joint(n).id] for n in names]),
            "_arm_qvel": np.array([model.jnt_dofadr[model.joint(n).id] for n in names]),
            "_gear_qpos": np.array([model.jnt_qposadr[model.joint(n + GEAR_SUFFIX).id] for n in names] if real else [], dtype=int),
            "_gear_qvel": np.array([model.jnt_dofadr[model.joint(n + GEAR_SUFFIX).id] for n in names] if real else [], dtype=int),
            "_finger_qpos": np.array([model.jnt_qposadr[model.joint(f"{s}_finger").id] for s in sides], dtype=int),
            "_finger_qvel": np.array([model.jnt_dofadr[model.joint(f"{s}_finger").id] for s in sides], dtype=int),
            "_pos_act": pos_act,
            "_vel_act": vel_act,
            "_ff_act": ff_act,  # the ideal servos' acceleration feed-forward (none on the real arm: its firmware's gains are 0)
            "_finger_act": np.array([model.actuator(f"{s}_finger").id for s in sides], dtype=int),
            "_arm_gains": (model.actuator_gainprm[pos_act, 0].copy(), model.actuator_gainprm[vel_act, 0].copy()),
            "_arm_body_ids": np.flatnonzero((model.body_gravcomp > 0) & (model.body_rootid == arm_root)),
            "_gripper_site": model.site(GRIPPER_SITE).id,
            "_gripper_body": model.body("gripper_link").id,
            "_pad_geoms": {model.geom(name).id: name for name in PAD_GEOMS} if sides else {},
            "_lip_geoms": {model.geom(f"{LIP_PREFIX}{k}").id: k for k in range(lip_points)},
            "_suction_act": model.actuator(SUCTION_ACTUATOR).id if self._suction else -1,
            "_cup_body": model.body(CUP_BODY).id if self._suction else -1,
            "_object_bodies": object_bodies,
            "parked_bodies": [(model.body(OBJECT_PREFIX + obj.id).id, obj) for obj in parked],
            "arm_root": arm_root,
        }

    def _install(self, compiled: dict, scene: Scene, previous: dict | None) -> None:
        """The quick half of a scene change (call under the lock): adopt a compiled model, carrying the arm
        and gripper state across from `previous`."""
        model, data = compiled["model"], compiled["data"]
        for name, value in compiled.items():
            if name.startswith("_"):
                setattr(self, name, value)
        parked_bodies, arm_root = compiled["parked_bodies"], compiled["arm_root"]
        self._body_to_object = {body: obj_id for obj_id, body in self._object_bodies.items()}
        self._body_to_object.update({body: obj.id for body, obj in parked_bodies})
        if previous is None:
            # The arm powers up in its sleep pose, fingers open.
            data.qpos[self._arm_qpos] = np.clip(self._geometry.sleep_rad, self._geometry.lower_rad, self._geometry.upper_rad)
            data.qpos[self._finger_qpos] = self._geometry.finger_offset_max_m
            data.ctrl[self._pos_act] = data.qpos[self._arm_qpos]
            data.ctrl[self._finger_act] = self._geometry.finger_offset_max_m + self._sim.gripper.open_preload_m
            self._next_control_s = 0.0
        else:
            data.time = previous["time"]
            data.qpos[self._arm_qpos] = previous["arm_qpos"]
            data.qvel[self._arm_qvel] = previous["arm_qvel"]
            data.qpos[self._gear_qpos] = previous["gear_qpos"]
            data.qvel[self._gear_qvel] = previous["gear_qvel"]
            data.qpos[self._finger_qpos] = previous["finger_qpos"]
            data.qvel[self._finger_qvel] = previous["finger_qvel"]
            data.ctrl[self._pos_act] = previous["pos_ctrl"]
            data.ctrl[self._vel_act] = previous["vel_ctrl"]
            if len(self._ff_act) == len(previous["ff_ctrl"]):
                data.ctrl[self._ff_act] = previous["ff_ctrl"]
            data.ctrl[self._finger_act] = previous["finger_ctrl"]
            if not previous["torque"]:
                self._apply_torque(model, False)
        mujoco.mj_forward(model, data)
        if self._publisher is not None and previous is None:
            self._publisher.publish(float(data.time), data.qpos[self._arm_qpos], data.qvel[self._arm_qvel])
        self._feeder = None
        if scene.feeder is not None:
            arm_geoms = np.flatnonzero(model.body_rootid[model.geom_bodyid] == arm_root).tolist()
            watched = [(self._object_bodies[obj.id], obj) for obj in scene.objects]
            self._feeder = FeederRuntime(model, data, scene.feeder, self._workcell.feeder,
                                         self._workcell.block_edge_m("large"), watched, parked_bodies, arm_geoms)
            self._feeder.tick(model, data)  # a clear spot starts filled
        self._model, self._data, self._scene = model, data, scene
        self._torque = True if previous is None else previous["torque"]
        self._show_checkerboard()  # a placed intrinsics target stays where it was across scene changes

    def set_scene(self, scene: Scene | dict) -> None:
        """Replace all objects (thread-safe; the arm and gripper keep their state). Accepts a Scene or
        its dict form ({"objects": [...]}, the ground-truth format)."""
        if isinstance(scene, dict):
            scene = Scene.from_dict(scene, workcell=self._workcell.name)
        if not isinstance(scene, Scene):
            raise InvalidInput(f"set_scene expects a Scene or a dict with 'objects', got {type(scene).__name__}")
        compiled = self._compile(scene)  # outside the lock: physics, devices and e-stop go on meanwhile
        with self.lock:
            data = self._data
            previous = {
                "time": data.time,
                "arm_qpos": data.qpos[self._arm_qpos].copy(),
                "arm_qvel": data.qvel[self._arm_qvel].copy(),
                "gear_qpos": data.qpos[self._gear_qpos].copy(),
                "gear_qvel": data.qvel[self._gear_qvel].copy(),
                "finger_qpos": data.qpos[self._finger_qpos].copy(),
                "finger_qvel": data.qvel[self._finger_qvel].copy(),
                "pos_ctrl": data.ctrl[self._pos_act].copy(),
                "vel_ctrl": data.ctrl[self._vel_act].copy(),
                "ff_ctrl": data.ctrl[self._ff_act].copy(),
                "finger_ctrl": data.ctrl[self._finger_act].copy(),
                "torque": self._torque,
            }
            self._install(compiled, scene, previous)

    def reset_scene(self) -> None:
        """Put every object back where the current scene started it (the arm keeps its pose)."""
        self.set_scene(self._scene)

    @property
    def scene(self) -> Scene:
        return self._scene

    @property
    def model(self) -> mujoco.MjModel:
        return self._model

    # ------------------------------------------------------------ device hooks (call under self.lock)
    def arm_positions(self) -> np.ndarray:
        return self._data.qpos[self._arm_qpos].copy()

    def arm_reference(self) -> np.ndarray:
        """The servos' position references: where the arm is commanded to be now."""
        return self._data.ctrl[self._pos_act].copy()

    @property
    def ideal_servos(self) -> bool:
        """The ideal arm's servos (position + velocity servo, acceleration fed forward, following the trajectory at
        every physics step); False: the real arm's firmware (`realism: real`: a P gain, goals once per control tick)."""
        return self._publisher is None

    @property
    def timestep_s(self) -> float:
        """The physics step (simulated s)."""
        return float(self._model.opt.timestep)

    def arm_reference_velocity(self) -> np.ndarray:
        """The servos' velocity feed-forward: the commanded trajectory's slope now (the real arm's firmware is
        given it but uses none)."""
        if self._publisher is not None:
            return self._commanded_velocity.copy()
        return self._data.ctrl[self._vel_act].copy()

    def arm_reading(self) -> tuple[np.ndarray, np.ndarray, float]:
        """What the driver reports: (position, velocity, age in simulated s). Ideal: the joints now, exactly;
        real: the last published joint state (encoder counts, at the driver's rate)."""
        if self._publisher is None:
            return self.arm_positions(), self.arm_velocities(), 0.0
        position, velocity, at_s = self._publisher.sample
        return position.copy(), velocity.copy(), float(self._data.time) - at_s

    def arm_velocities(self) -> np.ndarray:
        return self._data.qvel[self._arm_qvel].copy()

    def finger_positions(self) -> tuple[float, float]:
        left, right = self._data.qpos[self._finger_qpos]
        return float(left), float(right)

    def finger_velocities(self) -> tuple[float, float]:
        left, right = self._data.qvel[self._finger_qvel]
        return float(left), float(right)

    def apply_arm_reference(self, position_rad: np.ndarray, velocity_rad_s: np.ndarray, accel_rad_s2: np.ndarray | None = None) -> None:
        """The servos' references: position, velocity and (the ideal servos) acceleration, fed forward through the
        arm's rigid-body dynamics (_inverse_dynamics); None: no feed-forward (a hold, a halt)."""
        self._data.ctrl[self._pos_act] = position_rad
        if self._publisher is not None:  # the real firmware: no velocity feed-forward (its velocity actuator is the motor's damping)
            self._commanded_velocity = np.clip(np.asarray(velocity_rad_s, dtype=float), -10.0, 10.0)
            return
        self._data.ctrl[self._vel_act] = np.minimum(np.maximum(velocity_rad_s, -10.0), 10.0)  # np.clip: 3x the time, every step
        self._feed_forward = None if accel_rad_s2 is None else (np.asarray(accel_rad_s2, float), np.asarray(velocity_rad_s, float))

    def _apply_feed_forward(self) -> None:
        """Inside a physics step, between mj_step1 and mj_step2 (the model's mass matrix and bias forces are those of
        the state the step integrates from): the ideal servos' feed-forward torque for the acceleration last applied
        (apply_arm_reference), or none. Computed before the step instead, from the step before's quantities: bench
        seed 0's replacements 1.0007x the acceleration limit instead of 1.0005x."""
        if len(self._ff_act):
            request = self._feed_forward
            self._data.ctrl[self._ff_act] = 0.0 if request is None else self._inverse_dynamics(*request)

    def _inverse_dynamics(self, accel_rad_s2, velocity_rad_s) -> np.ndarray:
        """The torque (N*m, the arm's joints) that makes the arm follow `accel_rad_s2` at `velocity_rad_s`, from the
        model, as the ideal servos compensate gravity from it (gravcomp): M(q) a (the joints' coupling included) +
        the Coriolis and centrifugal terms at the measured state + the joints' viscous friction. The mass-matrix term
        alone left 1.05x the limit where a joint's acceleration changes while the others move fast (bench seed 0).
        Needs the model's position and velocity stages at the current state (mj_step1)."""
        model, data = self._model, self._data
        vector = np.zeros(model.nv)
        vector[self._arm_qvel] = accel_rad_s2
        torque = np.zeros(model.nv)
        mujoco.mj_mulM(model, data, torque, vector)
        torque += data.qfrc_bias - data.qfrc_gravcomp
        return torque[self._arm_qvel] + model.dof_damping[self._arm_qvel] * np.asarray(velocity_rad_s, float)

    def apply_finger_reference(self, offset_m: float) -> None:
        self._data.ctrl[self._finger_act] = offset_m

    def apply_suction(self, level: float) -> None:
        """Vacuum level of the cup's adhesion actuator: 0 vented .. 1 full."""
        self._data.ctrl[self._suction_act] = level

    def cup_velocity_m_s(self) -> np.ndarray:
        """World linear velocity of the suction cup."""
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(self._model, self._data, mujoco.mjtObj.mjOBJ_BODY, self._cup_body, velocity, 0)
        return velocity[3:].copy()

    def cup_seal_object(self) -> str | None:
        """The object whose face the whole lip rests on (within the lip's compliance), else None."""
        return seal_object(self._model, self._data, self._lip_geoms, self._cup_body, self._body_to_object,
                           self._sim.suction.lip_compliance_m, LIP_MARGIN_M)

    def _apply_torque(self, model: mujoco.MjModel, enabled: bool) -> None:
        kp, kv = self._arm_gains if enabled else (np.zeros(len(self._pos_act)), np.zeros(len(self._vel_act)))
        model.actuator_gainprm[self._pos_act, 0] = kp
        model.actuator_biasprm[self._pos_act, 1] = -kp
        model.actuator_gainprm[self._vel_act, 0] = kv
        model.actuator_biasprm[self._vel_act, 2] = -kv
        model.actuator_gainprm[self._ff_act, 0] = 1.0 if enabled else 0.0
        model.body_gravcomp[self._arm_body_ids] = 1.0 if enabled else 0.0

    def set_arm_torque(self, enabled: bool) -> None:
        self._apply_torque(self._model, enabled)
        self._torque = enabled

    # ---------------------------------------------------------------- camera
    def _snapshot(self, renderer) -> tuple[float, np.ndarray, bool]:
        """Copy the state to draw; (sim time, arm joints, gripper commanded closed) of exactly that state."""
        with self.lock:
            if renderer.model is not self._model:
                renderer.set_model(self._model, CAMERA_NAME)
            renderer.update_scene(self._model, self._data)
            return float(self._data.time), self.arm_positions(), self.gripper.command == "grasp"

    def _renderer(self) -> RenderThread:
        if self._render_thread is None:
            cam = self._camera_config
            shadows = camera_is_real(self.realism) and self._sim.realism_scene is not None
            self._render_thread = RenderThread(self._model, CAMERA_NAME, cam.width, cam.height, self._snapshot, shadows=shadows)
        return self._render_thread

    def render_raw(self) -> RawImages:
        """A clean render (no noise) now; for tests and tools."""
        return self._renderer().render()

    def render(self) -> Frame:
        """Render one frame now without advancing the physics (noise applied as configured)."""
        if self._closed:
            raise RuntimeError("SimWorkcell is closed")
        return self.camera.publish(self._renderer().render())

    def capture_next_frame(self) -> Frame:
        """Fast mode: advance the physics to the next frame time of the camera clock and render."""
        period = 1.0 / self.camera.fps
        timestep = self._model.opt.timestep
        with self.lock:
            next_frame_s = (math.floor(self.sim_time_s / period + 1e-6) + 1) * period
            steps = max(1, math.ceil((next_frame_s - self.sim_time_s) / timestep - 1e-6))
            for _ in range(steps):
                self._step_once()
        return self.render()

    # -------------------------------------------------------------- lifecycle
    def start(self) -> None:
        """Connect the devices; in real time also start the physics and camera threads."""
        if self._started:
            return
        for device in (self.arm, self.gripper, self.camera):
            if not device.is_connected:
                device.connect()
        self._started = True
        self._renderer()  # creates the GL context now and logs which backend renders
        if self.realtime:
            self._stop_event.clear()
            self._physics_thread = threading.Thread(target=self._physics_loop, name="sim-physics", daemon=True)
            self._physics_thread.start()
            self._renderer().start_periodic(1.0 / self.camera.fps, self.camera.publish)

    def close(self) -> None:
        """Stop the threads and release the devices. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        self._stop_event.set()
        if self._physics_thread is not None:
            self._physics_thread.join(timeout=5.0)
        if self._render_thread is not None:
            self._render_thread.close()
        for device in (self.arm, self.gripper, self.camera):
            if device.is_connected:
                device.close()

    def __enter__(self) -> SimWorkcell:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()
