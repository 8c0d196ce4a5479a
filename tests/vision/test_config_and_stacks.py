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
        (lambda d: d["tags"].update(dictionary="DICT_NOT_A_DICT"), "tags.dictionary"),
        (lambda d: d["board"].update(x_range_m=[0.5, -0.5]), "board"),
        (lambda d: d["blocks"].update(small_size_m=0.05), "blocks"),
        (lambda d: d["blocks"]["colors"].update(red=200), "blocks"),
        (lambda d: d["tags"]["block_tags"].update({100: {"color": "pink", "destination": 1}}), "block_tags"),
        (lambda d: d["blocks"].update(min_height_m=float("nan")), "blocks.min_height_m"),
        (lambda d: d["tags"].update(board_tags={1: [0.0, 0.0]}), "tags"),
        (lambda d: d.update(extra_section=1), "extra_section"),
    ],
)
def test_bad_config_is_a_clear_error(tmp_path, mutate, field):
    with pytest.raises(ConfigError, match=field):
        load_perception_config(_write(tmp_path, mutate))


def test_default_config_loads(cfg):
    assert cfg.tags.dictionary == "DICT_APRILTAG_36h11"
    assert set(cfg.blocks.colors) == {"red", "orange", "yellow", "green", "blue", "violet"}
    assert cfg.tags.block_tags[150].color == "red" and cfg.tags.block_tags[150].destination == 2


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
