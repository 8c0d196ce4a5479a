"""Autonomous jobs' request and responses (server/routes/auto.py)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from server.response_models import Detection, JobInfo
from server.wire_base import Request, Vector3, Wire

AUTO_LEVEL_LIMIT = 100  # sanity bound; the job's own levels (GET /api/auto/jobs) are checked by the station
AUTO_PARAMS_MAX = 32


class AutoRequest(Request):
    """Start an autonomous job: a name from GET /api/auto/jobs, one of its levels, its parameters."""

    job: str = Field(min_length=1, max_length=64, description="job name (GET /api/auto/jobs)")
    level: int | None = Field(None, ge=0, le=AUTO_LEVEL_LIMIT, description="one of the job's levels; None = its highest")
    params: dict[Annotated[str, Field(max_length=64)], Any] | None = Field(
        None, max_length=AUTO_PARAMS_MAX, description="job parameters by name, each of the type GET /api/auto/jobs gives"
    )


class AutoParam(Wire):
    name: str
    type: str = Field(description="Python type name: int, float, str, bool, list, ...")


class AutoJobInfo(Wire):
    name: str
    levels: list[int] = Field(description="[] = the job has no levels")
    summary: str
    params: list[AutoParam]
    judged: bool = Field(description="a competition event (DESIGN §7): the simulation scores it with the judge")
    scored: bool = Field(description="the simulation scores it: the judge (§7), else the job's own scorer")
    scene: bool = Field(description="POST /api/sim/scene can generate its starting scene")
    time_limit_s: float | None = Field(None, description="the event's time limit, simulated seconds")
    available: bool = Field(True, description="the station's workcell can run it (its gripper type and geometry)")
    unavailable_reason: str | None = Field(None, description="why not, when not available: what the workcell lacks")


class AutoJobsResponse(Wire):
    data: list[AutoJobInfo]
    count: int


class TaskProgress(Wire):
    """job.extra.task of a running autonomous job (also on the websocket's telemetry)."""

    done: int
    left: int
    step: str
    attempts: int
    failures: list[str]
    moves: int
    next_block: Detection | None = Field(None, description="the block being moved (a detection)")
    next_target_m: Vector3 | None = Field(None, description="where it goes: bottom-centre x, y and surface z, world frame")


class ScoreRule(Wire):
    rule: str
    points: int
    detail: str
    object_ids: list[str]


class AutoScore(Wire):
    points: int
    max_points: int
    within_limit: bool
    full: bool
    time_limit_s: float
    breakdown: list[ScoreRule]


class AutoScoreResponse(Wire):
    """The judge's score of the last autonomous job started over the API (simulation only)."""

    job_id: str
    job: str
    level: int | None
    state: Literal["running", "succeeded", "failed", "cancelled"]
    final: bool = Field(description="True once the job has ended and its final ground truth was scored")
    sim_time_s: float = Field(description="simulated seconds from the job's start to its end (so far, while running)")
    score: AutoScore | None = Field(None, description="None while running, or for a job the judge does not score")
    note: str = ""


class AutoResponse(Wire):
    job: JobInfo
    score: AutoScoreResponse | None = Field(None, description="with ?wait=true in the simulation: the final score")
