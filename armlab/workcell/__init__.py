"""The workcell config (config/workcells/<name>.yaml), one fact in one place (DESIGN §3). The package re-exports
the names most callers use; the rest come from their modules: model (Workcell), loading (load_workcell,
known_workcells, the arm model and motion config of a workcell), board, objects, rig and spots (the sections),
tag_families and fields."""

from armlab.workcell.loading import DEFAULT_WORKCELL, load_workcell, load_workcell_arm
from armlab.workcell.model import Workcell

__all__ = ["DEFAULT_WORKCELL", "Workcell", "load_workcell", "load_workcell_arm"]
