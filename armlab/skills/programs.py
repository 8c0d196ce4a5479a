"""Editing taught programs: rename, replace the waypoints, duplicate, export and import (JSON, CSV).

Every waypoint written is checked first (joint limits, above the table, inside the workspace box) and a
malformed file is refused naming the line and the reason; the database is written only after all
checks pass, in one transaction, so a refused edit or import changes nothing stored.

A station sees only its own arm's and workcell's programs (station.program_owner): another arm's program is
counted in the list, never read as joints, and refused by name (WrongArm) when asked for by id.
"""

from __future__ import annotations

from collections.abc import Sequence

from armlab import program_io
from armlab.errors import InvalidInput
from armlab.skills.repeat_plan import RepeatSettings, check_waypoints, plan_transfer, same_pose
from armlab.station.core import Station
from armlab.store import MAX_PROGRAM_NAME_CHARS, DamagedRecord, OwnedPrograms, Program, Waypoint, program_tree


def station_programs(station: Station) -> OwnedPrograms:
    """This station's programs (its arm and workcell), its damaged rows, and how many other arms' there are."""
    return station.store.programs_of(station.program_owner)


def get_program(station: Station, program_id: int) -> Program:
    """The program with this id if it is this station's arm's; NotFound, DamagedRecord, WrongArm."""
    return station.store.get_program(program_id, station.program_owner)


def delete_program(station: Station, program_id: int) -> None:
    """Delete this arm's program (a damaged one too); another arm's is deleted from its own station (WrongArm)."""
    try:
        get_program(station, program_id)
    except DamagedRecord:
        pass  # its owner was checked before its waypoints were read: a damaged row of this arm goes
    station.store.delete_program(program_id)


def update_program(station: Station, program_id: int, name: str | None = None, waypoints: Sequence | None = None) -> Program:
    """Rename and/or replace the waypoints (a flat list or a step tree; every waypoint of the expanded sequence
    checked); NotFound, ValueError, UnsafeTrajectory, WrongArm."""
    get_program(station, program_id)
    if waypoints is not None:
        station.require_arm("editing a program's waypoints")
        check_waypoints(station, list(program_tree.expand(waypoints)))
    return station.store.update_program(program_id, name=name, waypoints=waypoints)


def duplicate_program(station: Station, program_id: int, name: str | None = None) -> Program:
    program = get_program(station, program_id)
    suffix = " (copy)"
    name = name or program.name[: MAX_PROGRAM_NAME_CHARS - len(suffix)] + suffix
    return station.store.save_program(name, program.steps or program.waypoints, owner=station.program_owner)


def move_times_s(station: Station, waypoints: Sequence[Waypoint]) -> list[float]:
    """The planned time of the move into each waypoint at full speed, rest to rest (0 for the first, a
    gripper step or a dwell): the CSV export's t_s gaps."""
    times = [0.0]
    settings = RepeatSettings(ease_in_speed_fraction=1.0)
    for previous, waypoint in zip(waypoints, waypoints[1:]):
        if same_pose(previous, waypoint):
            times.append(0.0)
            continue
        run = plan_transfer(station, previous.joints_rad, waypoint.joints_rad, 100.0, settings, labels=(0, 1))
        times.append(max(run.duration_s, waypoint.moving_time_s or 0.0))
    return times


def export_program(station: Station, program_id: int, file_format: str) -> tuple[str, str]:
    """(file text, suggested file name) of a program as JSON or CSV."""
    station.require_arm("exporting a program (its joints and move times are the arm's)")
    program = get_program(station, program_id)
    stem = "".join(c if c.isalnum() or c in "-_" else "_" for c in program.name)[:60] or f"program-{program.id}"
    if file_format == "json":
        return program_io.to_json(program.name, program.waypoints, station.model.joint_names, program.steps), f"{stem}.json"
    if file_format == "csv":  # flat: the step tree expanded (loops unrolled, waits as dwells)
        return program_io.to_csv(program.waypoints, move_times_s(station, program.waypoints)), f"{stem}.csv"
    raise InvalidInput(f"format must be 'json' or 'csv', not {file_format!r}")


def import_program(station: Station, file_format: str, content: str, name: str | None = None) -> Program:
    """Parse (ProgramFileError naming the line), check every waypoint, then save as a new program."""
    station.require_arm("importing a program (its waypoints are checked against the arm)")
    dof = int(station.model.dof)
    if file_format == "json":
        file_name, waypoints = program_io.parse_json(content, dof)
    elif file_format == "csv":
        file_name, waypoints = None, program_io.parse_csv(content, dof)
    else:
        raise InvalidInput(f"format must be 'json' or 'csv', not {file_format!r}")
    check_waypoints(station, list(program_tree.expand(waypoints)))  # a step tree's expanded sequence
    return station.store.save_program(name or (file_name or "").strip() or "imported", waypoints, owner=station.program_owner)
