"""The 3-D panel's geometry (web/js/view3d.js), all from configuration: the arm as a URDF generated from its
config file with the vendor's meshes (armlab.station.arm_urdf), and the workcell (board, grid, tags, places).
Read-only, no token: a view-only page draws the same scene."""

from __future__ import annotations

import numpy as np
from fastapi import APIRouter
from fastapi.responses import Response

from armlab.station.arm_info import station_workcell_name
from armlab.station.arm_urdf import FINGER_JOINTS, TOOL_LINK, MeshSet, arm_urdf
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
    width_m into each finger's offset, the meshes' source and licence; None without an arm) and the
    workcell (as the websocket hello's)."""
    workcell = load_workcell(station_workcell_name(station)).to_wire()
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
        "fingers": {"joints": list(FINGER_JOINTS), "pad_thickness_m": gripper.pad_thickness_m} if gripper else None,
        "meshes": {"source": meshes.source, "licence": meshes.licence} if meshes else None,
        "mesh_urls": sorted({meshes.url + visual["file"] for visual in meshes.visuals}) if meshes else [],
    }
    return {"arm": arm, "workcell": workcell}
