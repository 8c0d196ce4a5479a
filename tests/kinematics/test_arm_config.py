"""Arm files: both shipped arms load with the promised attributes; broken files fail at load with a
ConfigError naming the file and the field."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from armlab.errors import ConfigError
from armlab.kinematics import load_arm

ARMS_DIR = Path(__file__).resolve().parents[2] / "config" / "arms"


def test_rx200_attributes(rx200):
    assert rx200.name == "rx200" and rx200.dof == 5
    assert rx200.joint_names == ("waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate")
    assert np.allclose(np.degrees(rx200.lower_rad), [-180, -108, -108, -100, -180])
    assert np.allclose(np.degrees(rx200.upper_rad), [180, 113, 93, 123, 180])
    assert np.allclose(rx200.sleep_rad, [0, -1.80, 1.55, 0.8, 0])
    assert np.allclose(rx200.home_rad, 0.0)
    assert rx200.velocity_limit_rad_s[1] == pytest.approx(1.0) and rx200.accel_limit_rad_s2.shape == (5,)
    assert np.allclose(rx200.T_world_base @ [1, 0, 0, 1], [0, 1, 0, 1])  # base x = world y
    assert rx200.config.gripper.finger_offset_max_m == pytest.approx(0.037)
    assert list(rx200.config.urdf_origins) == [*rx200.joint_names, "gripper_point"]
    with pytest.raises(ValueError):
        rx200.lower_rad[0] = 0.0  # read-only: nobody changes the limits behind the model's back


def test_ur3_attributes(ur3):
    assert ur3.dof == 6 and ur3.config.family == "generic"
    assert np.allclose(np.degrees(ur3.upper_rad), [360, 360, 180, 360, 360, 360])
    assert np.allclose(np.degrees(ur3.velocity_limit_rad_s), [180, 180, 180, 360, 360, 360])
    rows = np.asarray(ur3.config.dh.rows)
    assert np.allclose(rows[:, 1], [0.1519, 0, 0, 0.11235, 0.08535, 0.0819])
    assert np.allclose(rows[:, 2], [0, -0.24365, -0.21325, 0, 0, 0])
    assert np.allclose(rows[:, 3], [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0])


def write_variant(tmp_path, change):
    data = yaml.safe_load((ARMS_DIR / "rx200.yaml").read_text())
    change(data)
    path = tmp_path / "broken_arm.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def set_in(path_keys, value):
    def change(data):
        node = data
        for key in path_keys[:-1]:
            node = node[key]
        node[path_keys[-1]] = value

    return change


BROKEN = {
    "nan limit": (set_in(["limits", "lower_deg"], [-180, float("nan"), -108, -100, -180]), "lower_deg"),
    "inverted limits": (set_in(["limits", "upper_deg"], [180, -110, 93, 123, 180]), "limits.lower_deg[1]"),
    "zero-width limits": (set_in(["limits", "upper_deg"], [180, -108, 93, 123, 180]), "limits.lower_deg[1]"),
    "zero velocity": (set_in(["limits", "velocity_rad_s"], [3.1, 0.0, 3.1, 3.1, 3.1]), "velocity_rad_s[1]"),
    "short limits": (set_in(["limits", "acceleration_rad_s2"], [5.0, 5.0]), "limits.acceleration_rad_s2"),
    "dh row too short": (set_in(["dh", "rows", 2], [0.0, 0.2, 0.0, 1]), "dh.rows[2]"),
    "dh missing row": (lambda d: d["dh"]["rows"].pop(), "dh.rows"),
    "screw axes count": (lambda d: d["pox"]["screw_axes"].pop(), "pox.screw_axes"),
    "screw axis not unit": (set_in(["pox", "screw_axes", 1], [0, 2, 0, -0.1, 0, 0]), "pox.screw_axes[1]"),
    "M not rigid": (set_in(["pox", "M", 3], [0, 0, 1, 1]), "pox.M"),
    "base not 4x4": (set_in(["T_world_base"], [[0, -1, 0], [1, 0, 0], [0, 0, 1]]), "T_world_base"),
    "sleep outside limits": (set_in(["poses", "sleep_rad"], [0, -2.5, 1.55, 0.8, 0]), "poses.sleep_rad"),
    "unknown field": (set_in(["colour"], "red"), "colour"),
    "gripper inverted": (set_in(["gripper", "finger_offset_min_m"], 0.05), "gripper.finger_offset_min_m"),
    # the old first-guess DH rows (row 4 twisted the wrong way, 0.164075 to the gripper point)
    "dh disagrees with pox": (set_in(["dh", "rows", 3], [0.0, 0.0, 0.0, 1.5707963267948966, 1]), "dh and pox disagree"),
    "urdf gripper point": (set_in(["urdf_origins", "gripper_point"], [0.099075, 0.0, 0.0]), "urdf_origins.gripper_point"),
    "urdf origin off axis": (set_in(["urdf_origins", "elbow"], [0.05, 0.0, 0.21]), "urdf_origins"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_arm_file_names_file_and_field(tmp_path, case):
    change, field = BROKEN[case]
    path = write_variant(tmp_path, change)
    with pytest.raises(ConfigError) as error:
        load_arm(path)
    message = str(error.value)
    assert str(path) in message and field in message, message


def test_unknown_arm_lists_the_available_ones():
    with pytest.raises(ConfigError, match="rx200"):
        load_arm("no_such_arm")


def test_pox_only_arm_works_with_numerical_ik(tmp_path):
    # An arm file with only the PoX description (no DH): FK and the numerical IK still work.
    def change(data):
        del data["dh"]
        data["family"] = "generic"
        data["name"] = "rx200_pox_only"

    arm = load_arm(write_variant(tmp_path, change))
    q = np.array([0.2, 0.1, 0.3, 0.6, -0.4])
    assert np.allclose(arm.fk(q), load_arm("rx200").fk(q), atol=1e-12)
    solution = arm.ik_pose(arm.fk(q))
    assert np.allclose(arm.fk(solution), arm.fk(q), atol=1e-4)
