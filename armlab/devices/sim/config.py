"""Validated configuration of the simulated workcell: SimWorkcellConfig (what a caller chooses), the
physics/servo parameters of config/sim.yaml and the camera of config/cameras/<name>.yaml, plus the pure
pose maths for the camera mount and its seeded "bumped rig" error."""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from armlab.config import StrictModel, load_config, resolve_config_path
from armlab.devices.camera import Intrinsics
from armlab.devices.finger_gripper import FingerGripperConfig
from armlab.devices.sim.arm_realism import ArmRealismConfig
from armlab.kinematics.rotations import rotation_from_rotvec

Positive = Annotated[float, Field(gt=0.0)]
NonNegative = Annotated[float, Field(ge=0.0)]
Fraction = Annotated[float, Field(ge=0.0, le=1.0)]
Realism = Literal["real", "camera", "ideal"]
REALISMS = ("real", "camera", "ideal")  # the choices of every --realism


def camera_is_real(realism: str) -> bool:
    """real and camera: the real L515's imperfections, the second light and the clutter on the board."""
    return realism in ("real", "camera")


def arm_is_real(realism: str) -> bool:
    """real only: the arm as the real one runs (camera keeps the exact arm until the station calibrates the arm)."""
    return realism == "real"
REALISM_ENV = "ARMLAB_REALISM"  # overrides config/sim.yaml's realism where no caller chose one (the test suite: ideal)


class SimWorkcellConfig(StrictModel):
    """How to run the simulation. realtime=False is the deterministic fast mode for tests/evaluations."""

    realtime: bool = False
    # Real time only: simulated seconds per wall-clock second (the physics thread's pace). 1 for the product; the
    # tests' long real-time runs (whole jobs over HTTP) take 2-3, as a fast machine would run ahead of the clock.
    time_scale: Annotated[float, Field(ge=0.1, le=10.0)] = 1.0
    seed: int = 0
    camera_pose_error: bool = True
    arm_rig_error: bool = True  # realism real: the arm's seeded joint offsets, link lengths and base pose (False: nominal)
    color_noise: bool = True
    depth_noise: bool = True
    camera_fps: Positive = 30.0
    arm: str | None = None  # None: the workcell's arm; another arm than the workcell's is refused
    camera: str | None = None  # None: the workcell's camera (config/cameras/<name>.yaml)
    sim: str = "sim"  # config/<sim>.yaml
    workcell: str = "rx200_armlab"  # config/workcells/<workcell>.yaml: arm, gripper, board, tags, camera, feeder
    # real: the camera's imperfections of the real L515 (its file's `realism:`), a second light with shadows
    # and clutter on the board (config/sim.yaml `realism_scene:`), and the arm as the real one runs (its servos'
    # `realism:` in config/sim.yaml, armlab.devices.sim.arm_realism; an arm without one stays ideal); ideal: the
    # exact camera and arm; camera: the real camera and board with the exact arm. None: $ARMLAB_REALISM, else
    # config/sim.yaml `realism`.
    realism: Realism | None = None
    depth_offset_m: float | None = None  # realism real: replace the camera file's depth offset / tilt (tests)
    depth_tilt_deg: float | None = None


class PhysicsConfig(StrictModel):
    timestep_s: Positive
    control_period_s: Positive
    impratio: Positive
    noslip_iterations: Annotated[int, Field(ge=0, le=50)] = 0
    cone: Literal["elliptic", "pyramidal"] = "elliptic"
    sleep: bool = True  # resting free bodies sleep (no contacts computed) until something touches them
    settle_tolerance_rad: Positive
    settle_timeout_s: NonNegative

    @model_validator(mode="after")
    def _control_not_faster_than_physics(self) -> PhysicsConfig:
        if self.control_period_s < self.timestep_s or self.control_period_s > 0.01:
            raise ValueError("control_period_s must be >= timestep_s and <= 0.01 (control at >= 100 Hz)")
        return self


class ArmServoConfig(StrictModel):
    kp: list[Positive]
    kv: list[NonNegative]
    armature: list[NonNegative]
    damping: list[NonNegative]
    force_limit_nm: list[Positive]
    link_masses_kg: list[Positive]
    link_radius_m: list[Positive] | None = None  # DH-built arms: the capsule radius of each link
    realism: ArmRealismConfig | None = None  # `realism: real` runs this arm as the real one; None: ideal even then

    @model_validator(mode="after")
    def _same_lengths(self) -> ArmServoConfig:
        lengths = {len(self.kp), len(self.kv), len(self.armature), len(self.damping), len(self.force_limit_nm)}
        if len(lengths) != 1 or len(self.link_masses_kg) != len(self.kp):
            raise ValueError("arm: kp, kv, armature, damping, force_limit_nm, link_masses_kg need one value per joint")
        if self.realism is not None and len(self.realism.stall_torque_nm) != len(self.kp):
            raise ValueError("arm: realism: needs one value per joint (as kp)")
        if self.link_radius_m is not None and len(self.link_radius_m) != len(self.kp):
            raise ValueError("link_radius_m needs one value per joint")
        return self


class SuctionSimConfig(StrictModel):
    """The simulated vacuum cup (armlab.devices.sim.suction): the lip is a ring of lip_points small spheres;
    the vacuum (MuJoCo adhesion actuator, adhesion_force_n at full vacuum) builds only while one object's face
    lies beneath every lip point along the cup's axis within lip_compliance_m of the lip plane (the bellows
    conform that far: a cup of lip radius r seals up to a tilt of about asin(lip_compliance_m / 2r); a lip
    point over an edge has no face beneath it). While holding, a cup accelerating harder than
    max_acceleration_m_s2 (low-passed over acceleration_filter_s) breaks the seal: the block is lost."""

    adhesion_force_n: Positive
    lip_points: Annotated[int, Field(ge=4, le=32)] = 8
    lip_sphere_radius_m: Positive
    lip_compliance_m: Positive
    lip_friction: list[NonNegative] = Field(min_length=3, max_length=3)
    lip_solref: list[float] = Field(min_length=2, max_length=2)
    cup_mass_kg: Positive
    max_acceleration_m_s2: Positive
    acceleration_filter_s: Positive
    settle_time_s: Positive  # grasp(wait=True) waits this long for the seal to form (release: to vent)


class ObjectsConfig(StrictModel):
    density_kg_m3: Positive
    friction: list[NonNegative] = Field(min_length=3, max_length=3)
    board_friction: list[NonNegative] = Field(min_length=3, max_length=3)
    solref: list[float] = Field(min_length=2, max_length=2)


class PoseErrorConfig(StrictModel):
    position_m: NonNegative
    rotation_deg: NonNegative


class RenderConfig(StrictModel):
    multisamples: Annotated[int, Field(ge=0, le=16)] = 0


class LightConfig(StrictModel):
    """A MuJoCo spot light (positions and directions in the world frame, m)."""

    position_m: list[float] = Field(min_length=3, max_length=3)
    direction: list[float] = Field(min_length=3, max_length=3)
    diffuse: Fraction
    cutoff_deg: Annotated[float, Field(gt=0.0, le=90.0)] = 60.0
    exponent: Annotated[float, Field(ge=0.0, le=128.0)] = 0.0  # spot falloff: cos(angle off axis) ** exponent
    cast_shadow: bool = True


class ClutterItem(StrictModel):
    """A thing lying on the board that is not a block (visual only: no contacts, not in the scene or the
    judge's truth). kind: cable (a polyline of capsules through points_m), pliers (two handles and a jaw
    at position_m, yaw_deg) or hand (a palm and four fingers reaching in at position_m, yaw_deg)."""

    kind: Literal["cable", "pliers", "hand"]
    points_m: list[list[float]] | None = None
    position_m: list[float] | None = None
    yaw_deg: float = 0.0
    radius_m: Positive = 0.003
    rgba: list[Fraction] = Field(min_length=4, max_length=4)

    @model_validator(mode="after")
    def _has_geometry(self) -> ClutterItem:
        if self.kind == "cable" and (self.points_m is None or len(self.points_m) < 2 or any(len(p) != 2 for p in self.points_m)):
            raise ValueError("a cable needs points_m: at least two [x, y] points")
        if self.kind != "cable" and (self.position_m is None or len(self.position_m) != 2):
            raise ValueError(f"{self.kind} needs position_m: [x, y]")
        return self


class SceneRealismConfig(StrictModel):
    """What `realism: real` adds to the workcell itself: a second light casting shadows (the real frames'
    board brightness varies 9-32 % over the board), the shadow map size, and clutter on the board."""

    second_light: LightConfig
    shadow_size_px: Annotated[int, Field(ge=256, le=8192)] = 2048
    clutter: list[ClutterItem] = []


class SimConfig(StrictModel):
    """config/sim.yaml."""

    render: RenderConfig = RenderConfig()
    physics: PhysicsConfig
    arm: ArmServoConfig  # the RX200's servos
    arms: dict[str, ArmServoConfig] = {}  # other arms' servos, by arm name (config/arms/<name>.yaml)
    gripper: FingerGripperConfig  # the finger gripper's dimensions (armlab.devices.finger_gripper)
    suction: SuctionSimConfig | None = None
    objects: ObjectsConfig
    camera_pose_error: PoseErrorConfig
    realism: Realism = "ideal"  # the workcell's default; `--realism` and SimWorkcellConfig.realism override it
    realism_scene: SceneRealismConfig | None = None

    def servos(self, arm: str) -> ArmServoConfig:
        """The servo settings of `arm`: `arm:` for the RX200, else `arms.<name>` (ValueError naming the field)."""
        if arm == "rx200":
            return self.arm
        if arm not in self.arms:
            raise ValueError(f"config/sim.yaml: arms.{arm}: no servo settings for arm '{arm}' (have: rx200, {', '.join(self.arms)})")
        return self.arms[arm]


class IntrinsicsConfig(StrictModel):
    fx: Positive
    fy: Positive
    cx: float
    cy: float
    dist: list[float] = Field(default_factory=lambda: [0.0] * 5, min_length=5, max_length=5)


class MountConfig(StrictModel):
    position_m: list[float] = Field(min_length=3, max_length=3)
    tilt_deg: Annotated[float, Field(ge=0.0, le=45.0)]


class DepthConfig(StrictModel):
    min_range_m: Positive
    max_range_m: Positive
    noise_std_mm: NonNegative
    dropout_fraction: Annotated[float, Field(ge=0.0, le=0.5)]


class ColorConfig(StrictModel):
    noise_std: NonNegative


class CameraRealismConfig(StrictModel):
    """The real L515's imperfections (`realism: real`), magnitudes measured on real frames by
    bench/real_camera.py (which frames and figures: the camera file's comments)."""

    # The depth's board plane against the true board, as calibration reports it: its height above the board
    # at the board tags' centre (negative: behind, away from the camera) and its tilt, rising along the
    # board's +y turned by depth_tilt_axis_deg (0: the tilt's axis is the board's x axis).
    depth_offset_m: Annotated[float, Field(ge=-0.05, le=0.05)]
    depth_tilt_deg: Annotated[float, Field(ge=-10.0, le=10.0)]
    depth_tilt_axis_deg: float = 0.0
    # Depth noise: std at 1 m growing as (range / 1 m) ** exponent (replaces depth.noise_std_mm).
    noise_std_at_1m_mm: NonNegative
    noise_range_exponent: Annotated[float, Field(ge=0.0, le=3.0)] = 1.0
    # Depth edges: pixels within edge_band_px of a step > edge_step_mm read as holes (0) or flying pixels
    # (a depth between the two sides) with these fractions.
    edge_step_mm: Positive
    edge_band_px: Annotated[int, Field(ge=1, le=10)]
    edge_hole_fraction: Fraction
    edge_flying_fraction: Fraction
    # Dark faces (rendered grey level below dark_level): this fraction reads 0.
    dark_level: Annotated[int, Field(ge=0, le=255)]
    dark_hole_fraction: Fraction
    # Columns at the image's left and right sides with no depth at all (the depth camera's narrower field).
    no_depth_columns: list[Annotated[int, Field(ge=0, le=400)]] = Field(default_factory=lambda: [0, 0], min_length=2, max_length=2)
    # Colour: white-balance gains (R, G, B) on the render, each drifting by up to +-white_balance_drift;
    # exposure drifting by up to +-exposure_drift; slow sinusoids of simulated time with seeded phases.
    white_balance_gains: list[Positive] = Field(min_length=3, max_length=3)
    white_balance_drift: list[Fraction] = Field(min_length=3, max_length=3)
    exposure_drift: Fraction
    drift_period_s: Positive

    @model_validator(mode="after")
    def _fractions_fit(self) -> CameraRealismConfig:
        if self.edge_hole_fraction + self.edge_flying_fraction > 1.0:
            raise ValueError("realism: edge_hole_fraction + edge_flying_fraction must not exceed 1")
        return self


class SimCameraConfig(StrictModel):
    """config/cameras/<name>.yaml for a simulated camera."""

    name: str
    type: str
    width: Annotated[int, Field(gt=0, le=4096)]
    height: Annotated[int, Field(gt=0, le=4096)]
    fps: Positive
    intrinsics: IntrinsicsConfig
    mount: MountConfig
    depth: DepthConfig
    color: ColorConfig
    realism: CameraRealismConfig | None = None  # None: the camera has no `real` imperfections

    @model_validator(mode="after")
    def _principal_point_inside(self) -> SimCameraConfig:
        if not (0 < self.intrinsics.cx < self.width and 0 < self.intrinsics.cy < self.height):
            raise ValueError("intrinsics: principal point must lie inside the image")
        if self.depth.min_range_m >= self.depth.max_range_m:
            raise ValueError("depth: min_range_m must be below max_range_m")
        return self

    def to_intrinsics(self) -> Intrinsics:
        k = self.intrinsics
        return Intrinsics(self.width, self.height, k.fx, k.fy, k.cx, k.cy, tuple(k.dist))


def resolve_realism(requested: str | None, sim: SimConfig) -> str:
    """The realism to run: the caller's choice, else $ARMLAB_REALISM, else config/sim.yaml's (ValueError naming
    the variable for a bad value)."""
    import os

    if requested is not None:
        return requested
    value = os.environ.get(REALISM_ENV, "").strip()
    if value:
        if value not in REALISMS:
            raise ValueError(f"${REALISM_ENV}: expected one of {', '.join(REALISMS)}, got {value!r}")
        return value
    return sim.realism


def load_sim_config(name: str = "sim") -> SimConfig:
    return load_config(resolve_config_path(name, "."), SimConfig)


def load_camera_config(name: str = "sim_l515") -> SimCameraConfig:
    return load_config(resolve_config_path(name, "cameras"), SimCameraConfig)


def nominal_T_world_camera(mount: MountConfig) -> np.ndarray:
    """Camera pose from the mount, OpenCV axes: x = image right = world +x, z = optical axis pointing
    down, tilted by tilt_deg toward -y (the arm), y = image down (toward -y)."""
    tilt = math.radians(mount.tilt_deg)
    x_axis = np.array([1.0, 0.0, 0.0])
    z_axis = np.array([0.0, -math.sin(tilt), -math.cos(tilt)])
    y_axis = np.cross(z_axis, x_axis)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x_axis, y_axis, z_axis])
    T[:3, 3] = mount.position_m
    return T


def draw_pose_error(rng: np.random.Generator, error: PoseErrorConfig) -> np.ndarray:
    """A 4x4 perturbation (applied in the camera frame): translation uniform in +-position_m per axis,
    rotation about a random axis by an angle uniform in +-rotation_deg."""
    translation = rng.uniform(-error.position_m, error.position_m, size=3)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angle = math.radians(rng.uniform(-error.rotation_deg, error.rotation_deg))
    T = np.eye(4)
    T[:3, :3] = rotation_from_rotvec(axis * angle)
    T[:3, 3] = translation
    return T
