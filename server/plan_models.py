"""Wire models of "plan, then execute" (issue 22 item 2): the plan a `?plan_only=true` move answers with, and what
DELETE /api/plans/{plan_id} answers (server/routes/plans.py)."""

from __future__ import annotations

from pydantic import Field

from server.response_models import GripperPose
from server.wire_base import Wire


class MovePlan(Wire):
    """A motion planned and checked as the move itself would be, moving nothing (POST /api/arm/pose or /api/arm/joints
    with ?plan_only=true). POST /api/plans/{plan_id}/execute sends exactly this trajectory; it is refused once the plan
    is stale (stale_when)."""

    plan_id: str = Field(description="the plan's id, for POST /api/plans/{plan_id}/execute and DELETE /api/plans/{plan_id}")
    command: str = Field(description="the station command it executes as (move_joints, move_to, home, sleep, jog: a jog step; grab, drop: "
                         "a job of several motions and gripper steps; repeat: a repeat's motions; step: a paused job's next "
                         "step)")
    controller: str | None = Field(description="the controller that made it: only it may execute it")
    goal_q_rad: list[float] = Field(description="the goal joints, radians, joint_names order (grab, drop: where the gripper "
                                    "grasps or releases)")
    duration_s: float = Field(description="the trajectory's duration at the speed override it was planned at")
    times_s: list[float] = Field(description="sample times of the trajectory (decimated for showing; first and last kept)")
    q_rad: list[list[float]] = Field(description="the joints at times_s, radians")
    gripper_path_m: list[list[float]] = Field(description="the gripper point at times_s, world frame, metres")
    gripper_pose: GripperPose = Field(description="the gripper at the goal (commanded kinematics)")
    speed_percent: float = Field(description="the speed override it was planned at")
    created_s: float = Field(description="when it was made (Unix seconds)")
    expires_s: float = Field(description="when it expires (Unix seconds)")
    stale_when: list[str] = Field(description="what makes the station refuse it")
    steps: list[str] = Field(default_factory=list, description="grab, drop: the job's steps in order (motions and gripper "
                             "actions; the trajectory joins the motions); empty for a single move")


class PlanDiscarded(Wire):
    """DELETE /api/plans/{plan_id}: the plan is gone; executing it is then refused (404)."""

    plan_id: str
    discarded: bool = True


PLAN_WIRE_MODELS = (MovePlan, PlanDiscarded)
