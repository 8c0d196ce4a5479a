"""Manual arm and gripper commands. `?wait=true` answers once the motion ends; the wait holds no worker
thread (server/waiting.py) and ends when the client hangs up."""

from __future__ import annotations

from fastapi import APIRouter, Query, Request
from starlette.concurrency import run_in_threadpool

from armlab.station.arm_info import arm_info
from server.deps import ControlAuth, StationDep
from server.models import (
    ArmInfo,
    CartesianJogRequest,
    GripperRequest,
    JogRequest,
    JointsRequest,
    MoveCheck,
    PoseNameRequest,
    PoseRequest,
    Status,
    StepRequest,
    TorqueRequest,
)
from server.plan_models import MovePlan
from server.waiting import until_arm_still, until_fingers_still

router = APIRouter(prefix="/api", tags=["arm"])


@router.get("/arm", response_model=ArmInfo)
def get_arm(station: StationDep) -> dict:
    """The arm and gripper the station runs: joint names and limits, vendor, gripper type (as in the hello)."""
    return arm_info(station)


async def _answer(request: Request, station, wait: bool) -> dict:
    """The status, once the arm has stopped when the client asked to wait."""
    if wait:
        # a move is at most max_moving_time_s at full speed; the speed override stretches it
        await until_arm_still(request, station, station.config.max_moving_time_s * 100.0 / station.speed_percent + 5.0)
    return await run_in_threadpool(station.status)


PLAN_ONLY = Query(False, description="plan and check the move as it would be made, move nothing: answers the plan "
                  "(MovePlan) with its id for POST /api/plans/{plan_id}/execute")


async def _named_pose(request: Request, station, controller, pose: str, body: PoseNameRequest | None, wait: bool,
                      plan_only: bool) -> dict:
    """home or sleep: moved to (the status), or with plan_only planned to (the plan, nothing moves)."""
    moving_time_s = body.moving_time_s if body else None
    if plan_only:
        await run_in_threadpool(station.require_arm, pose)
        goal_rad = station.model.home_rad if pose == "home" else station.model.sleep_rad
        return await run_in_threadpool(station.plan_only, pose, goal_rad, moving_time_s, source=controller)
    await run_in_threadpool(getattr(station, pose), moving_time_s, wait=False, source=controller)
    return await _answer(request, station, wait)


@router.post("/arm/home", response_model=Status | MovePlan)
async def post_home(request: Request, station: StationDep, controller: ControlAuth, body: PoseNameRequest | None = None,
                    wait: bool = False, plan_only: bool = PLAN_ONLY) -> dict:
    """The home pose (body optional: {moving_time_s}). ?plan_only=true: the plan, nothing moves."""
    return await _named_pose(request, station, controller, "home", body, wait, plan_only)


@router.post("/arm/sleep", response_model=Status | MovePlan)
async def post_sleep(request: Request, station: StationDep, controller: ControlAuth, body: PoseNameRequest | None = None,
                     wait: bool = False, plan_only: bool = PLAN_ONLY) -> dict:
    """The folded rest pose (body optional: {moving_time_s}). ?plan_only=true: the plan, nothing moves."""
    return await _named_pose(request, station, controller, "sleep", body, wait, plan_only)


@router.post("/arm/joints", response_model=Status | MovePlan)
async def post_joints(request: Request, body: JointsRequest, station: StationDep, controller: ControlAuth, wait: bool = False,
                      plan_only: bool = PLAN_ONLY) -> dict:
    """Joint move (radians); out-of-limit or malformed → 422 and nothing moves. ?plan_only=true: the plan, nothing moves."""
    if plan_only:
        return await run_in_threadpool(station.plan_only, "move_joints", body.q_rad, body.moving_time_s, source=controller)
    await run_in_threadpool(station.move_joints, body.q_rad, body.moving_time_s, wait=False, source=controller)
    return await _answer(request, station, wait)


@router.post("/arm/pose", response_model=Status | MovePlan)
async def post_pose(request: Request, body: PoseRequest, station: StationDep, controller: ControlAuth, wait: bool = False,
                    plan_only: bool = PLAN_ONLY) -> dict:
    """Move the gripper point to a world position; unreachable → 422 'unreachable' and nothing moves. ?plan_only=true:
    the plan, nothing moves."""
    if plan_only:
        pose = (body.position_m, body.pitch_rad, body.yaw_rad)
        return await run_in_threadpool(station.plan_only, "move_to", None, body.moving_time_s, pose=pose, source=controller)
    await run_in_threadpool(station.move_to, body.position_m, body.pitch_rad, body.yaw_rad, body.moving_time_s, wait=False, source=controller)
    return await _answer(request, station, wait)


@router.post("/arm/joints/check", response_model=MoveCheck)
def post_joints_check(body: JointsRequest, station: StationDep) -> dict:
    """The joint move POST /arm/joints would make, checked the same way (limits, board, workspace, the arm against
    itself), moving nothing: the goal and its duration, or 422 with the reason."""
    return station.check_move(body.q_rad, body.moving_time_s)


@router.post("/arm/pose/check", response_model=MoveCheck)
def post_pose_check(body: PoseRequest, station: StationDep) -> dict:
    """The move POST /arm/pose would make (IK, then the joint move's checks), moving nothing: the goal joints and
    the move's duration, or 422 'unreachable' / the check's reason."""
    return station.check_move(moving_time_s=body.moving_time_s, pose=(body.position_m, body.pitch_rad, body.yaw_rad))


@router.post("/arm/torque", response_model=Status)
def post_torque(body: TorqueRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Torque on or off; off outside teach lets the arm fall, so it needs confirm: true (409 otherwise)."""
    station.set_torque(body.enabled, source=controller, confirm=body.confirm)
    return station.status()


@router.post("/arm/jog", response_model=Status)
def post_jog(body: JogRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Hold-to-run joint jog: runs for jog_hold_s after this request or the controller's last heartbeat
    (POST /api/heartbeat or the websocket's heartbeat message), then ramps to rest by itself."""
    station.jog(body.velocity_rad_s, source=controller, speed_percent=body.speed_percent)
    return station.status()


@router.post("/arm/jog/cartesian", response_model=Status)
def post_cartesian_jog(body: CartesianJogRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Hold-to-run Cartesian jog: the gripper point moves along world x|y|z keeping its pitch and yaw, for jog_hold_s
    after this request or the controller's last heartbeat, then ramps to rest by itself; it brakes before a place
    the line cannot pass (the board, a joint limit, out of reach, the arm itself), 422 with the reason when it
    cannot move at all."""
    station.jog_cartesian(body.axis, body.velocity_m_s, source=controller, speed_percent=body.speed_percent)
    return station.status()


@router.post("/arm/jog/stop", response_model=Status)
def post_jog_stop(station: StationDep, controller: ControlAuth) -> dict:
    """The controller let go: its hold-to-run jog (joint or Cartesian) ramps down to rest now (nothing when none runs)."""
    station.stop_jog(source=controller)
    return station.status()


@router.post("/arm/step", response_model=Status | MovePlan)
async def post_step(request: Request, body: StepRequest, station: StationDep, controller: ControlAuth, wait: bool = False,
                    plan_only: bool = PLAN_ONLY) -> dict:
    """Jog step of the gripper: along world x/y/z keeping its pitch and yaw, or a pitch/roll rotation; a step
    that cannot keep them → 422 with the reason, a step while the arm moves → 409; nothing moves then.
    ?plan_only=true: the step planned from the measured joints (the plan), nothing moves."""
    amount = body.distance_m if body.axis in ("x", "y", "z") else body.angle_rad
    if plan_only:
        return await run_in_threadpool(station.step_gripper, body.axis, amount, body.speed_percent, source=controller,
                                       plan_only=True)
    await run_in_threadpool(station.step_gripper, body.axis, amount, body.speed_percent, wait=False, source=controller)
    return await _answer(request, station, wait)


@router.post("/gripper", response_model=Status)
async def post_gripper(request: Request, body: GripperRequest, station: StationDep, controller: ControlAuth, wait: bool = True) -> dict:
    """Grasp or release; waits (default) until the fingers are still."""
    await run_in_threadpool(station.gripper_command, body.action, wait=False, source=controller)
    if wait:
        await until_fingers_still(request, station)
    return await run_in_threadpool(station.status)
