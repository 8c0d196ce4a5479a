"""The SQLite store: programs, calibrations and job results survive reopening the file."""

import math

import pytest

from armlab.store import NotFound, Store, Waypoint


def test_programs_persist_across_store_instances(tmp_path):
    path = tmp_path / "sub" / "station.sqlite3"
    first = Store(path)
    saved = first.save_program("wave", [Waypoint((0.0, 0.1, 0.2, 0.3, 0.4), "release"), Waypoint((0.5, 0, 0, 0, 0), "grasp")])
    reopened = Store(path)
    programs = reopened.list_programs()
    assert [p.name for p in programs] == ["wave"]
    assert programs[0].id == saved.id
    assert programs[0].waypoints[0].joints_rad == (0.0, 0.1, 0.2, 0.3, 0.4)
    assert programs[0].waypoints[1].gripper == "grasp"
    assert reopened.get_program(saved.id).to_dict() == saved.to_dict()


def test_program_ids_increase_and_delete_removes(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    a = store.save_program("a", [Waypoint((0.0,), "release")])
    b = store.save_program("b", [Waypoint((1.0,), "grasp")])
    assert b.id > a.id
    store.delete_program(a.id)
    assert [p.name for p in store.list_programs()] == ["b"]
    with pytest.raises(NotFound, match=str(a.id)):
        store.get_program(a.id)


@pytest.mark.parametrize(
    ("name", "waypoints", "message"),
    [
        ("", [Waypoint((0.0,), "release")], "name"),
        ("empty", [], "waypoint"),
    ],
)
def test_invalid_programs_are_refused(tmp_path, name, waypoints, message):
    store = Store(tmp_path / "db.sqlite3")
    with pytest.raises(ValueError, match=message):
        store.save_program(name, waypoints)
    assert store.list_programs() == []


@pytest.mark.parametrize(("joints", "gripper"), [((math.nan,), "grasp"), ((0.0,), "squeeze"), ((), "grasp")])
def test_bad_waypoints_are_refused(joints, gripper):
    with pytest.raises(ValueError):
        Waypoint(joints, gripper)


def test_latest_calibration_and_job_results(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    assert store.latest_calibration() is None
    store.save_calibration({"n": 1})
    store.save_calibration({"n": 2})
    assert Store(tmp_path / "db.sqlite3").latest_calibration() == {"n": 2}
    job = {"id": "j1", "name": "grab", "state": "running", "message": "", "started_s": 10.0, "finished_s": None, "result": None}
    store.record_job(job)
    store.record_job({**job, "state": "succeeded", "finished_s": 12.0, "result": {"holding": True}})
    results = store.job_results()
    assert len(results) == 1 and results[0]["state"] == "succeeded" and results[0]["result"] == {"holding": True}


# Damaged data (issue 10, item 7) ------------------------------------------------------------------

import json  # noqa: E402
import os  # noqa: E402
import signal  # noqa: E402
import sqlite3  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

from armlab.store import DamagedDatabase  # noqa: E402

WAYPOINTS = [Waypoint((0.1 * i, 0.0, 0.2, 0.3, 0.4), "release" if i % 2 else "grasp") for i in range(4)]


def _filled(path: Path, programs: int = 40, backups: int = 0) -> Store:
    store = Store(path, backups=backups)
    for index in range(programs):
        store.save_program(f"program {index}", WAYPOINTS * 10)  # ~40 waypoints: rows span many pages
    store.save_calibration({"n": 1})
    return store


def _assert_one_line_naming(error: DamagedDatabase, *paths: Path) -> str:
    message = str(error)
    assert "\n" not in message and len(message) < 800, message
    for path in paths:
        assert str(path) in message, message
    return message


def test_a_garbage_file_is_refused_naming_it(tmp_path):
    path = tmp_path / "station.sqlite3"
    path.write_bytes(os.urandom(8192))
    with pytest.raises(DamagedDatabase) as refused:
        Store(path)
    message = _assert_one_line_naming(refused.value, path)
    assert "not a database" in message or "damaged" in message
    assert path.read_bytes()[:16] != b"SQLite format 3\x00"  # the damaged file is left as it was, for inspection


def test_a_truncated_file_is_refused_and_names_the_last_good_backup(tmp_path):
    path = tmp_path / "station.sqlite3"
    _filled(path)
    Store(path, backups=2)  # start-up after a good check: makes <db>.bak1
    backup = Path(f"{path}.bak1")
    assert backup.exists() and backup.stat().st_size > 0
    size = path.stat().st_size
    with path.open("r+b") as handle:
        handle.truncate(size // 2)
    with pytest.raises(DamagedDatabase) as refused:
        Store(path, backups=2)
    _assert_one_line_naming(refused.value, path, backup)
    assert Path(f"{path}.bak1").read_bytes()[:16] == b"SQLite format 3\x00"  # a refused start makes no backup of garbage
    assert len(Store(backup).list_programs()) == 40  # the named backup really holds the data


def test_a_corrupted_page_is_found_by_the_start_up_check(tmp_path):
    path = tmp_path / "station.sqlite3"
    _filled(path)
    page_size = sqlite3.connect(path).execute("PRAGMA page_size").fetchone()[0]
    pages = path.stat().st_size // page_size
    with path.open("r+b") as handle:
        handle.seek(page_size * (pages // 2))
        handle.write(b"\xa5" * page_size)
    with pytest.raises(DamagedDatabase) as refused:
        Store(path)
    _assert_one_line_naming(refused.value, path)


def test_an_empty_existing_file_is_damaged_but_a_missing_one_is_new(tmp_path):
    empty = tmp_path / "empty.sqlite3"
    empty.write_bytes(b"")
    with pytest.raises(DamagedDatabase, match="0 bytes") as refused:
        Store(empty)
    _assert_one_line_naming(refused.value, empty)
    new = tmp_path / "new.sqlite3"
    assert Store(new).list_programs() == [] and new.stat().st_size > 0


def test_rolling_backups_keep_the_last_n(tmp_path):
    path = tmp_path / "station.sqlite3"
    store = Store(path, backups=2)
    names = []
    for index in range(4):
        store.save_program(f"p{index}", WAYPOINTS)
        names.append(f"p{index}")
        Store(path, backups=2)  # a start
    backups = sorted(p.name for p in tmp_path.iterdir() if ".bak" in p.name)
    assert backups == ["station.sqlite3.bak1", "station.sqlite3.bak2"]
    assert [p.name for p in Store(Path(f"{path}.bak1")).list_programs()] == names  # newest: all four
    assert [p.name for p in Store(Path(f"{path}.bak2")).list_programs()] == names[:3]  # the start before
    Store(path, backups=0)
    assert sorted(p.name for p in tmp_path.iterdir() if ".bak" in p.name) == backups  # 0 = no new backup


def _raw_insert(path: Path, name_sql: str, waypoints_sql: str) -> None:
    connection = sqlite3.connect(path)
    with connection:
        connection.execute(f"INSERT INTO programs (name, created_s, waypoints_json) VALUES ({name_sql}, 1.0, {waypoints_sql})")
    connection.close()


def test_a_bad_row_is_reported_and_skipped_never_hiding_the_others(tmp_path, caplog):
    path = tmp_path / "station.sqlite3"
    store = Store(path)
    first = store.save_program("first", WAYPOINTS)
    _raw_insert(path, "CAST(X'66ff6f' AS TEXT)", "'[]'")  # bad UTF-8 in the name
    _raw_insert(path, "'bad json'", "'[{\"joints_rad\": [0.1'")  # truncated JSON
    _raw_insert(path, "'bad waypoint'", "'[{\"joints_rad\": [], \"gripper\": \"grasp\"}]'")  # valid JSON, invalid waypoint
    _raw_insert(path, "'bad utf8 json'", "CAST(X'5b7bff7d5d' AS TEXT)")
    last = store.save_program("last", WAYPOINTS)
    programs, skipped = store.read_programs()
    assert [p.name for p in programs] == ["first", "last"]
    assert len(skipped) == 4 and all(str(path) in entry for entry in skipped), skipped
    assert any("UTF-8" in entry for entry in skipped) and any("JSON" in entry for entry in skipped)
    assert [p.name for p in store.list_programs()] == ["first", "last"]
    assert sum("skipped" in record.getMessage() for record in caplog.records) >= 4
    damaged_id = first.id + 1
    with pytest.raises(NotFound, match="damaged"):
        store.get_program(damaged_id)
    store.delete_program(damaged_id)  # a damaged row can still be removed
    assert len(store.read_programs()[1]) == 3
    assert store.get_program(last.id).name == "last"


def test_bad_calibration_and_job_rows_are_skipped(tmp_path):
    path = tmp_path / "station.sqlite3"
    store = Store(path)
    store.save_calibration({"n": 1})
    connection = sqlite3.connect(path)
    with connection:
        connection.execute("INSERT INTO calibrations (created_s, data_json) VALUES (2.0, '{oops')")
        connection.execute(
            "INSERT INTO job_results (id, name, state, message, started_s, result_json) VALUES ('bad', 'x', 'failed', '', 5.0, '{oops')"
        )
    connection.close()
    store.record_job({"id": "good", "name": "grab", "state": "succeeded", "message": "", "started_s": 1.0, "result": None})
    assert store.latest_calibration() == {"n": 1}  # the newest good one
    assert [job["id"] for job in store.job_results()] == ["good"]


_WRITER = """
import sys
from armlab.store import Store, Waypoint
store = Store(sys.argv[1])
waypoints = [Waypoint((0.001 * i, 0.0, 0.2, 0.3, 0.4), "grasp") for i in range(200)]
i = 0
while True:
    program = store.save_program(f"p{i}", waypoints)
    calibration_id = store.save_calibration({"i": i, "pad": "x" * 20000})
    print(program.id, calibration_id, flush=True)
    i += 1
"""


@pytest.mark.parametrize("acknowledged", [1, 7, 23])
def test_sigkill_while_saving_loses_nothing_acknowledged_and_leaves_no_partial_program(tmp_path, acknowledged):
    path = tmp_path / "station.sqlite3"
    writer = subprocess.Popen([sys.executable, "-c", _WRITER, str(path)], stdout=subprocess.PIPE, text=True,
                              cwd=Path(__file__).resolve().parents[1])
    try:
        acks = [tuple(int(value) for value in writer.stdout.readline().split()) for _ in range(acknowledged)]
        writer.send_signal(signal.SIGKILL)  # mid-write of the next program or calibration, most likely
    finally:
        writer.kill()
        writer.wait(10)
    store = Store(path)  # passes its integrity check
    programs = {program.id: program for program in store.list_programs()}
    assert store.read_programs()[1] == []
    for program_id, _ in acks:
        assert program_id in programs
    assert all(len(program.waypoints) == 200 for program in programs.values())  # all of a program or none of it
    connection = sqlite3.connect(path)
    calibrations = [json.loads(row[0]) for row in connection.execute("SELECT data_json FROM calibrations")]
    connection.close()
    assert len(calibrations) >= acknowledged and all(len(c["pad"]) == 20000 for c in calibrations)


# A read-only file and a full disk (issue 18 item 8): real OS limits on a child process --------------

REPO = Path(__file__).resolve().parents[1]
OPEN_STORE = (
    "import sys; sys.path.insert(0, sys.argv[1]); from armlab.store import Store\n"
    "try:\n    Store(sys.argv[2], backups=2)\nexcept Exception as error:\n"
    "    print(type(error).__name__ + ': ' + str(error)); sys.exit(3)\n"
)


def _open_in_child(db: Path, unprivileged: bool = False, max_file_bytes: int | None = None) -> subprocess.CompletedProcess:
    """Store(db, backups=2) in a child process: unprivileged (uid 65534 when we are root, whom file modes do
    not stop) and/or with RLIMIT_FSIZE (files cannot grow past max_file_bytes: no room for a backup)."""
    import resource

    def limits() -> None:
        if max_file_bytes is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG) instead of killing
            resource.setrlimit(resource.RLIMIT_FSIZE, (max_file_bytes, max_file_bytes))

    command = [sys.executable, "-c", OPEN_STORE, str(REPO), str(db)]
    if unprivileged and os.geteuid() == 0:
        command = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", *command]
    return subprocess.run(command, capture_output=True, text=True, timeout=60, preexec_fn=limits)


@pytest.fixture()
def open_dir():
    """A temporary folder anyone may enter (pytest's tmp_path is private to its user)."""
    import shutil
    import tempfile

    folder = Path(tempfile.mkdtemp(prefix="armlab-store-"))
    folder.chmod(0o755)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_a_read_only_database_is_reported_as_read_only_not_damaged(open_dir):
    path = open_dir / "station.sqlite3"
    _filled(path, programs=2)
    path.chmod(0o444)
    result = _open_in_child(path, unprivileged=True)
    assert result.returncode == 3, result.stdout + result.stderr
    message = result.stdout.strip()
    assert "read-only" in message and str(path) in message and "damaged" not in message, message
    assert "\n" not in message and "Traceback" not in result.stderr


def test_no_room_for_the_start_up_backup_says_so_and_leaves_no_partial_copy(open_dir):
    path = open_dir / "station.sqlite3"
    _filled(path, programs=40)  # ~0.5 MB
    size = path.stat().st_size
    result = _open_in_child(path, max_file_bytes=size // 2)
    assert result.returncode == 3, result.stdout + result.stderr
    message = result.stdout.strip()
    assert "backup" in message and str(path) in message and "Traceback" not in result.stderr, result.stdout + result.stderr
    assert not Path(f"{path}.bak-new").exists(), "a partial backup was left behind"
    assert len(Store(path).list_programs()) == 40  # the database itself is untouched
