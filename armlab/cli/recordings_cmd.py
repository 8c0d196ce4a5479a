"""`armlab recordings list|export`: the station's MCAP recordings (the folder `armlab serve` records to, with the same
--config, --db and --recordings), and their export as a LeRobot v3.0 dataset.

    armlab recordings list [--json]
    armlab recordings export ID [ID ...] --format lerobot --out DIR [--fps 30] [--task TEXT] [--allow-truncated]

One episode per recording, in the order given. A refused export prints the reason on stderr, exits 1 and writes nothing.
"""

from __future__ import annotations

import argparse
import json
import sys

EXPORT_FORMATS = ("lerobot",)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("recordings", help="list the station's MCAP recordings and export them (LeRobot datasets)")
    commands = parser.add_subparsers(dest="recordings_command", required=True)

    def common(sub: argparse.ArgumentParser) -> None:
        sub.add_argument("--config", default=None, help="station config file (default config/station.yaml)")
        sub.add_argument("--db", default=None, help="SQLite file whose folder holds recordings/ (default: the config's)")
        sub.add_argument("--recordings", default=None, metavar="DIR",
                         help="the recordings folder (default: the config's recording.directory, else recordings/ next to the database)")

    listing = commands.add_parser("list", help="every recording: id, duration, size, label")
    common(listing)
    listing.add_argument("--json", action="store_true", help="one JSON document instead of lines")
    listing.set_defaults(func=run_list)

    exporting = commands.add_parser("export", help="write recordings as a LeRobot v3.0 dataset (one episode each)")
    common(exporting)
    exporting.add_argument("ids", nargs="+", metavar="ID", help="recording ids (armlab recordings list)")
    exporting.add_argument("--format", choices=EXPORT_FORMATS, required=True)
    exporting.add_argument("--out", required=True, help="a new (or empty) folder for the dataset")
    exporting.add_argument("--fps", type=int, default=30, help="frames per second of the dataset (default 30)")
    exporting.add_argument("--task", default=None, help="every episode's task (default: each recording's label, else its jobs)")
    exporting.add_argument("--allow-truncated", action="store_true",
                           help="export a recording cut short up to its last complete chunk (refused by default)")
    exporting.add_argument("--json", action="store_true", help="print the result as JSON")
    exporting.set_defaults(func=run_export)


def _library(args: argparse.Namespace):
    from armlab.recording import RecordingLibrary
    from armlab.station import load_station_config

    config = load_station_config(args.config)
    return RecordingLibrary(args.recordings or config.recordings_dir(args.db), config.recording)


def _run(name: str, body) -> int:
    from armlab.errors import ArmlabError
    from armlab.store import NotFound

    try:
        return body()
    except (ArmlabError, NotFound, OSError) as error:
        print(f"armlab recordings {name}: {error}", file=sys.stderr, flush=True)
        return 1


def run_list(args: argparse.Namespace) -> int:
    def body() -> int:
        items = _library(args).list()
        if args.json:
            print(json.dumps(items, indent=2))
            return 0
        for item in items:
            flags = "truncated" if item["truncated"] else item["state"]
            print(f"{item['id']}  {item['duration_s']:8.1f} s  {item['size_bytes'] / 1e6:8.1f} MB  {flags:9}  {item['label']}")
        return 0

    return _run("list", body)


def run_export(args: argparse.Namespace) -> int:
    from armlab.recording.lerobot import export_library_recordings

    def body() -> int:
        result = export_library_recordings(_library(args), args.ids, args.out, fps=args.fps, tasks=[args.task] * len(args.ids),
                                           allow_truncated=args.allow_truncated)
        if args.json:
            print(json.dumps(result.as_dict(), indent=2))
        else:
            width, height = result.video_size_px
            print(f"wrote {result.out}: LeRobot v3.0, {result.episodes} episode(s), {result.frames} frames at {result.fps} fps, "
                  f"camera {width}x{height} {result.video_codec}, tasks {result.tasks}, in {result.seconds:.1f} s")
        return 0

    return _run("export", body)
