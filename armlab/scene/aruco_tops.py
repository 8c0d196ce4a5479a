"""ArUco tags on the blocks' top faces: a scene's blocks tagged by colour with the workcell's block tags."""

from __future__ import annotations

from armlab.scene.model import Scene, SceneObject, as_workcell
from armlab.workcell import Workcell


def aruco_ids_by_color(workcell: Workcell | None = None) -> dict[str, int]:
    """Colour -> ArUco id of the workcell's block tags (the first id of each colour)."""
    ids: dict[str, int] = {}
    for tag_id, entry in sorted(as_workcell(workcell).block_tags.ids.items()):
        ids.setdefault(entry.color, tag_id)
    return ids


def with_aruco_tops(scene: Scene, ids_by_color: dict[str, int] | None = None) -> Scene:
    """The same scene with an ArUco tag on the top face of every block whose colour has an id
    (default: the scene's workcell's block_tags, e.g. the UR3 write-up's yellow 100, red 150, blue 200)."""
    ids = aruco_ids_by_color(scene.workcell) if ids_by_color is None else ids_by_color
    return Scene(tuple(
        SceneObject(o.id, o.type, o.color, o.size, o.position_m, o.quat_wxyz,
                    ids.get(o.color) if o.type == "block" else None, workcell=o.workcell)
        for o in scene.objects
    ), feeder=scene.feeder, origin=scene.origin, workcell=scene.workcell)
