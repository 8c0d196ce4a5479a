"""The course's board (config/boards/rob550.yaml: AprilTag tagStandard41h12, read by the AprilTag
library) rendered by the simulation: the station calibrates on it as well as on the 36h11 board and
finds the blocks, against the simulator's ground truth."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from armlab.config import config_dir
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.scene import generate_scene
from armlab.vision import calibrate_extrinsics, detect_blocks, detect_tags, load_perception_config
from armlab.vision.evaluate import click_grid_errors, score_blocks
from armlab.workcell import load_workcell

SEEDS = (3, 11)


def _workcell_file(tmp_dir, board: str | None) -> str:
    """The default workcell, with board_tags replaced by config/boards/<board>.yaml when given."""
    data = yaml.safe_load((config_dir() / "workcells" / "rx200_armlab.yaml").read_text())
    if board is not None:
        data["board_tags"] = board
    path = tmp_dir / f"workcell_{board or 'default'}.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


def _run(workcell_path: str, seed: int):
    """Calibrate from a frame of a pick_sort L2 scene with the rig bumped by `seed`; detect its blocks."""
    cfg = load_perception_config(workcell=load_workcell(workcell_path))
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=seed, camera_pose_error=True, workcell=workcell_path))
    cell.start()
    try:
        cell.set_scene(generate_scene("pick_sort", level=2, seed=seed))
        cell.step(0.5)
        frame, truth = cell.render(), cell.truth()
    finally:
        cell.close()
    cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg, depth_mm=frame.depth_mm)
    camera_error_m = float(np.linalg.norm(cal.camera_position_m - np.asarray(truth["camera"]["T_world_camera"])[:3, 3]))
    score = score_blocks(detect_blocks(frame.color_bgr, frame.depth_mm, cal, cfg), truth, frame.depth_mm)
    return cfg, frame, cal, camera_error_m, click_grid_errors(cal, truth), score


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("boards")
    boards = {"36h11": _workcell_file(tmp, None), "41h12": _workcell_file(tmp, "rob550")}
    return {(name, seed): _run(path, seed) for name, path in boards.items() for seed in SEEDS}


def test_the_rob550_board_is_41h12_and_selectable():
    cell = load_workcell(_workcell_file(__import__("pathlib").Path(__import__("tempfile").mkdtemp()), "rob550"))
    assert cell.board_tags.family == "tagStandard41h12" and cell.board_tags.detector == "tagStandard41h12"
    assert sorted(cell.board_tags.centres_m) == [1, 2, 3, 4]


@pytest.mark.parametrize("seed", SEEDS)
def test_the_sim_renders_41h12_tags_that_only_the_41h12_decoder_reads(runs, seed):
    cfg, frame, *_ = runs[("41h12", seed)]
    tags = detect_tags(frame.color_bgr, cfg)
    tags = [t for t in tags if t.id != 10]  # the gripper's tag (workcell gripper.marker, the board's family) is in view too
    assert [t.id for t in tags] == [1, 2, 3, 4] and all(t.hamming == 0 for t in tags)
    assert detect_tags(frame.color_bgr, dictionary="DICT_APRILTAG_36h11") == []


@pytest.mark.parametrize("seed", SEEDS)
def test_41h12_calibrates_as_well_as_36h11_and_blocks_are_found(runs, seed):
    _, _, cal41, cam41, click41, score41 = runs[("41h12", seed)]
    _, _, cal36, cam36, click36, _ = runs[("36h11", seed)]
    assert cal41.tag_ids == (1, 2, 3, 4)
    assert cam41 < 0.002 and cam41 < cam36 + 0.001, (cam41, cam36)  # camera position, m
    assert click41.mean() < 0.0005 and click41.max() < 0.0015, (click41.mean(), click41.max())
    assert click41.mean() < click36.mean() + 0.0003
    assert cal41.reprojection_error_px < 0.5
    assert score41.false_negatives == 0 and score41.false_positives == 0 and score41.true_positives >= 3
    assert score41.color_correct == score41.size_correct == score41.true_positives
    assert max(score41.position_errors_m) < 0.003


def test_an_unknown_board_name_is_a_clear_error(tmp_path):
    from armlab.errors import ConfigError

    with pytest.raises(ConfigError, match="board_tags.*'no_such_board'.*rob550"):
        load_workcell(_workcell_file(tmp_path, "no_such_board"))
