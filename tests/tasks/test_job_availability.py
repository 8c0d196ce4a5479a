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


@pytest.mark.parametrize("params, problem", [
    ({"x_m": True}, "parameter 'x_m' of job 'stack_here'"),
    ({"x_m": None}, "parameter 'x_m' of job 'stack_here'"),
    ({"x_m": "0.1"}, "parameter 'x_m' of job 'stack_here'"),
    ({"y_m": 1.5}, "parameter 'y_m' of job 'stack_here'"),
    ({"x_m": float("nan")}, "parameter 'x_m' of job 'stack_here'"),
    ({"color": "pink"}, "parameter 'color' of job 'stack_here'"),
    ({"size": "huge"}, "parameter 'size' of job 'stack_here'"),
    ({"z_m": 0.1}, "has no parameter 'z_m'; parameters: x_m, y_m, color, size"),
    ([0.1], "params must be an object"),
])
def test_a_jobs_parameters_are_checked_by_its_model(params, problem):
    from armlab.errors import InvalidInput
    from armlab.tasks.registry import checked_request

    with pytest.raises(InvalidInput, match=problem.replace("(", r"\(").replace(")", r"\)")):
        checked_request("stack_here", None, params)


def test_the_parameters_given_are_passed_as_numbers_and_a_job_without_parameters_takes_none():
    from armlab.errors import InvalidInput
    from armlab.tasks.registry import checked_request

    _, level, params = checked_request("stack_here", None, {"x_m": 0, "y_m": -0.12, "color": "red"})
    assert level is None and params == {"x_m": 0.0, "y_m": -0.12, "color": "red"} and isinstance(params["x_m"], float)
    assert checked_request("pick_sort", 2, None)[1:] == (2, {})
    with pytest.raises(InvalidInput, match="job 'pick_sort' has no parameter 'color'"):
        checked_request("pick_sort", 2, {"color": "red"})
