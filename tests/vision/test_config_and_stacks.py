"""Perception config validation (clear errors naming the field) and the pure stack arithmetic."""

from __future__ import annotations

import pytest
import yaml

from armlab.config import config_dir
from armlab.errors import ConfigError
from armlab.vision import load_perception_config
from armlab.vision.blocks import stack_from_height


def _write(tmp_path, mutate):
    data = yaml.safe_load((config_dir() / "vision.yaml").read_text())
    mutate(data)
    path = tmp_path / "vision.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(
    ("mutate", "field"),
    [
        (lambda d: d["blocks"]["colors"].update(red=200), "blocks"),
        (lambda d: d["blocks"]["colors"].pop("yellow"), "block_tags"),  # a block tag's colour must be a class
        (lambda d: d["blocks"].update(min_height_m=float("nan")), "blocks.min_height_m"),
        (lambda d: d.update(extra_section=1), "extra_section"),
        (lambda d: d.update(workcell="no_such_cell"), "no_such_cell"),
    ],
)
def test_bad_config_is_a_clear_error(tmp_path, mutate, field):
    with pytest.raises(ConfigError, match=field):
        load_perception_config(_write(tmp_path, mutate))


@pytest.mark.parametrize(
    ("mutate", "field"),
    [
        (lambda d: d.update(tags={"dictionary": "DICT_4X4_50"}), "tags.dictionary"),
        (lambda d: d.update(tags={"board_tags": {1: [0.0, 0.0]}}), "tags.board_tags"),
        (lambda d: d.update(board={"x_range_m": [-0.5, 0.5]}), "board.x_range_m"),
        (lambda d: d["blocks"].update(small_size_m=0.025), "blocks.small_size_m"),
    ],
)
def test_a_workcell_fact_copied_into_vision_yaml_is_refused(tmp_path, mutate, field):
    with pytest.raises(ConfigError, match=rf"vision.yaml.*{field}.*workcells/rx200_armlab.yaml"):
        load_perception_config(_write(tmp_path, mutate))


def test_default_config_loads(cfg):
    assert cfg.tags.dictionary == "DICT_APRILTAG_36h11"
    assert set(cfg.blocks.colors) == {"red", "orange", "yellow", "green", "blue", "violet"}
    assert cfg.tags.block_tags[150].color == "red" and cfg.tags.block_tags[150].destination == 2


def test_tag_layout_board_and_sizes_are_the_workcells(cfg):
    from armlab.workcell import load_workcell

    cell = load_workcell()
    assert cfg.workcell == cell.name
    assert cfg.tags.board_tags == cell.board_tags.centres_m
    assert cfg.tags.board_tag_size_m == cell.board_tags.size_m
    assert cfg.tags.dictionary == cell.board_tags.dictionary
    assert cfg.tags.block_tags == cell.block_tags.ids and cfg.tags.block_tag_dictionary == cell.block_tags.dictionary
    assert (cfg.board.x_range_m, cfg.board.y_range_m) == (cell.board.x_range_m, cell.board.y_range_m)
    assert (cfg.blocks.large_size_m, cfg.blocks.small_size_m) == (cell.block_edge_m("large"), cell.block_edge_m("small"))
    assert cfg.board.grid_points_m() == pytest.approx(cell.board.grid_points_m())
    # DESIGN §3, written out independently of both configs:
    assert cfg.tags.board_tags == {1: (-0.25, -0.025), 2: (0.25, -0.025), 3: (0.25, 0.275), 4: (-0.25, 0.275)}
    assert len(cfg.board.grid_points_m()) == 19 * 14


def test_vision_follows_a_changed_workcell(tmp_path, monkeypatch):
    import shutil

    shutil.copytree(config_dir(), tmp_path / "config")
    path = tmp_path / "config" / "workcells" / "rx200_armlab.yaml"
    data = yaml.safe_load(path.read_text())
    data["board_tags"]["centres_m"][2] = [0.300, -0.050]
    data["blocks"]["edges_m"] = {"large": 0.040, "small": 0.020}
    path.write_text(yaml.safe_dump(data))
    monkeypatch.setenv("ARMLAB_CONFIG_DIR", str(tmp_path / "config"))
    cfg = load_perception_config()
    assert cfg.tags.board_tags[2] == (0.300, -0.050)
    assert (cfg.blocks.large_size_m, cfg.blocks.small_size_m) == (0.040, 0.020)


@pytest.mark.parametrize(
    ("top_m", "size", "level", "sizes"),
    [
        (0.038, "large", 1, ("large",)),
        (0.025, "small", 1, ("small",)),
        (0.0632, "small", 2, ("large", "small")),
        (0.0505, "small", 2, ("small", "small")),
        (0.1141, "large", 3, ("large", "large", "large")),
        (0.1515, "large", 4, ("large",) * 4),
    ],
)
def test_stack_from_height(cfg, top_m, size, level, sizes):
    got_level, got_sizes, err = stack_from_height(top_m, size, cfg)
    assert (got_level, got_sizes) == (level, sizes) and err < 0.002
