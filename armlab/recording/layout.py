"""The Foxglove layout shipped with the station (config/foxglove/armlab_layout.json), built with foxglove-sdk's layout
classes (foxglove.layouts) from the channels' topics and the live server's URDF asset, so it cannot name a topic the
station does not publish:

- a 3-D panel: the arm's URDF (package://armlab/urdf/arm.urdf, moved by /tf's link frames), the board grid, the
  detections' cubes, the plan, the camera's frustum and image;
- the colour image with its calibration, the depth image (turbo colour map);
- a plot of the measured and commanded joints (one series each per joint of the arm);
- the event log (/events: the station's events, its state changes, its jobs) and the gripper's raw messages.

    python -m armlab.recording.layout [--arm rx200] [--output config/foxglove/armlab_layout.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import foxglove.layouts as fl

from armlab.config import config_dir
from armlab.kinematics import load_arm
from armlab.recording.channels import TOPICS
from armlab.recording.live import URDF_URI

LAYOUT_FILE = config_dir() / "foxglove" / "armlab_layout.json"
COLOURS = ("#4e98e2", "#f5774d", "#61cbff", "#b078f5", "#5cd6a9", "#f7df71", "#e05ffa")


def _joint_series(joint_names: list[str]) -> list:
    series = []
    for index, name in enumerate(joint_names):
        colour = COLOURS[index % len(COLOURS)]
        series.append(fl.PlotSeries(value=f'/joint_states.joints[:]{{name=="{name}"}}.position', label=f"{name} (rad)",
                                    color=colour, timestamp_method="receiveTime", enabled=True))
        series.append(fl.PlotSeries(value=f'/joint_commands.joints[:]{{name=="{name}"}}.position', label=f"{name} commanded",
                                    color=colour, line_style="dashed", timestamp_method="receiveTime", enabled=True))
    return series


def build_layout(joint_names: list[str]) -> dict:
    """The layout as JSON-ready data."""
    three_d = fl.ThreeDeePanel(title="Workcell", config=fl.ThreeDeeConfig(
        follow_tf="world",
        camera_state=fl.ThreeDeeCameraState(distance=1.2, phi=55.0, theta_offset=-60.0, target=(0.0, 0.15, 0.05), perspective=True),
        layers={
            "armlab-urdf": fl.BaseRendererUrdfLayerSettings(layer_id="foxglove.Urdf", instance_id="armlab-urdf", label="ArmLab arm",
                                                            visible=True, source_type="url", url=URDF_URI, control_mode="transforms",
                                                            display_mode="visual", order=1),
            "armlab-grid": fl.BaseRendererGridLayerSettings(layer_id="foxglove.Grid", instance_id="armlab-grid", label="Board",
                                                            visible=True, frame_id="world", size=1.0, divisions=20, order=2),
        },
        topics={
            "/detections/scene": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/plan": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/camera/color/compressed": fl.BaseRendererImageTopicSettings(visible=False, camera_info_topic="/camera/calibration"),
        },
    ))
    colour = fl.ImagePanel(title="Colour", config=fl.ImageConfig(image_mode=fl.ImageModeConfig(
        image_topic="/camera/color/compressed", calibration_topic="/camera/calibration")))
    depth = fl.ImagePanel(title="Depth (mm)", config=fl.ImageConfig(image_mode=fl.ImageModeConfig(
        image_topic="/camera/depth", calibration_topic="/camera/calibration", color_mode="colormap", color_map="turbo")))
    joints = fl.PlotPanel(title="Joints: measured and commanded (rad)", config=fl.PlotConfig(
        paths=_joint_series(joint_names), show_legend=True, legend_display="top", following_view_width=20.0))
    events = fl.LogPanel(title="Events, state and jobs", config=fl.LogConfig(topic_to_render="/events", min_log_level=1, show_name=True))
    gripper = fl.RawMessagesPanel(title="Gripper", config=fl.RawMessagesConfig(topic_path="/gripper"))
    content = fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=3, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(proportion=2, content=three_d),
            fl.SplitItem(proportion=1, content=joints)])),
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(content=colour), fl.SplitItem(content=depth),
            fl.SplitItem(content=fl.SplitContainer(direction="row", items=[
                fl.SplitItem(proportion=2, content=events), fl.SplitItem(proportion=1, content=gripper)]))])),
    ])
    data = json.loads(fl.Layout(content=content).to_json())
    missing = sorted(topic for topic in _topics_named(data) if topic not in TOPICS)
    if missing:
        raise ValueError(f"the layout names topics the station does not publish: {missing}")
    return data


def _topics_named(value) -> set[str]:
    """Every topic a layout names (a string starting with "/" up to its first "." or "{")."""
    if isinstance(value, dict):
        return set().union(*(_topics_named(item) for item in value.values())) | set().union(*(_topics_named(key) for key in value))
    if isinstance(value, list):
        return set().union(*(_topics_named(item) for item in value)) if value else set()
    if isinstance(value, str) and value.startswith("/"):
        return {value.split("{")[0].split(".")[0]}
    return set()


def layout_text(joint_names: list[str]) -> str:
    return json.dumps(build_layout(joint_names), indent=1) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description="write the station's Foxglove layout")
    parser.add_argument("--arm", default="rx200", help="the arm whose joints the plot shows (default rx200, the default workcell's)")
    parser.add_argument("--output", default=str(LAYOUT_FILE))
    args = parser.parse_args()
    output = Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(layout_text(list(load_arm(args.arm).joint_names)))
    print(f"wrote {output}")


if __name__ == "__main__":
    main()
