"""The board as this station sees and reaches it: the board tags of the current calibration (id, world position,
reprojection error, drift now) and the reach map (top-down, only tilted, out of reach) the page overlays."""

from __future__ import annotations

from fastapi import APIRouter
from starlette.concurrency import run_in_threadpool

from armlab.station.tag_list import board_tag_rows
from server.deps import StationDep

router = APIRouter(prefix="/api", tags=["calibration"])


@router.get("/calibration/tags")
def read_board_tags(station: StationDep) -> dict:
    """One row per board tag of the workcell: {id, position_m (world centre), size_m, used_in_calibration, projected_px
    (where the calibration puts its centre), reprojection_error_px (its corners as detected at calibration against the
    projection, RMS), seen_now, drift_px (the newest frame's detection against the projection)}; the projection and
    errors are null without a calibration."""
    perception, _ = station.perception.get()
    info = station.calibration_info
    rows = board_tag_rows(station.calibration, info.get("tags") or [], perception.tags if perception is not None else [],
                          station.perception_config)
    return {"data": rows, "count": len(rows), "calibrated": bool(info.get("calibrated")),
            "reprojection_error_px": info.get("reprojection_error_px")}


@router.get("/reach")
async def read_reach(station: StationDep) -> dict:
    """Where the gripper reaches on the board at a block's grasp height, for this arm and workcell: a grid
    {x0_m, y0_m, step_m, nx, ny, z_m, rows: [ny strings of nx letters: 'T' top-down, 't' only tilted, '.' out of
    reach], legend}; row j is y0_m + j·step_m, letter i is x0_m + i·step_m. Computed once (seconds; a numeric-IK arm
    longer) and kept until the arm's calibration changes. 409 on a station without an arm."""
    await run_in_threadpool(station.require_arm, "the reach map")
    return await run_in_threadpool(station.reach.get, station)
