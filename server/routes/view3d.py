"""The 3-D panel's geometry (web/js/view3d.js), all from configuration: the arm as a URDF generated from its
config file with the vendor's meshes (armlab.station.arm_urdf), and the workcell (board, grid, tags, places).
And the depth image as a decimated, coloured point cloud in the world frame. Read-only, no token: a view-only
page draws the same scene."""

from __future__ import annotations

import numpy as np
from fastapi import APIRouter, Query
from fastapi.responses import Response

from armlab.station.arm_info import station_workcell_name
from armlab.station.arm_urdf import FINGER_JOINTS, TOOL_LINK, MeshSet, arm_urdf, part_links
from armlab.tasks.judge import GRIPPER_BOX_M
from armlab.vision.pixel_world import depth_point_cloud
from armlab.workcell import load_workcell
from server.deps import StationDep
from server.errors import ApiError

router = APIRouter(prefix="/api/view3d", tags=["view3d"])


def _urdf(station) -> tuple[str, MeshSet | None]:
    model = station.model
    if model is None:
        raise ApiError(404, "not_found", "this station has no arm")
    meshes = MeshSet.load(model.name)
    return arm_urdf(model.config, np.asarray(model.T_world_base), meshes), meshes


@router.get("/arm.urdf", response_class=Response)
def get_arm_urdf(station: StationDep) -> Response:
    """The station's arm as a URDF: root link `world` (the board frame), `tool_point` at the gripper point."""
    return Response(_urdf(station)[0], media_type="application/xml")


@router.get("/scene")
def get_scene(station: StationDep) -> dict:
    """Everything the 3-D panel draws that does not move: the arm (its URDF inline, the joints telemetry's
    joints_rad sets, the tool link, the finger joints with the pad thickness that turns the gripper's
    width_m into each finger's offset, the meshes' source and licence, part_links: the links of each part a refused
    motion's error names, to draw in red; None without an arm) and the
    workcell (as the websocket hello's, with pick_stack's gripper box: the judge's box the gripper point must
    stay inside, min_m / max_m corners)."""
    box = GRIPPER_BOX_M
    workcell = load_workcell(station_workcell_name(station)).to_wire() | {"gripper_box_m": {
        "task": "pick_stack", "min_m": [-box["x_abs_max"], box["y_min"], 0.0], "max_m": [box["x_abs_max"], box["y_max"], box["z_max"]]}}
    if station.model is None:
        return {"arm": None, "workcell": workcell}
    urdf, meshes = _urdf(station)
    config = station.model.config
    gripper = config.gripper
    arm = {
        "name": station.model.name,
        "urdf": urdf,
        "joint_names": list(station.model.joint_names),
        "tool_link": TOOL_LINK,
        "part_links": part_links(config),
        "fingers": {"joints": list(FINGER_JOINTS), "pad_thickness_m": gripper.pad_thickness_m} if gripper else None,
        "meshes": {"source": meshes.source, "licence": meshes.licence} if meshes else None,
        "mesh_urls": sorted({meshes.url + visual["file"] for visual in meshes.visuals}) if meshes else [],
    }
    return {"arm": arm, "workcell": workcell}


@router.get("/points", response_class=Response, responses={200: {"content": {"application/octet-stream": {}}}})
def get_points(station: StationDep, step_px: int = Query(8, ge=2, le=64, description="every step_px-th pixel in u and v")) -> Response:
    """The newest depth image as world points through the calibration, every step_px-th pixel: little-endian
    float32 x, y, z (metres) for the N points, then uint8 r, g, b for each; N in X-Points. 409 without a
    calibration or a depth image."""
    calibration = station.calibration
    if calibration is None:
        raise ApiError(409, "not_calibrated", "the point cloud needs the camera's calibration")
    frame, _ = station.frames.get()
    depth = getattr(frame, "depth_mm", None)
    if depth is None:
        raise ApiError(409, "no_depth", "the camera gives no depth image")
    points, colors = depth_point_cloud(calibration, depth, frame.color_bgr, step_px)
    return Response(points.astype("<f4").tobytes() + colors.tobytes(), media_type="application/octet-stream",
                    headers={"X-Points": str(len(points)), "X-Capture-Time-S": f"{frame.timestamp_s:.6f}",
                             "Cache-Control": "no-store"})
