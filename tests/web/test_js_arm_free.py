"""The page knows no arm of its own: no joint name of any arm in config/arms/ appears in web/js (the sliders,
readouts, plot legend and teach columns come from the server's hello / status), so a new arm in config
needs no JS change."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]


def test_no_joint_name_of_a_configured_arm_is_written_in_web_js():
    names = {name for path in (REPO / "config/arms").glob("*.yaml") for name in yaml.safe_load(path.read_text())["joint_names"]}
    assert {"waist", "wrist_rotate", "shoulder_pan", "wrist_3"} <= names  # the premise: both arms' files were read
    found = []
    for path in sorted((REPO / "web/js").glob("*.js")):
        if path.name == "wire_types.js":  # generated from the server's models (field descriptions)
            continue
        text = path.read_text()
        found += [f"{path.name}: {name}" for name in names if re.search(rf"[\"'`]{re.escape(name)}[\"'`]|\b{re.escape(name)}\s*:", text)]
    assert not found, f"arm joint names written in the page's code: {found}"
