"""Simulation-only: set the scene, read ground truth (for tests and scoring, never for perception)."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter
from pydantic import Field

from armlab.scene import Scene, generate_scene
from armlab.scene.model import check_can_stand
from armlab.station.core import Station
from armlab.station.jobs import jsonable
from server.deps import ControlAuth, StationDep
from server.errors import ApiError
from server.models import CameraBumpRequest, Request, SceneRequest

router = APIRouter(prefix="/api/sim", tags=["sim"])


def _cell(station: Station):
    if station.sim is None:
        raise ApiError(404, "not_found", "the simulation API exists only when the backend is the simulation")
    return station.sim


@router.post("/scene")
def post_scene(body: SceneRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Replace the objects: a generated event scene (event, level, seed) or explicit objects (at most 100,
    none below the board, none overlapping another: 422 naming them, and the scene stays)."""
    _cell(station)
    station.allowed_or_raise("set_scene", controller)
    if body.objects is not None:
        scene = Scene.from_dict({"objects": [item.model_dump(exclude_none=True) for item in body.objects]},
                                workcell=station.config.workcell)
        check_can_stand(scene)
    else:
        scene = generate_scene(body.event, level=body.level or 1, seed=body.seed or 0, workcell=station.config.workcell)
    station.set_scene(scene, source=controller)  # checked under the station lock, changed outside it
    station.events.add("info", f"scene set: {body.event or 'custom'} ({len(scene.objects)} objects)", kind="scene")
    return {"objects": len(scene.objects), "event": body.event, "level": body.level, "seed": body.seed}


@router.get("/scene")
def read_scene(station: StationDep) -> dict:
    """The scene loaded now: its generator's event, level and seed (None for an explicit scene) and object count."""
    scene = _cell(station).scene
    event, level, seed = scene.origin if scene.origin is not None else (None, None, None)
    return {"event": event, "level": level, "seed": seed, "objects": len(scene.objects)}


@router.get("/truth")
def read_truth(station: StationDep) -> dict:
    """Ground truth: object poses, camera pose and intrinsics, gripper contacts."""
    return jsonable(_cell(station).truth())


@router.post("/camera/bump")
def post_camera_bump(body: CameraBumpRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Knock the simulated camera mount (translation, then rotation vector, in the camera's frame): a
    calibrated station then warns 'camera moved: recalibrate' in its status until recalibrated."""
    cell = _cell(station)
    station.allowed_or_raise("set_scene", controller)
    cell.knock_camera(body.translation_m, body.rotation_rad)
    station.note_change_everywhere()  # the remembered depth of every hidden pixel was seen by the camera before the knock
    station.events.add("warn", f"simulated camera mount bumped by {controller}")
    return {"translation_m": body.translation_m, "rotation_rad": body.rotation_rad}


class CheckerboardRequest(Request):
    """Simulation only: where to put the intrinsics checkerboard (config/intrinsics.yaml target)."""

    position_m: Annotated[list[Annotated[float, Field(ge=-3.0, le=3.0)]], Field(min_length=3, max_length=3)] = Field(
        description="the board's centre, metres, in `frame`")
    rotation_rad: Annotated[list[Annotated[float, Field(ge=-3.2, le=3.2)]], Field(min_length=3, max_length=3)] = Field(
        [0.0, 0.0, 0.0], description="rotation vector, radians: frame 'camera': the turn from squarely facing the camera "
        "(camera axes); frame 'world': the board's orientation (zero: lying face up)")
    frame: Literal["camera", "world"] = Field("camera", description="'camera': the camera's OpenCV frame (z along the optical axis)")


@router.post("/checkerboard")
def post_checkerboard(body: CheckerboardRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Hold the intrinsics checkerboard at a pose (contact-free: nothing else moves), for the Intrinsics capture."""
    import cv2
    import numpy as np

    from armlab.devices.sim.checkerboard import pose_in_camera_frame  # MuJoCo only on the simulation's route

    cell = _cell(station)
    station.allowed_or_raise("set_scene", controller)
    if body.frame == "camera":
        T_world_camera = np.asarray(cell.truth()["camera"]["T_world_camera"], dtype=float)
        position, R = pose_in_camera_frame(T_world_camera, body.position_m, body.rotation_rad)
    else:
        position, R = np.asarray(body.position_m, dtype=float), cv2.Rodrigues(np.asarray(body.rotation_rad, dtype=float))[0]
    cell.place_checkerboard(position, R)
    station.note_change_everywhere()  # what the arm hides may be behind the board now: its remembered depth is unknown
    return {"position_m": [float(x) for x in position], "frame": "world"}


@router.delete("/checkerboard")
def delete_checkerboard(station: StationDep, controller: ControlAuth) -> dict:
    """Put the intrinsics checkerboard away (out of sight)."""
    cell = _cell(station)
    station.allowed_or_raise("set_scene", controller)
    cell.place_checkerboard()
    station.note_change_everywhere()  # the board is gone: depth remembered from when it stood there is stale
    return {"placed": False}
