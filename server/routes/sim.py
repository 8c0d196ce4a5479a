"""Simulation-only: set the scene, read ground truth (for tests and scoring, never for perception)."""

from __future__ import annotations

from fastapi import APIRouter

from armlab.station.core import Station
from armlab.station.jobs import jsonable
from server.deps import ControlAuth, StationDep
from server.errors import ApiError
from server.models import CameraBumpRequest, SceneRequest

router = APIRouter(prefix="/api/sim", tags=["sim"])


def _cell(station: Station):
    if station.sim is None:
        raise ApiError(404, "not_found", "the simulation API exists only when the backend is the simulation")
    return station.sim


@router.post("/scene")
def post_scene(body: SceneRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Replace the objects: a generated event scene (event, level, seed) or explicit objects."""
    from armlab.scene import Scene, generate_scene

    _cell(station)
    station.allowed_or_raise("set_scene", controller)
    if body.objects is not None:
        scene = Scene.from_dict({"objects": [item.model_dump(exclude_none=True) for item in body.objects]})
    else:
        scene = generate_scene(body.event, level=body.level or 1, seed=body.seed or 0)
    station.set_scene(scene, source=controller)  # checked under the station lock, changed outside it
    station.events.add("info", f"scene set: {body.event or 'custom'} ({len(scene.objects)} objects)")
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
    import cv2
    import numpy as np

    cell = _cell(station)
    station.allowed_or_raise("set_scene", controller)
    T_old_new = np.eye(4)
    T_old_new[:3, :3] = cv2.Rodrigues(np.asarray(body.rotation_rad, dtype=float))[0]
    T_old_new[:3, 3] = body.translation_m
    cell.bump_camera(T_old_new)
    station.events.add("warn", f"simulated camera mount bumped by {controller}")
    return {"translation_m": body.translation_m, "rotation_rad": body.rotation_rad}
