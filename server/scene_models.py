"""Request bodies of the simulation's scene routes (server/routes/sim.py, POST /api/auto's scene)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from armlab.scene import COLORS
from armlab.scene.events import JOBS as SCENE_JOBS
from armlab.scene.model import MAX_SCENE_OBJECTS, OBJECT_TYPES, SIZES
from server.wire_base import Angle, Position, Request


class SceneObjectRequest(Request):
    """One object of an explicit scene, in the ground-truth format (quat_wxyz wins over yaw_rad)."""

    id: str = Field(pattern=r"^[A-Za-z0-9_.:-]{1,64}$")
    type: Literal[OBJECT_TYPES]  # type: ignore[valid-type]
    color: Literal[COLORS]  # type: ignore[valid-type]
    size: Literal[SIZES] | None = Field(None, description="blocks: large (default) or small; distractors: None = large")  # type: ignore[valid-type]
    position_m: Position = Field(description="body centre, world frame")
    yaw_rad: Angle | None = None
    quat_wxyz: Annotated[list[Annotated[float, Field(ge=-1e6, le=1e6)]], Field(min_length=4, max_length=4)] | None = Field(
        None, description="orientation (w, x, y, z), non-zero; normalised by the station"
    )
    aruco_id: int | None = Field(None, ge=0, le=249, description="ArUco tag (DICT_4X4_250) on a block's top face")


class CameraBumpRequest(Request):
    """Simulation only: knock the camera mount, as a bump on the rig would (the camera's own OpenCV frame)."""

    translation_m: Annotated[list[Annotated[float, Field(ge=-0.05, le=0.05)]], Field(min_length=3, max_length=3)] = Field(
        description="shift of the camera, metres (each |value| <= 0.05)")
    rotation_rad: Annotated[list[Annotated[float, Field(ge=-0.1, le=0.1)]], Field(min_length=3, max_length=3)] = Field(
        description="rotation vector of the turn, radians (each |value| <= 0.1)")


class SceneRequest(Request):
    """A generated competition scene (event, level, seed) or explicit objects (ground-truth format)."""

    event: Literal[tuple(SCENE_JOBS)] | None = Field(None, description="a competition event or another job with a scene generator")  # type: ignore[valid-type]
    level: int | None = Field(None, ge=1, le=3)
    seed: int | None = Field(None, ge=0, le=2**32 - 1)
    objects: list[SceneObjectRequest] | None = Field(None, max_length=MAX_SCENE_OBJECTS)

    @model_validator(mode="after")
    def _one_kind(self) -> SceneRequest:
        if (self.event is None) == (self.objects is None):
            raise ValueError("give either event (with level and seed) or objects")
        return self
