"""`armlab programs list|import|export`: the station's taught programs from scripts, on its database file (the
one `armlab serve` opens with the same --config, --workcell and --db), checked as the station checks them.

    armlab programs list [--json]
    armlab programs import PATH [--format rosbag2|jointdata|csv|json] [--name N] [--mode waypoints|trajectory]
                                [--clamp RAD] [--topic T]
    armlab programs export ID --format rosbag2|csv|json --out PATH [--storage mcap|sqlite3]

A refused import prints the reason on stderr, exits 1 and stores nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
from datetime import UTC

IMPORT_FORMATS = ("rosbag2", "jointdata", "csv", "json")
EXPORT_FORMATS = ("rosbag2", "csv", "json")


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("programs", help="list, import and export taught programs (the station's database)")
    commands = parser.add_subparsers(dest="programs_command", required=True)

    def common(sub: argparse.ArgumentParser) -> None:
        sub.add_argument("--config", default=None, help="station config file (default config/station.yaml)")
        sub.add_argument("--workcell", default=None, help="workcell (its arm's programs); default from the config")
        sub.add_argument("--db", default=None, help="SQLite file (default: the config's, as armlab serve uses)")

    listing = commands.add_parser("list", help="this arm's programs: id, name, waypoints, last saved")
    common(listing)
    listing.add_argument("--json", action="store_true", help="one JSON document instead of lines")
    listing.set_defaults(func=run_list)

    importing = commands.add_parser("import", help="store a file as a new program (checked first; a refused file stores nothing)")
    common(importing)
    importing.add_argument("path", help="a ROS 2 bag (folder, .mcap, .db3 or .zip), a jointdata .txt, a program .csv or .json")
    importing.add_argument("--format", choices=IMPORT_FORMATS, default=None, help="default: from the name (a folder: rosbag2)")
    importing.add_argument("--name", default=None, help="the program's name (default: the file's name)")
    importing.add_argument("--mode", choices=("waypoints", "trajectory"), default="waypoints",
                           help="rosbag2/jointdata: thin to waypoints (gripper steps and holds kept) or keep the trajectory")
    importing.add_argument("--clamp", type=float, default=0.0, metavar="RAD",
                           help="clamp samples beyond a joint limit by at most RAD into it (default 0: refuse them)")
    importing.add_argument("--topic", default=None, help="rosbag2: the JointState topic (default: the bag's only one)")
    importing.set_defaults(func=run_import)

    exporting = commands.add_parser("export", help="write a program as a ROS 2 bag, CSV or JSON")
    common(exporting)
    exporting.add_argument("id", type=int, help="the program's id (armlab programs list)")
    exporting.add_argument("--format", choices=EXPORT_FORMATS, required=True)
    exporting.add_argument("--out", required=True, help="a new path; rosbag2: a bag folder, or one MCAP file if it ends in .mcap")
    exporting.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap", help="rosbag2 storage (default mcap)")
    exporting.set_defaults(func=run_export)


def _station(args: argparse.Namespace):
    from armlab.cli.serve_cmd import build_station_config
    from armlab.station.factory import make_offline_station

    config = build_station_config(argparse.Namespace(config=args.config, workcell=args.workcell, seed=None, event=None, level=None,
                                                     scene_seed=None, realism=None))
    return make_offline_station(config, db_path=args.db)


def _run(name: str, args: argparse.Namespace, body) -> int:
    from armlab.errors import ArmlabError
    from armlab.store import DamagedDatabase, UnusableDatabase

    try:
        return body(_station(args))
    except (ArmlabError, DamagedDatabase, UnusableDatabase, OSError, ValueError) as error:
        print(f"armlab programs {name}: {error}", file=sys.stderr, flush=True)
        return 1


def run_list(args: argparse.Namespace) -> int:
    from datetime import datetime

    from armlab.skills.programs import station_programs

    def body(station) -> int:
        owned = station_programs(station)
        if args.json:
            print(json.dumps({"programs": [{"id": p.id, "name": p.name, "waypoints": len(p.waypoints), "arm": p.arm,
                                            "workcell": p.workcell, "updated_s": p.updated_s} for p in owned.programs],
                              "skipped": owned.skipped, "others_count": sum(owned.others.values())}))
            return 0
        for program in owned.programs:
            when = datetime.fromtimestamp(program.updated_s or program.created_s, UTC).strftime("%Y-%m-%d %H:%M UTC")
            print(f"{program.id:>5}  {program.name}  ({len(program.waypoints)} waypoints, saved {when})")
        for line in owned.skipped:
            print(f"skipped: {line}")
        if owned.others:
            print(f"({sum(owned.others.values())} programs of other arms or workcells not listed)")
        if not owned.programs:
            print(f"no programs of {station.program_owner.describe()} in {station.store.path}")
        return 0

    return _run("list", args, body)


def run_import(args: argparse.Namespace) -> int:
    from armlab.program_formats import ImportOptions
    from armlab.skills.program_files import guess_format, import_program_file

    def body(station) -> int:
        file_format = args.format or guess_format(args.path)
        options = ImportOptions(mode=args.mode, clamp_rad=args.clamp)
        imported = import_program_file(station, file_format, path=args.path, name=args.name, options=options, topic=args.topic)
        for note in imported.notes:
            print(note)
        program = imported.program
        print(f"stored program {program.id} '{program.name}': {len(program.waypoints)} waypoints ({station.store.path})")
        return 0

    return _run("import", args, body)


def run_export(args: argparse.Namespace) -> int:
    from armlab.skills.program_files import export_program_path

    def body(station) -> int:
        written = export_program_path(station, args.id, args.format, args.out, args.storage)
        print(f"wrote program {args.id} to {written}")
        return 0

    return _run("export", args, body)
