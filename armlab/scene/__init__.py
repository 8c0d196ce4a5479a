"""Scenes as data and their generators. The package re-exports the names most callers use; the rest come
from their modules: model (Scene, SceneObject, Feeder, check_can_stand, the colours, sizes and limits),
events (generate_scene, EVENTS and JOBS: every competition event and level of DESIGN §7, sort_by_tag and
clear_table), layout (placing piles in board regions), random_layout (random_scene) and aruco_tops
(with_aruco_tops)."""

from armlab.scene.events import generate_scene
from armlab.scene.model import COLORS, Scene, SceneObject, as_workcell, quat_from_yaw

__all__ = ["COLORS", "Scene", "SceneObject", "as_workcell", "generate_scene", "quat_from_yaw"]
