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
    parser.add_argument("--recordings", default=None, metavar="DIR",
                        help="where MCAP recordings go (default: the config's recording.directory, else recordings/ next to the database)")
    parser.add_argument("--seed", type=int, default=None, help="simulation seed (camera mount error, noise)")
    parser.add_argument("--event", default=None, help="starting scene: pick_sort, pick_stack, line_up, stack_high, to_the_sky")
    parser.add_argument("--level", type=int, default=None, help="starting scene level (1-3)")
    parser.add_argument("--scene-seed", type=int, default=None, help="starting scene seed")
    parser.add_argument("--realism", choices=("real", "camera", "ideal"), default=None,
                        help="simulation: real (the camera's imperfections, shadows, clutter; the arm's droop, backlash, "
                             "encoder counts and rig offsets), camera (the real camera, the exact arm) or ideal (exact); "
                             "default from the config, else config/sim.yaml `realism`")
    parser.add_argument("--workcell", default=None,
                        help="workcell (config/workcells/<name>.yaml: arm, gripper, board, camera); default from the config, rx200_armlab")
    parser.add_argument("--backend", choices=("sim", "real"), default=None,
                        help="sim or real devices (default: sim, or real when --arm none or --camera is given)")
    parser.add_argument("--arm", default=None,
                        help="real backend: arm config (config/devices/; default interbotix_arm); 'none': no arm, perception only")
    parser.add_argument("--gripper", default=None, help="real backend: gripper config (config/devices/; default interbotix_gripper)")
    parser.add_argument("--camera", default=None,
                        help="real backend: camera config (config/cameras/: realsense_l515 (default), webcam, recorded)")
    parser.add_argument("--source", default=None,
                        help="the camera's source: recorded: a folder of image_*.png + depth_*.png or a ROS bag; webcam: a device index or video file")
    parser.add_argument("--intrinsics", default=None,
                        help="recorded camera: intrinsics file (K, dist, image_size); default the folder's intrinsics.json or the bag's camera_info")
    parser.add_argument("--board", default=None,
                        help="real backend: the board's tags: a config/boards/ name (rob550: tagStandard41h12) or 'auto' (the known "
                             "board whose tags the first frame shows; the default with a recorded camera); default the workcell's")
    parser.add_argument("--frame", default=None, help="recorded camera (folder): hold the pair image_<FRAME>.png + depth_<FRAME>.png")
    parser.add_argument("--foxglove", type=int, nargs="?", const=8765, default=None, metavar="PORT",
                        help="also stream live to Foxglove: its WebSocket server on PORT (default 8765; view-only, no token: "
                             "see the README)")
    parser.add_argument("--foxglove-host", default="127.0.0.1",
                        help="the Foxglove server's address (default 127.0.0.1; another one needs --foxglove-allow-remote)")
    parser.add_argument("--foxglove-allow-remote", action="store_true",
                        help="let --foxglove-host be a non-loopback address: anyone who can reach it sees the camera and the arm")
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
        for key, value in (("seed", args.seed), ("event", args.event), ("level", args.level), ("scene_seed", args.scene_seed),
                           ("realism", getattr(args, "realism", None)))
        if value is not None
    }
    if sim_updates:
        config = config.model_validate({**config.model_dump(), "sim": {**config.sim.model_dump(), **sim_updates}})
    return config


def device_choice(args: argparse.Namespace) -> tuple[str, str, str, object, str | None]:
    """(backend, arm, gripper, camera config, board) from the command line: --arm none or --camera means real devices;
    --source, --intrinsics and --frame override the camera config's fields. ConfigError naming the option."""
    from armlab.config import read_config_file, resolve_config_path
    from armlab.errors import ConfigError

    arm = args.arm or "interbotix_arm"
    backend = args.backend or ("real" if args.arm == "none" or args.camera is not None else "sim")
    if backend == "sim":
        given = [f"--{name}" for name in ("arm", "gripper", "camera", "source", "intrinsics", "frame", "board")
                 if getattr(args, name, None) is not None]
        if given:
            raise ConfigError(f"{', '.join(given)}: devices are chosen for the real backend; the simulation has its own (drop --backend sim)")
        return backend, arm, "", None, None
    gripper = args.gripper or ("none" if arm == "none" else "interbotix_gripper")
    path = resolve_config_path(args.camera or "realsense_l515", "cameras")
    camera = read_config_file(path)
    overrides = {name: getattr(args, name) for name in ("source", "intrinsics", "frame") if getattr(args, name, None) is not None}
    for name in overrides:
        if (name != "source" and camera.get("type") != "recorded") or (name == "source" and camera.get("type") not in ("recorded", "opencv")):
            raise ConfigError(f"--{name}: the {path.stem} camera ({path}, type {camera.get('type')}) has no {name}")
    if "source" in overrides and camera.get("type") == "opencv" and overrides["source"].isdigit():
        overrides["source"] = int(overrides["source"])
    board = getattr(args, "board", None) or ("auto" if camera.get("type") == "recorded" else None)
    return backend, arm, gripper, {**camera, **overrides}, board


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
    from armlab.errors import ConfigError
    from armlab.station.factory import make_device_station, make_sim_station
    from server.app import create_app
    from server.auth import open_url, resolve_token
    from server.logging_config import log_config
    from server.serving import run

    try:
        config = build_station_config(args)  # the workcell decides the arm: unknown or contradicting names stop here
        backend, arm, gripper, camera, board = device_choice(args)
        check_foxglove(args)
    except ConfigError as error:
        print(f"armlab serve: {error}", file=sys.stderr, flush=True)
        return 2
    problem = open_checked_store(args.db if args.db is not None else config.database_file(), config.database_backups)
    if problem is not None:
        print(f"armlab serve: {problem}", file=sys.stderr, flush=True)
        return 2
    token, generated = resolve_token(args.token)
    made = None
    if backend == "real":
        try:  # built before the server starts: a device or recording that cannot be used stops start-up in one line
            made = make_device_station(config, arm, gripper, camera, db_path=args.db, board=board)
        except (ValueError, ConnectionError, OSError, ImportError) as error:
            print(f"armlab serve: {error}", file=sys.stderr, flush=True)
            return 2
        for note in made.notes:
            print(note, flush=True)
        if not made.station.has_arm:
            print("no arm: perception only (calibrate, detections, click → world); motion commands are refused", flush=True)

        def factory():
            return made
    else:
        def factory():
            return make_sim_station(config, db_path=args.db)
    recordings_dir = args.recordings or config.recordings_dir(args.db)
    live = None
    if args.foxglove is not None:
        from armlab.recording.live import LiveServer

        try:  # bound before the web server starts: a port in use stops start-up in one line
            live = LiveServer(args.foxglove_host, args.foxglove, config.foxglove, allow_remote=args.foxglove_allow_remote,
                              name=f"ArmLab {config.workcell}").start()
        except ConfigError as error:
            print(f"armlab serve: {error}", file=sys.stderr, flush=True)
            if made is not None:
                made.close()
            return 2
    app = create_app(
        station_factory=factory, token=token, allowed_hosts=[args.host, *config.allowed_hosts], on_close=print_close_report,
        recordings_dir=recordings_dir, live=live,
    )
    url = open_url(args.host, args.port, token)
    origin = "generated" if generated else "given"
    print(f"ArmLab control station ({origin} control token). Open:\n    {url}\n", flush=True)
    print(f"recordings go to {recordings_dir}", flush=True)
    if live is not None:
        print(f"Foxglove: open connection > Foxglove WebSocket > {live.url} (layout: config/foxglove/armlab_layout.json)", flush=True)
        if not is_loopback(args.foxglove_host):
            print(f"warning: Foxglove on {args.foxglove_host}: no token; anyone who can reach port {live.port} sees the camera and "
                  "the arm (view-only: nothing it sends reaches the station)", flush=True)
    if args.host not in ("127.0.0.1", "localhost", "::1"):
        print(f"warning: listening on {args.host}: anyone who can reach it can watch; the token guards control", flush=True)
    try:
        run(app, args.host, args.port, args.log_level, log_config())
    finally:
        if made is not None and made.station.is_running:  # the server never started (e.g. the port is taken)
            made.close()
        if live is not None:
            live.stop()
    return 0


def is_loopback(host: str) -> bool:
    from armlab.recording.live import is_loopback as loopback

    return loopback(host)


def check_foxglove(args: argparse.Namespace) -> None:
    """The --foxglove options, checked before anything starts (ConfigError naming the option)."""
    from armlab.errors import ConfigError
    from armlab.recording.live import check_address

    if args.foxglove is None:
        if args.foxglove_host != "127.0.0.1" or args.foxglove_allow_remote:
            raise ConfigError("--foxglove-host / --foxglove-allow-remote: only with --foxglove [PORT]")
        return
    check_address(args.foxglove_host, args.foxglove, args.foxglove_allow_remote)


def print_close_report(report: dict) -> None:
    """One line at shutdown: the threads joined, and any still running (a hang to look into)."""
    import sys

    joined = ", ".join(report.get("joined", ())) or "none"
    alive = report.get("alive", ())
    line = f"armlab serve: stopped; threads joined: {joined}"
    if alive:
        line += f"; still running: {', '.join(alive)}"
    print(line, file=sys.stderr, flush=True)
