"""`armlab eval`: the same seeds give the same results serially, over a process pool and over a local Ray
cluster (real processes, real pool, a real `ray start` head); the --json shape; --truth-out files that
hold each run's final ground truth; and bad input refused with one line on stderr before anything runs."""

import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from armlab.cli import main
from armlab.tasks.evaluate import parse_seeds, run_one
from armlab.tasks.judge import judge

EVENT, LEVEL = "pick_sort", "1"  # the fastest job: ~1-3 s wall per run
SEEDS = [1, 2]
RUN_KEYS = {"event", "level", "seed", "points", "max_points", "sim_time_s", "wall_time_s", "breakdown", "failures"}
CLI_TIMEOUT_S = 600


def eval_cli(*args: str, timeout_s: float = CLI_TIMEOUT_S) -> subprocess.CompletedProcess:
    """`armlab eval` in a real process."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.run([sys.executable, "-m", "armlab.cli", "eval", *args], capture_output=True, text=True,
                          timeout=timeout_s, env=env)


def eval_json(*args: str) -> dict:
    result = eval_cli(*args, "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def without_wall(runs: list[dict]) -> list[dict]:
    return [{k: v for k, v in run.items() if k != "wall_time_s"} for run in runs]


@pytest.fixture(scope="module")
def serial() -> dict:
    """The reference: the seeds one after another in one process."""
    return eval_json(EVENT, "--level", LEVEL, "--seeds", "1-2")


# ---------------------------------------------------------------------------------------------------
# Results


@pytest.mark.slow
def test_json_shape_and_summary(serial):
    assert set(serial) == {"runs", "summary", "record"}
    runs = serial["runs"]
    assert [run["seed"] for run in runs] == SEEDS
    for run in runs:
        assert set(run) == RUN_KEYS
        assert run["event"] == EVENT and run["level"] == 1
        assert 0 <= run["points"] <= run["max_points"] == 100  # pick_sort L1: 3 blocks x 30 + 10 x level 1
        assert 0 < run["sim_time_s"] and 0 < run["wall_time_s"]
        assert sum(rule["points"] for rule in run["breakdown"]) == run["points"]
        assert isinstance(run["failures"], list)
    assert runs[0]["sim_time_s"] != runs[1]["sim_time_s"]  # different seeds, different runs
    summary = serial["summary"]
    fractions = [run["points"] / run["max_points"] for run in runs]
    assert summary["runs"] == 2 and summary["crashed"] == 0
    assert summary["mean_points_fraction"] == pytest.approx(sum(fractions) / 2, abs=1e-4)
    assert summary["min_points_fraction"] == pytest.approx(min(fractions), abs=1e-4)
    assert summary["mean_sim_time_s"] == pytest.approx(sum(r["sim_time_s"] for r in runs) / 2, abs=1e-3)
    assert summary["mean_wall_time_s"] == pytest.approx(sum(r["wall_time_s"] for r in runs) / 2, abs=1e-3)
    rtf = sum(r["sim_time_s"] for r in runs) / sum(r["wall_time_s"] for r in runs)
    assert summary["realtime_factor_per_worker"] == pytest.approx(rtf, rel=1e-2)
    assert summary["realtime_factor_per_cpu_s"] > 0
    assert 0.0 <= summary["full_rate"] <= 1.0
    full = summary["full_points_runs"]
    assert summary["full_points_rate"] == full / 2 == summary["full_rate"]
    assert summary["full_points_ci95"] == pytest.approx(
        {0: [0.0, 0.6576], 1: [0.0945, 0.9055], 2: [0.3424, 1.0]}[full], abs=1e-4)  # Wilson of n = 2, by hand
    low, high = summary["mean_points_ci95"]
    assert low <= summary["mean_points_fraction"] <= high
    record = serial["record"]
    assert record["event"] == EVENT and record["level"] == 1 and record["seeds"] == SEEDS
    assert record["realism"] in ("real", "camera", "ideal") and record["workcell"] == "rx200_armlab"
    head = subprocess.run(["git", "-C", str(Path(__file__).resolve().parents[2]), "rev-parse", "HEAD"],
                          capture_output=True, text=True)
    if head.returncode == 0:
        assert record["git"]["commit"] == head.stdout.strip()


@pytest.mark.slow
def test_process_pool_equals_serial(serial, tmp_path):
    """Two worker processes (spawn), seeds given out of order: the same runs, in seed order; --truth-out
    writes each run's final ground truth, which the judge scores exactly as the run was scored."""
    pooled = eval_json(EVENT, "--level", LEVEL, "--seeds", "2,1", "--workers", "2", "--truth-out", str(tmp_path))
    assert without_wall(pooled["runs"]) == without_wall(serial["runs"])
    keep = ("runs", "crashed", "mean_points_fraction", "min_points_fraction", "full_rate", "mean_sim_time_s")
    assert {k: pooled["summary"][k] for k in keep} == {k: serial["summary"][k] for k in keep}

    assert sorted(p.name for p in tmp_path.iterdir()) == ["1.json", "2.json"]
    for run in pooled["runs"]:
        truth = json.loads((tmp_path / f"{run['seed']}.json").read_text())
        assert {"objects", "camera", "gripper_path_m"} <= set(truth)
        assert {obj["id"] for obj in truth["objects"]} >= {"block_0", "block_1", "block_2"}
        score = judge(EVENT, int(LEVEL), truth, sim_time_s=run["sim_time_s"])
        assert score.points == run["points"]
        assert [r.to_dict() for r in score.breakdown] == run["breakdown"]


@pytest.mark.slow
def test_truth_out_gripper_path_sampled_at_10_hz(tmp_path):
    from armlab.devices.sim import SimWorkcell

    if not hasattr(SimWorkcell, "start_path_recording"):
        pytest.skip("SimWorkcell has no gripper path recorder yet (start_path_recording / gripper_path)")
    result = eval_json(EVENT, "--level", LEVEL, "--seeds", "3", "--truth-out", str(tmp_path))
    run = result["runs"][0]
    path = json.loads((tmp_path / "3.json").read_text())["gripper_path_m"]
    assert path is not None and all(len(point) == 3 for point in path)
    assert len(path) >= 10.0 * run["sim_time_s"]
    moved_m = max(abs(a - b) for p, q in zip(path, path[1:]) for a, b in zip(p, q))
    assert moved_m > 0.0  # the arm moved during the job


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture(scope="module")
def ray_head():
    """A real local Ray head (2 CPUs, no dashboard) started for this test and stopped after it; its address."""
    pytest.importorskip("ray", reason="Ray is not installed: pip install 'armlab[cluster]' (the test extra has it)")
    ray_bin = Path(sys.executable).with_name("ray")
    port = _free_port()
    temp_dir = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must fit 107 bytes
    log = open(Path(temp_dir) / "head.log", "w+")
    head = subprocess.Popen(
        [str(ray_bin), "start", "--head", "--block", "--node-ip-address=127.0.0.1", f"--port={port}",
         "--num-cpus=2", "--include-dashboard=false", "--disable-usage-stats",
         "--object-store-memory=100000000", f"--temp-dir={temp_dir}"],
        stdout=log, stderr=subprocess.STDOUT, start_new_session=True, env={**os.environ, "MUJOCO_GL": "egl"})
    try:
        deadline = time.monotonic() + 120
        while "Ray runtime started" not in Path(log.name).read_text():
            assert head.poll() is None, Path(log.name).read_text()[-2000:]
            assert time.monotonic() < deadline, "Ray head did not start within 120 s"
            time.sleep(0.2)
        yield f"127.0.0.1:{port}"
    finally:
        head.send_signal(signal.SIGTERM)  # `ray start --block` stops the processes it started
        try:
            head.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(head.pid, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                os.killpg(head.pid, 0)  # anything left of the head's own process group?
            except ProcessLookupError:
                break
            time.sleep(0.2)
        else:
            os.killpg(head.pid, signal.SIGKILL)
        log.close()


@pytest.mark.slow
def test_ray_equals_serial(serial, ray_head):
    over_ray = eval_json(EVENT, "--level", LEVEL, "--seeds", "1-2", "--ray", ray_head)
    assert without_wall(over_ray["runs"]) == without_wall(serial["runs"])


# ---------------------------------------------------------------------------------------------------
# Seeds and bad input


def test_parse_seeds_lists_and_ranges():
    assert parse_seeds("1,2,3") == [1, 2, 3]
    assert parse_seeds("1-20") == list(range(1, 21))
    assert parse_seeds(" 9 , 0-2 ") == [0, 1, 2, 9]
    assert parse_seeds("0-9999") == list(range(10000))


@pytest.mark.parametrize("seeds, message", [
    ("", "empty seed list"),
    ("  ", "empty seed list"),
    ("1,,2", "an empty item"),
    ("1,", "an empty item"),
    ("3-1", "runs backwards"),
    ("a", "'a' is not a seed"),
    ("1.5", "'1.5' is not a seed"),
    ("-1", "'-1' is not a seed"),
    ("1--3", "'1--3' is not a seed"),
    ("0-10000", "more than 10000 seeds"),
    ("0-99999999999", "seeds go up to"),
    ("1-5,3", "seed 3 given more than once"),
])
def test_bad_seed_lists_are_refused_before_anything_runs(seeds, message, capsys, tmp_path):
    out = tmp_path / "truth"
    assert main(["eval", EVENT, "--level", LEVEL, "--seeds", seeds, "--truth-out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert message in captured.err and captured.err.startswith("armlab eval: ")
    assert captured.err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("args, message", [
    (["no_such_job", "--level", "1"], "unknown job 'no_such_job'"),
    ([EVENT, "--level", "4"], "has levels 1, 2, 3, not 4"),
    ([EVENT, "--level", "0"], "has levels 1, 2, 3, not 0"),
    ([EVENT], "give --level"),
    ([EVENT, "--level", "one"], "--level must be an integer"),
    ([EVENT, "--level", "1", "--workers", "0"], "workers must be an integer in 1..256"),
    ([EVENT, "--level", "1", "--workers", "two"], "--workers must be an integer"),
])
def test_bad_requests_are_refused(args, message, capsys):
    assert main(["eval", *args, "--seeds", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and message in captured.err and captured.err.count("\n") == 1


def test_bad_seed_list_in_a_real_process():
    result = eval_cli(EVENT, "--level", LEVEL, "--seeds", "1,,2", timeout_s=120)
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.strip().splitlines() == [
        "armlab eval: bad seed list '1,,2': an empty item is not a seed (N) or a range (N-M) of non-negative integers"]


def test_a_run_that_raises_is_recorded_as_crashed():
    run = run_one(EVENT, 7, 5)  # run_episode refuses level 7: that seed's result, not the evaluation's end
    assert run["crashed"] and run["points"] == 0 and run["max_points"] is None and run["seed"] == 5
    assert "crashed: InvalidInput" in run["failures"][0] and "levels" in run["failures"][0]
