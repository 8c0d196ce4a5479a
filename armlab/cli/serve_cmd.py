"""`armlab serve`: start the station (on the simulation by default) and its web server."""

from __future__ import annotations

import argparse


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("serve", help="start the control station (simulation by default)")
    parser.add_argument("--host", default="127.0.0.1", help="bind address (default 127.0.0.1: this machine only)")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--token", default=None, help="control token (default: $ARMLAB_TOKEN, else generated)")
    parser.add_argument("--config", default=None, help="station config file (default config/station.yaml)")
    parser.add_argument("--db", default=None, help="SQLite file for programs/calibrations/jobs (default from the config)")
    parser.add_argument("--seed", type=int, default=None, help="simulation seed (camera mount error, noise)")
    parser.add_argument("--event", default=None, help="starting scene: pick_sort, pick_stack, line_up, stack_high, to_the_sky")
    parser.add_argument("--level", type=int, default=None, help="starting scene level (1-3)")
    parser.add_argument("--scene-seed", type=int, default=None, help="starting scene seed")
    parser.add_argument("--workcell", default=None,
                        help="workcell (config/workcells/<name>.yaml: arm, gripper, board, camera); default from the config, rx200_armlab")
    parser.add_argument("--backend", choices=("sim", "real"), default="sim", help="sim (default) or real devices")
    parser.add_argument("--arm", default="interbotix_arm", help="real backend: arm config (config/devices/)")
    parser.add_argument("--gripper", default="interbotix_gripper", help="real backend: gripper config (config/devices/)")
    parser.add_argument("--camera", default="realsense_l515", help="real backend: camera config (config/cameras/)")
    parser.add_argument("--log-level", default="warning", choices=("debug", "info", "warning", "error"))
    parser.set_defaults(func=run_serve)


def build_station_config(args: argparse.Namespace):
    """config/station.yaml (or --config) with the command-line overrides applied."""
    from armlab.config import config_dir, read_config_file, validate_config
    from armlab.station import StationConfig, load_station_config

    config = load_station_config(args.config)
    workcell = getattr(args, "workcell", None)
    if workcell is not None:  # the workcell decides the arm: re-validate the file's own fields with it
        path = args.config or config_dir() / "station.yaml"
        config = validate_config({**read_config_file(path), "workcell": workcell}, StationConfig, f"{path} with --workcell {workcell}")
    sim_updates = {
        key: value
        for key, value in (("seed", args.seed), ("event", args.event), ("level", args.level), ("scene_seed", args.scene_seed))
        if value is not None
    }
    if sim_updates:
        config = config.model_validate({**config.model_dump(), "sim": {**config.sim.model_dump(), **sim_updates}})
    return config


def open_checked_store(db_path, backups: int) -> str | None:
    """Check the database file (and make its rolling backup); None if sound, else the one-line reason."""
    from armlab.store import DamagedDatabase, Store, UnusableDatabase

    try:
        Store(db_path, backups=backups)
    except (DamagedDatabase, UnusableDatabase) as error:
        return str(error)
    return None


def run_serve(args: argparse.Namespace) -> int:
    import os
    import sys

    os.environ.setdefault("MUJOCO_GL", "egl")
    from armlab.station.factory import make_device_station, make_sim_station
    from server.app import create_app
    from server.auth import open_url, resolve_token
    from server.logging_config import log_config
    from server.serving import run

    from armlab.errors import ConfigError

    try:
        config = build_station_config(args)  # the workcell decides the arm: unknown or contradicting names stop here
    except ConfigError as error:
        print(f"armlab serve: {error}", file=sys.stderr, flush=True)
        return 2
    problem = open_checked_store(args.db if args.db is not None else config.database_file(), config.database_backups)
    if problem is not None:
        print(f"armlab serve: {problem}", file=sys.stderr, flush=True)
        return 2
    token, generated = resolve_token(args.token)
    if args.backend == "real":
        def factory():
            return make_device_station(config, args.arm, args.gripper, args.camera, db_path=args.db)
    else:
        def factory():
            return make_sim_station(config, db_path=args.db)
    app = create_app(
        station_factory=factory, token=token, allowed_hosts=[args.host, *config.allowed_hosts], on_close=print_close_report
    )
    url = open_url(args.host, args.port, token)
    origin = "generated" if generated else "given"
    print(f"ArmLab control station ({origin} control token). Open:\n    {url}\n", flush=True)
    if args.host not in ("127.0.0.1", "localhost", "::1"):
        print(f"warning: listening on {args.host}: anyone who can reach it can watch; the token guards control", flush=True)
    run(app, args.host, args.port, args.log_level, log_config())
    return 0


def print_close_report(report: dict) -> None:
    """One line at shutdown: the threads joined, and any still running (a hang to look into)."""
    import sys

    joined = ", ".join(report.get("joined", ())) or "none"
    alive = report.get("alive", ())
    line = f"armlab serve: stopped; threads joined: {joined}"
    if alive:
        line += f"; still running: {', '.join(alive)}"
    print(line, file=sys.stderr, flush=True)
