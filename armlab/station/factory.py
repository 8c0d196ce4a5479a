"""Building a Station: on the simulated workcell (the default of `armlab serve`) or on real devices."""

from __future__ import annotations

from pathlib import Path

from armlab.devices.factory import make_devices
from armlab.devices.none import NoArm, NoGripper
from armlab.errors import ConfigError
from armlab.scene import generate_scene
from armlab.station.board_choice import AUTO, board_perception_config
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.workcell import load_workcell_arm


class SimStation:
    """A Station plus the SimWorkcell it runs on; close() stops both (station first)."""

    def __init__(self, station: Station, cell) -> None:
        self.station = station
        self.cell = cell

    def close(self) -> dict:
        """Close the station then the simulation; the station's report ({"joined", "alive"} thread names)
        with the simulation's threads added."""
        report = {"joined": [], "alive": []}
        try:
            report = self.station.close() or report
        finally:
            self.cell.close()
        threads = {"sim-physics": getattr(self.cell, "_physics_thread", None)}
        for name, thread in threads.items():
            if thread is not None:
                report["alive" if thread.is_alive() else "joined"].append(name)
        return report


def make_sim_station(config: StationConfig | None = None, db_path: str | Path | None = None) -> SimStation:
    """Start a real-time SimWorkcell (seed and starting scene from config.sim) and a started Station on it."""
    from armlab.devices.sim import (  # MuJoCo only when simulating (tests/test_layering.py)
        SimWorkcell,
        SimWorkcellConfig,
    )

    config = config or StationConfig()
    cell = SimWorkcell(SimWorkcellConfig(realtime=True, seed=config.sim.seed, camera_fps=config.sim.camera_fps,
                                         workcell=config.workcell, realism=config.sim.realism, time_scale=config.sim.time_scale))
    cell.start()
    try:
        if config.sim.event:
            cell.set_scene(generate_scene(config.sim.event, level=config.sim.level, seed=config.sim.scene_seed,
                                          workcell=config.workcell))
        store = Store(db_path if db_path is not None else config.database_file())
        station = Station(
            cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(config.workcell), config=config, store=store, sim=cell,
            backend="sim",
        )
        station.start()
    except BaseException:
        cell.close()
        raise
    return SimStation(station, cell)


class DeviceStation:
    """A Station on real (or mixed) devices; close() stops the station, then closes the devices it opened."""

    def __init__(self, station: Station, notes: tuple[str, ...] = ()) -> None:
        self.station = station
        self.notes = notes  # what start-up chose and why (the board tags found, the recording played), to print

    def close(self) -> dict:
        report = {"joined": [], "alive": []}
        try:
            report = self.station.close() or report
        finally:
            _close_devices(self.station.arm, self.station.gripper, self.station.camera)
        return report


def _close_devices(*devices) -> None:
    for device in devices:
        try:
            device.close()
        except Exception:  # noqa: BLE001 - closing the others matters more
            pass


def make_device_station(
    config: StationConfig | None = None,
    arm: str = "interbotix_arm",
    gripper: str = "interbotix_gripper",
    camera="realsense_l515",
    db_path: str | Path | None = None,
    board: str | None = None,
) -> DeviceStation:
    """A started Station on devices chosen by config files (config/devices/, config/cameras/); `camera` may also
    be a config mapping. arm "none" (config/devices/none.yaml): a station with no arm (and no gripper), perception
    only: every motion command is refused with the reason.

    Connect failures (no hardware, missing SDK, a recording that cannot be played) raise the device's clear
    error; whatever was opened is closed. board: the board's tags (armlab.station.board_choice): None the
    workcell's, a config/boards/ name, or "auto" (the known board whose tags the first frame shows).
    """
    config = config or StationConfig()
    devices = make_devices(arm, gripper, camera)
    has_arm = not isinstance(devices.arm, NoArm)
    if not has_arm and not isinstance(devices.gripper, NoGripper):
        raise ConfigError(f"gripper '{gripper}': a station with no arm has no gripper either (use gripper 'none')")
    try:
        perception_config, board_note = _board(config.workcell, board, devices.camera)
        store = Store(db_path if db_path is not None else config.database_file())
        model = load_workcell_arm(config.workcell) if has_arm else None
        station = Station(devices.arm, devices.gripper, devices.camera, model=model, config=config, store=store,
                          perception_config=perception_config, backend="real")
        station.start()
    except BaseException:
        _close_devices(devices.arm, devices.gripper, devices.camera)
        raise
    notes = [getattr(devices.camera, "description", None), board_note]
    for note in filter(None, notes):
        station.events.add("info", note)
    return DeviceStation(station, tuple(filter(None, notes)))


def _board(workcell: str, board: str | None, camera):
    """The perception config for `board` (None: the workcell's own) and a note; "auto" connects the camera to look."""
    frame = None
    if board == AUTO:
        if not camera.is_connected:
            camera.connect()
        frame = camera.read().color_bgr
    return board_perception_config(workcell, board, frame)


def make_offline_station(config: StationConfig | None = None, db_path: str | Path | None = None) -> Station:
    """A station for scripts that read and write its database (`armlab programs`): the workcell's arm model, its
    saved arm calibration (as a started station restores it) and every pose check, no devices, never started;
    nothing it does moves anything. The database is the one `armlab serve` opens with the same config and --db."""
    config = config or StationConfig()
    store = Store(db_path if db_path is not None else config.database_file(), backups=0)
    station = Station(NoArm(), NoGripper(), None, model=load_workcell_arm(config.workcell), config=config, store=store,
                      backend="offline")
    if config.restore_calibration:
        station.arm_calibration.restore()
    return station
