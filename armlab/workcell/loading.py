"""Loading workcells: config/workcells/<name>.yaml (memoised per file version), the names available, and the
arm model and motion config a workcell gives."""

from __future__ import annotations

import functools
import os
from pathlib import Path

from armlab.config import config_dir, load_config, resolve_config_path
from armlab.errors import ConfigError
from armlab.kinematics import load_arm
from armlab.kinematics.arm_model import ArmModel
from armlab.motion_config import MotionConfig, load_motion_config
from armlab.workcell.model import Workcell

DEFAULT_WORKCELL = "rx200_armlab"
_REPO_CONFIG_DIR = str(Path(__file__).resolve().parents[2] / "config")


@functools.lru_cache(maxsize=8)
def _load_cached(path: str, _mtime_ns: int, _size: int) -> Workcell:
    return load_config(path, Workcell)


def load_workcell(name: str | Path = DEFAULT_WORKCELL) -> Workcell:
    """config/workcells/<name>.yaml (under $ARMLAB_CONFIG_DIR if set), or a .yaml/.json path.

    ConfigError naming the file and the field when invalid. The validated model is immutable and
    memoised per file version (path, mtime, size), so hot paths may call this freely."""
    if str(name).endswith((".yaml", ".yml", ".json")):
        path = str(name)
    else:  # config_dir() without its Path.resolve(): this runs per scene object
        path = f"{os.environ.get('ARMLAB_CONFIG_DIR') or _REPO_CONFIG_DIR}/workcells/{name}.yaml"
    try:
        stat = os.stat(path)
    except OSError:
        try:
            path = str(resolve_config_path(name, "workcells"))
        except ConfigError:
            folder = Path(os.environ.get("ARMLAB_CONFIG_DIR") or _REPO_CONFIG_DIR) / "workcells"
            raise ConfigError(f"unknown workcell '{name}': no config '{name}' in {folder} "
                              f"(available: {', '.join(known_workcells())})") from None
        stat = os.stat(path)
    return _load_cached(path, stat.st_mtime_ns, stat.st_size)


def known_workcells() -> list[str]:
    """Names of the workcell files in config/workcells/."""
    return sorted(path.stem for path in (config_dir() / "workcells").glob("*.yaml"))


def load_workcell_arm(workcell: Workcell | str | Path = DEFAULT_WORKCELL):
    """The workcell's arm model: load_arm(workcell.arm) with the base pose the workcell gives it."""
    cell = workcell if isinstance(workcell, Workcell) else load_workcell(workcell)
    cell.check_arm_fits()
    model = load_arm(cell.arm)
    if cell.arm_base is None:
        return model
    config = model.config.model_copy(update={"T_world_base": cell.arm_base.T_world_base.tolist()})
    return ArmModel(config, f"{model.name} in workcell {cell.name}")


def load_workcell_motion_config(workcell: Workcell | str | Path = DEFAULT_WORKCELL, path: str | Path | None = None):
    """config/motion.yaml (or `path`) with the workcell's `motion:` overrides applied (approach heights...)."""
    cell = workcell if isinstance(workcell, Workcell) else load_workcell(workcell)
    base = load_motion_config(path)
    if not cell.motion:
        return base
    return MotionConfig.model_validate({**base.model_dump(), **cell.motion})


def block_edge_m(size: str, workcell: Workcell | None = None) -> float:
    """Edge of a cube of `size` in `workcell` (default: the default workcell), metres."""
    return (workcell or load_workcell()).block_edge_m(size)
