"""The Foxglove layout shipped with the station (config/foxglove/armlab_layout.json) is the one
armlab.recording.layout builds (regenerate it with `python -m armlab.recording.layout`): its 3-D panel loads the live
server's URDF asset moved by the transforms, it plots every joint of the default arm measured and commanded, shows
the colour and depth images with their calibration and the event log, and names only topics the station publishes."""

from __future__ import annotations

import json

from armlab.kinematics import load_arm
from armlab.recording import TOPICS
from armlab.recording.layout import LAYOUT_FILE, _topics_named, layout_text
from armlab.recording.live import URDF_URI


def _panels(node) -> list[dict]:
    if node.get("type") == "panel":
        return [node]
    return [panel for item in node.get("items", []) for panel in _panels(item["content"])]


def test_the_shipped_layout_is_the_built_one_and_names_only_published_topics():
    joint_names = list(load_arm("rx200").joint_names)
    shipped = LAYOUT_FILE.read_text()
    assert shipped == layout_text(joint_names), "stale: run python -m armlab.recording.layout"
    layout = json.loads(shipped)
    assert _topics_named(layout) <= set(TOPICS)
    panels = {panel["panelType"]: panel for panel in _panels(layout["content"])}
    assert {"ThreeDee", "Image", "Plot", "Log", "RawMessages"} <= set(panels), sorted(panels)
    urdf = panels["ThreeDee"]["config"]["layers"]["armlab-urdf"]
    assert urdf["url"] == URDF_URI and urdf["controlMode"] == "transforms"
    plotted = [series["value"] for series in panels["Plot"]["config"]["paths"]]
    for name in joint_names:
        assert f'/joint_states.joints[:]{{name=="{name}"}}.position' in plotted
        assert f'/joint_commands.joints[:]{{name=="{name}"}}.position' in plotted
    images = [panel["config"]["imageMode"] for panel in _panels(layout["content"]) if panel["panelType"] == "Image"]
    assert {image["imageTopic"] for image in images} == {"/camera/color/compressed", "/camera/depth"}
    assert all(image["calibrationTopic"] == "/camera/calibration" for image in images)
    assert panels["Log"]["config"]["topicToRender"] == "/events"
