"""The `armlab` command. Each subcommand group lives in its own module with a `register(subparsers)`
function; modules are imported lazily by name so `armlab fk` never imports MuJoCo or FastAPI."""

from __future__ import annotations

import argparse
import importlib
import sys

# Subcommand modules, each providing register(subparsers) -> None and setting `func` on its parsers.
COMMAND_MODULES = (
    "armlab.cli.serve_cmd",
    "armlab.cli.kinematics_cmd",
    "armlab.cli.sim_cmd",
    "armlab.cli.vision_cmd",
    "armlab.cli.eval_cmd",
    "armlab.cli.programs_cmd",
    "armlab.cli.recordings_cmd",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="armlab", description="ArmLab Control Station")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for module_name in COMMAND_MODULES:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name == module_name:
                continue
            raise
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    result = args.func(args)
    return int(result or 0)


if __name__ == "__main__":
    sys.exit(main())
