"""`armlab eval` refuses, up front, a job the workcell cannot run: to_the_sky needs fingers (side grasps)
and the UR3 workcell has a suction cup; pick_stack's columns need board tags inside the judge's fixed
gripper box and line_up's layouts the RX200's reach band, which the UR3 board does not give. The error
names the job, the workcell and what is missing; no run starts. The jobs that do run on the UR3 pass the
check (nothing run here: the check alone)."""

from __future__ import annotations

import pytest
import yaml

from armlab.cli import main
from armlab.tasks.evaluate import check_request
from armlab.workcell.loading import _REPO_CONFIG_DIR

UR3_FILE = yaml.safe_load(open(f"{_REPO_CONFIG_DIR}/workcells/ur3_suction.yaml"))


@pytest.mark.parametrize("job, missing", [
    ("to_the_sky", ["fingers", UR3_FILE["gripper"]["type"]]),
    ("pick_stack", ["gripper box", "(-450, -225) mm"]),  # the UR3 board's tag 1, read from the file below
    ("line_up", ["140-350 mm", "180-450 mm"]),
])
def test_eval_refuses_a_job_the_ur3_cannot_run(job, missing, capsys):
    assert [round(v * 1000) for v in UR3_FILE["board_tags"]["centres_m"][1]] == [-450, -225]
    assert [round(v * 1000) for v in UR3_FILE["scene"]["reach_m"]] == [180, 450]
    assert main(["eval", job, "--level", "1", "--seeds", "0", "--workcell", "ur3_suction"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1  # one line, no run started (no "seed 0:")
    message = captured.err
    assert f"job '{job}'" in message and "workcell 'ur3_suction'" in message, message
    for fragment in missing:
        assert fragment in message, message


@pytest.mark.parametrize("job", ["pick_sort", "stack_high", "sort_stack", "clear_table", "sort_by_tag"])
def test_the_jobs_that_run_on_the_ur3_pass_the_check(job):
    assert check_request(job, 1, "ur3_suction") == 1


@pytest.mark.parametrize("job", ["to_the_sky", "pick_stack", "line_up"])
def test_the_rx200_runs_them(job):
    assert check_request(job, 1, None) == 1 and check_request(job, 1, "rx200_armlab") == 1
