"""What the station's arm and gripper are, from configuration: the gripper type of its workcell and the
arm's joints as the browser receives them (websocket hello `arm`). One place for both, so nothing else
guesses from the number of joints or the arm's name."""

from __future__ import annotations

from armlab.motion.end_effector import EndEffector, end_effector
from armlab.motion.pose_path import holds_full_pose
from armlab.workcell import DEFAULT_WORKCELL, load_workcell

NO_ARM_REASON = "this station has no arm (perception only: calibrate, detections, click → world)"


def station_workcell_name(station) -> str:
    """The station's workcell (config/workcells/<name>.yaml): its config's, else perception's, else the default."""
    return (getattr(getattr(station, "config", None), "workcell", None)
            or getattr(getattr(station, "perception_config", None), "workcell", None) or DEFAULT_WORKCELL)


def station_gripper_type(station) -> str:
    """'fingers' or 'suction': the station's own `gripper_type` when it has one, else its workcell's
    (config/workcells/<workcell>.yaml gripper.type), else 'fingers' (a station without a workcell)."""
    if getattr(station, "model", True) is None:
        return "none"
    explicit = getattr(station, "gripper_type", None)
    if isinstance(explicit, str):
        return explicit
    workcell_name = getattr(getattr(station, "config", None), "workcell", None)
    if not workcell_name:
        return "fingers"

    return load_workcell(workcell_name).gripper.type


def station_end_effector(station) -> EndEffector:
    """The station's end effector (armlab.motion.end_effector), from station_gripper_type; InvalidInput for a
    station with no arm."""
    return end_effector(station_gripper_type(station))


def arm_info(station) -> dict:
    """The arm as the page builds its jog sliders, readouts, plot and teach table from it: name, vendor, joint
    names, [lower, upper] limits (rad), velocity limits (rad/s), home (rad), gripper type, and whether
    Cartesian moves keep the tool's whole orientation (six joints or more) or its pitch and yaw."""
    model = station.model
    if model is None:  # a station with no arm (armlab serve --arm none)
        return {"name": "none", "vendor": None, "joint_names": [], "joint_limits_rad": [], "velocity_limits_rad_s": [], "home_rad": [],
                "gripper_type": "none", "full_pose": False, "has_arm": False, "reason": NO_ARM_REASON}
    return {
        "name": model.name,
        "vendor": getattr(model.config, "vendor", None),
        "joint_names": list(model.joint_names),
        "joint_limits_rad": [[float(lo), float(hi)] for lo, hi in zip(model.lower_rad, model.upper_rad)],
        "velocity_limits_rad_s": [float(v) for v in model.velocity_limit_rad_s],
        "home_rad": [float(v) for v in model.home_rad],
        "gripper_type": station_gripper_type(station),
        "full_pose": holds_full_pose(model),
    }
