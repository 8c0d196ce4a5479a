"""Which calibration tags the station's board carries: the workcell's own, a named config/boards/<name>.yaml, or
("auto") the first of those whose tags a camera frame shows.

The workcell decides the board's geometry; only its tags are swapped. "auto" exists for recordings: frames
from the ROB 550 course carry tagStandard41h12 tags (config/boards/rob550.yaml), the default workcell's
simulated board tag36h11, and a recording says nothing about which it holds. Its choice is printed.
"""

from __future__ import annotations

from armlab.config import config_dir, read_config_file, resolve_config_path, validate_config
from armlab.errors import ConfigError
from armlab.vision import detect_tags, load_perception_config
from armlab.workcell import Workcell, load_workcell

AUTO = "auto"
MIN_TAGS = 3  # as many board tags as a calibration needs


def known_boards() -> list[str]:
    """Names of the files in config/boards/."""
    return sorted(path.stem for path in (config_dir() / "boards").glob("*.yaml"))


def workcell_with_board(workcell: str, board: str):
    """The workcell (config/workcells/<workcell>.yaml) with its board tags taken from config/boards/<board>.yaml."""
    if board not in known_boards():
        raise ConfigError(f"board '{board}': no config/boards/{board}.yaml (known: {', '.join(known_boards()) or 'none'})")
    path = resolve_config_path(load_workcell(workcell).name, "workcells")
    return validate_config({**read_config_file(path), "board_tags": board}, Workcell, f"{path} with board {board}")


def board_perception_config(workcell: str, board: str | None, color_bgr=None):
    """(armlab.vision PerceptionConfig or None for the workcell's own, a one-line note or None).

    board None: the workcell's tags. A name: config/boards/<name>.yaml. "auto": the workcell's tags if
    `color_bgr` shows at least MIN_TAGS of them, else the first board in config/boards/ whose tags it shows,
    else the workcell's (the note says none was seen)."""
    if board is None:
        return None, None
    if board != AUTO:
        return load_perception_config(workcell=workcell_with_board(workcell, board)), f"board tags: config/boards/{board}.yaml"
    if color_bgr is None:
        raise ValueError("board 'auto' needs a camera frame to look for tags in")
    candidates = [(None, load_perception_config(workcell=workcell))]
    candidates += [(name, load_perception_config(workcell=workcell_with_board(workcell, name))) for name in known_boards()]
    for name, config in candidates:
        seen = {tag.id for tag in detect_tags(color_bgr, config)} & set(config.tags.board_tags)
        if len(seen) >= MIN_TAGS:
            origin = f"the workcell's ({workcell})" if name is None else f"config/boards/{name}.yaml"
            return (None if name is None else config), f"board tags: {origin}, {config.tags.dictionary}: ids {sorted(seen)} in the first frame"
    return None, f"board tags: none of the known boards' tags are in the first frame; using the workcell's ({workcell})"
