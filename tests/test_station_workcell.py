"""The workcell decides the station's arm and gripper (issue 12 item 1): `armlab serve --workcell` and
`workcell:` in config/station.yaml run the station on the UR3 suction workcell; the default stays the
RX200; unknown names and contradictions stop start-up with an error naming the file and field."""

from __future__ import annotations

import argparse
import subprocess
import sys

import numpy as np
import pytest

from armlab.cli.serve_cmd import build_station_config
from armlab.errors import ConfigError
from armlab.station import StationConfig, load_station_config


def _args(config: str | None = None, workcell: str | None = None) -> argparse.Namespace:
    return argparse.Namespace(config=config, workcell=workcell, seed=None, event=None, level=None, scene_seed=None)


def test_default_station_is_the_rx200_workcell_and_workcell_decides_the_arm(tmp_path):
    assert (StationConfig().workcell, StationConfig().arm) == ("rx200_armlab", "rx200")
    assert load_station_config().arm == "rx200"
    config = build_station_config(_args(workcell="ur3_suction"))
    assert (config.workcell, config.arm) == ("ur3_suction", "ur3")
    path = tmp_path / "station.yaml"
    path.write_text("workcell: ur3_suction\nsim: {seed: 3}\n")
    assert (load_station_config(path).arm, load_station_config(path).sim.seed) == ("ur3", 3)


def test_contradicting_arm_and_unknown_workcell_are_refused_naming_file_and_field(tmp_path):
    path = tmp_path / "station.yaml"
    path.write_text("arm: rx200\nworkcell: ur3_suction\n")
    with pytest.raises(ConfigError, match=r"station.yaml.*arm: 'rx200' contradicts workcell 'ur3_suction', whose arm is 'ur3'"):
        load_station_config(path)
    path.write_text("arm: rx200\n")  # the file's own arm, and --workcell another arm's workcell
    with pytest.raises(ConfigError, match="--workcell ur3_suction.*contradicts"):
        build_station_config(_args(config=str(path), workcell="ur3_suction"))
    path.write_text("workcell: ur5_gripper\n")
    with pytest.raises(ConfigError, match=r"workcell: unknown workcell 'ur5_gripper'.*available: rx200_armlab, ur3_suction"):
        load_station_config(path)


def test_serve_with_an_unknown_workcell_exits_with_the_known_ones():
    result = subprocess.run([sys.executable, "-m", "armlab.cli", "serve", "--workcell", "nope", "--port", "0"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "unknown workcell 'nope'" in result.stderr and "rx200_armlab, ur3_suction" in result.stderr
    assert "Traceback" not in result.stderr


def test_station_starts_on_the_ur3_suction_workcell(tmp_path):
    from armlab.station.factory import make_sim_station

    sim_station = make_sim_station(StationConfig(workcell="ur3_suction", sim={"event": None}), db_path=tmp_path / "db.sqlite3")
    try:
        station, cell = sim_station.station, sim_station.cell
        assert station.model.name == "ur3" and station.model.joint_names == cell.arm.joint_names
        assert type(station.gripper).__name__ == "SuctionGripper" and station.gripper.gripper_type == "suction"
        assert cell.model.actuator("suction") is not None and cell.model.nu == 6 * 3 + 1  # 6 servos (position, velocity, acceleration feed-forward) + vacuum
        # the station's arm model stands where the simulated arm stands: its FK is the simulated tool point
        assert station.sim.wait_for(lambda: cell.sim_time_s > 0.2, 5.0)
        q = cell.arm.read_joint_state().position_rad
        assert np.linalg.norm(station.model.fk(q)[:3, 3] - cell.gripper_point_m()) < 0.001
        assert station.motion_config.approach_height_m == pytest.approx(0.10)  # the workcell's override
    finally:
        sim_station.close()
