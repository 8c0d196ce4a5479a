"""`armlab fk` and `armlab ik`: JSON on stdout, status 2 with {"error": ...} for bad input."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from armlab.cli import main


def run(capsys, *argv):
    status = main(list(argv))
    return status, json.loads(capsys.readouterr().out)


def test_fk_prints_world_pose(capsys, rx200):
    status, out = run(capsys, "fk", "rx200", "0.3", "-0.2", "0.4", "1.0", "0.5")
    assert status == 0
    expected = rx200.fk([0.3, -0.2, 0.4, 1.0, 0.5])
    assert np.allclose(out["position_m"], expected[:3, 3])
    assert np.allclose(out["matrix"], expected)
    roll, pitch, yaw = out["rpy_rad"]
    assert pitch == pytest.approx(1.2)  # q2 + q3 + q4: the approach axis below the horizontal
    assert roll == pytest.approx(0.5)  # wrist_rotate
    assert yaw == pytest.approx(0.3 + math.pi / 2)  # waist, plus the base's quarter turn in the world


def test_ik_round_trips_through_fk(capsys, rx200):
    status, out = run(capsys, "ik", "rx200", "-0.1", "0.3", "0.02", "--yaw", "0.5")
    assert status == 0
    assert out["pitch_rad"] == pytest.approx(math.pi / 2)
    assert np.allclose(rx200.fk(out["q_rad"])[:3, 3], [-0.1, 0.3, 0.02], atol=1e-9)
    status, out = run(capsys, "ik", "rx200", "0", "0.3", "0.05", "--pitch", "1.0", "--seed", "0", "0", "0", "0", "1.5")
    assert status == 0 and out["pitch_rad"] == 1.0 and out["q_rad"][4] == pytest.approx(1.5)


def test_ik_far_target_reports_the_pitch_found(capsys, rx200):
    status, out = run(capsys, "ik", "rx200", "0", "0.45", "0.02")
    assert status == 0 and out["pitch_rad"] < math.pi / 2
    assert rx200.pitch_of(out["q_rad"]) == pytest.approx(out["pitch_rad"])


@pytest.mark.parametrize(
    "argv, message",
    [
        (["ik", "rx200", "0", "0.8", "0.1"], "out of reach"),
        (["ik", "rx200", "0", "0.2", "-0.05"], "below the table"),
        (["ik", "rx200", "0", "nan", "0.1"], "finite"),
        (["ik", "rx200", "0", "0.2"], "3 numbers"),
        (["ik", "rx200", "0", "0.2", "0.1", "--pitch", "inf"], "finite"),
        (["ik", "rx200", "0", "0.2", "0.1", "--seed", "0", "0"], "--seed"),
        (["fk", "rx200", "0", "0", "0"], "5 joints"),
        (["fk", "rx200", "0", "x", "0", "0", "0"], "not a number"),
        (["fk", "rx200", "0", "3.0", "0", "0", "0"], "outside the joint limits"),
        (["fk", "no_such_arm", "0"], "no config"),
    ],
)
def test_bad_input_and_unreachable_exit_2_with_json_error(capsys, argv, message):
    status, out = run(capsys, *argv)
    assert status == 2
    assert message in out["error"]


def test_console_entry_point_end_to_end():
    result = subprocess.run(
        [sys.executable, "-m", "armlab.cli", "ik", "ur3", "0.3", "0.1", "0.05"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    q = json.loads(result.stdout)["q_rad"]
    assert len(q) == 6
    result = subprocess.run(
        [sys.executable, "-m", "armlab.cli", "ik", "rx200", "1", "1", "1"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 2 and "unreachable" in json.loads(result.stdout)["error"]
