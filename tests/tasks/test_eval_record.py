"""`armlab eval --record DIR` (issue 23 item 2): each run is recorded to its own complete MCAP file (calibration and
job: joints, camera, transforms, events), and recording does not change the run's result (fast-mode simulation)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from armlab.recording import iter_messages, summarize

EVENT, LEVEL = "pick_sort", "1"  # the fastest job


def eval_json(*args: str) -> dict:
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    result = subprocess.run([sys.executable, "-m", "armlab.cli", "eval", EVENT, "--level", LEVEL, *args, "--json"],
                            capture_output=True, text=True, timeout=600, env=env)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.mark.slow
def test_each_run_is_recorded_and_the_results_are_the_same(tmp_path):
    recorded = eval_json("--seeds", "1-2", "--record", str(tmp_path / "runs"))
    plain = eval_json("--seeds", "1-2")
    strip = [{k: v for k, v in run.items() if k not in ("wall_time_s", "cpu_time_s")} for run in plain["runs"]]
    assert [{k: v for k, v in run.items() if k not in ("wall_time_s", "cpu_time_s")} for run in recorded["runs"]] == strip
    files = sorted((tmp_path / "runs").glob("*.mcap"))
    assert [path.name.split("-")[2] for path in files] == ["seed1", "seed2"]
    for path in files:
        summary = summarize(path)
        assert summary.complete and not summary.truncated
        for topic in ("/joint_states", "/joint_commands", "/tf", "/camera/color/compressed", "/camera/calibration", "/events"):
            assert summary.topics[topic]["count"] > 0, (path.name, topic)
        logs = [message.message for _, _, _, message in iter_messages(path, {"/events"})]
        assert "job 'calibrate' started" in logs and any(text.startswith("job 'pick_sort' started") for text in logs), logs
