"""The real ROB 550 development frames (../shared/data/rob550_dev from the repository root, not part of
the repository: see its README) for tests: where they are, that station's camera, and the perception
config with the course's board (tagStandard41h12)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from armlab.config import config_dir
from armlab.devices.camera import Intrinsics
from armlab.vision import load_perception_config
from armlab.workcell import load_workcell

DEV = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "rob550_dev"
SKIP_REASON = f"the real ROB 550 development frames are not on this machine (looked in {DEV})"
needs_dev_frames = pytest.mark.skipif(not DEV.is_dir(), reason=SKIP_REASON)


def dev_images() -> list[Path]:
    """Every colour frame of the development set."""
    return sorted(DEV.glob("image_*.png"))


def f21_intrinsics() -> Intrinsics:
    """The course station's camera (calibration_f21.json: K and distortion from its camera_info)."""
    data = json.loads((DEV / "calibration_f21.json").read_text())
    K = data["K_from_camera_info"]
    return Intrinsics(1280, 720, K[0][0], K[1][1], K[0][2], K[1][2], tuple(data["D_from_camera_info_plumb_bob"]))


def rob550_config(tmp_dir: Path):
    """The shipped perception config on the default workcell with the course's board tags (rob550)."""
    data = yaml.safe_load((config_dir() / "workcells" / "rx200_armlab.yaml").read_text())
    data["board_tags"] = "rob550"
    path = Path(tmp_dir) / "workcell_rob550.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_perception_config(workcell=load_workcell(str(path)))
