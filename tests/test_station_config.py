"""config/station.yaml loads; bad values are refused naming the file and field; CLI overrides apply."""

import argparse

import pytest

from armlab.cli.serve_cmd import build_station_config
from armlab.errors import ConfigError
from armlab.station import StationConfig, load_station_config


def test_repository_config_loads():
    config = load_station_config()
    assert config.arm == "rx200" and config.telemetry_rate_hz >= 20
    assert config.database_file().name == "armlab.sqlite3" and config.database_file().is_absolute()


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("telemetry_rate_hz: 5\n", "telemetry_rate_hz"),
        ("jpeg_quality: .nan\n", "jpeg_quality"),
        ("perception_rate_hz: 0\n", "perception_rate_hz"),
        ("speed: 3\n", "speed"),
        ("sim: {level: 7}\n", "sim.level"),
    ],
)
def test_bad_config_names_file_and_field(tmp_path, text, field):
    path = tmp_path / "station.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as caught:
        load_station_config(path)
    assert str(path) in str(caught.value) and field in str(caught.value)


def test_serve_overrides_sim_start(tmp_path):
    path = tmp_path / "station.yaml"
    path.write_text("sim: {seed: 4, event: null}\n")
    args = argparse.Namespace(config=str(path), seed=None, event="line_up", level=2, scene_seed=9)
    config = build_station_config(args)
    assert (config.sim.seed, config.sim.event, config.sim.level, config.sim.scene_seed) == (4, "line_up", 2, 9)
    assert StationConfig().sim.event is None
