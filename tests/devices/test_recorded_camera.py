"""RecordedCamera on real files: the ROB 550 development frames, small pairs written here, and a tiny ROS 2
bag written with rosbags itself. Playback (held pair, loop, bag timing), intrinsics sources, and every bad
input refused naming the file."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from armlab.devices.factory import make_camera
from armlab.devices.recorded import RecordedCamera, RecordedCameraConfig, RecordingError
from armlab.errors import ConfigError
from recorded_helpers import DIST_TEST, K_TEST, pair_images, write_bag, write_intrinsics, write_pairs

DEV = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "rob550_dev"
needs_dev_frames = pytest.mark.skipif(not DEV.is_dir(), reason=f"the real ROB 550 development frames are not on this machine ({DEV})")


def _camera(source, **options) -> RecordedCamera:
    return RecordedCamera(RecordedCameraConfig(source=str(source), **options))


def _connected(source, **options) -> RecordedCamera:
    camera = _camera(source, **options)
    camera.connect()
    return camera


def _read_until(camera, predicate, timeout_s=5.0):
    """Frames until predicate(frame) holds (the condition the test waits for), else fail."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        frame = camera.read()
        if predicate(frame):
            return frame
    raise AssertionError(f"no frame satisfied the condition within {timeout_s} s")


# -- the real development frames ---------------------------------------------------------------------


@needs_dev_frames
def test_a_held_real_pair_is_resent_as_a_live_camera_with_the_folders_camera_info_intrinsics():
    camera = _connected(DEV, frame="blocks", fps=30.0)
    try:
        first, second = camera.read(), camera.read()
        intrinsics = camera.intrinsics
    finally:
        camera.close()
    expected_color = cv2.imread(str(DEV / "image_blocks.png"), cv2.IMREAD_COLOR)
    expected_depth = cv2.imread(str(DEV / "depth_blocks.png"), cv2.IMREAD_ANYDEPTH)
    assert np.array_equal(first.color_bgr, expected_color) and np.array_equal(first.depth_mm, expected_depth)
    assert first.depth_mm.dtype == np.uint16 and first.color_bgr.shape == (720, 1280, 3)
    assert second.sequence > first.sequence and second.timestamp_s > first.timestamp_s  # a live stream, stamped now
    assert np.array_equal(second.color_bgr, expected_color)
    calibration = json.loads((DEV / "calibration_f21.json").read_text())  # the station's camera_info values
    K = calibration["K_from_camera_info"]
    assert (intrinsics.width, intrinsics.height) == (1280, 720)
    assert (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy) == (K[0][0], K[1][1], K[0][2], K[1][2])
    assert intrinsics.dist == tuple(calibration["D_from_camera_info_plumb_bob"])
    assert "calibration_f21.json" in camera.description and first.intrinsics == intrinsics


@needs_dev_frames
def test_the_dev_folder_plays_every_pair_in_name_order_each_for_its_period():
    from armlab.devices.recorded.players import FolderPlayer

    names = sorted(p.name[len("image_"):-len(".png")] for p in DEV.glob("image_*.png"))
    player = FolderPlayer(RecordedCameraConfig(source=str(DEV), seconds_per_pair=2.0))
    shown = []
    for now_s in np.arange(0.0, 2.0 * (len(names) + 1), 1.0):  # the player's clock, two looks per pair
        color, depth = player.current(float(now_s))
        shown.append((color, depth))
    for index, name in enumerate([*names, names[0]]):
        expected = cv2.imread(str(DEV / f"image_{name}.png"), cv2.IMREAD_COLOR)
        assert all(np.array_equal(shown[2 * index + k][0], expected) for k in (0, 1)), name
    assert shown[2][1].dtype == np.uint16 and np.array_equal(shown[2][1], cv2.imread(str(DEV / f"depth_{names[1]}.png"), cv2.IMREAD_ANYDEPTH))


# -- generated folders --------------------------------------------------------------------------------


def test_pairs_loop_at_the_configured_period_with_the_folders_intrinsics_json(tmp_path):
    folder = write_pairs(tmp_path / "rec", names=("a", "b"))
    camera = _connected(folder, fps=60.0, seconds_per_pair=0.05)
    try:
        a, b = pair_images(0), pair_images(1)
        first = _read_until(camera, lambda f: np.array_equal(f.color_bgr, a[0]))
        assert np.array_equal(first.depth_mm, a[1])
        second = _read_until(camera, lambda f: np.array_equal(f.color_bgr, b[0]))
        assert np.array_equal(second.depth_mm, b[1])
        _read_until(camera, lambda f: np.array_equal(f.color_bgr, a[0]))  # looped
        intrinsics = camera.intrinsics
    finally:
        camera.close()
    assert (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy) == (K_TEST[0][0], K_TEST[1][1], K_TEST[0][2], K_TEST[1][2])
    assert intrinsics.dist == tuple(DIST_TEST) and (intrinsics.width, intrinsics.height) == (64, 48)


def test_without_loop_the_stream_ends_after_the_last_pair(tmp_path):
    camera = _connected(write_pairs(tmp_path / "rec"), fps=60.0, seconds_per_pair=0.05, loop=False)
    try:
        with pytest.raises(EOFError, match="last of 2 pairs"):
            deadline = time.monotonic() + 5.0
            while time.monotonic() < deadline:
                camera.read()
    finally:
        camera.close()


def test_an_intrinsics_file_given_wins_over_the_folders(tmp_path):
    folder = write_pairs(tmp_path / "rec")
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"K": [[200, 0, 30], [0, 210, 20], [0, 0, 1]], "dist": [0, 0, 0, 0, 0], "image_size": [64, 48]}))
    camera = _connected(folder, intrinsics=str(other))
    try:
        assert (camera.intrinsics.fx, camera.intrinsics.fy) == (200.0, 210.0)
    finally:
        camera.close()


def test_a_pair_that_fails_to_decode_is_skipped_and_the_next_one_shown(tmp_path):
    from armlab.devices.recorded.players import FolderPlayer

    folder = write_pairs(tmp_path / "rec", names=("a", "b", "c"))
    data = (folder / "depth_b.png").read_bytes()
    (folder / "depth_b.png").write_bytes(data[:60])  # the header (checked at open) stays, the pixels are gone
    player = FolderPlayer(RecordedCameraConfig(source=str(folder), seconds_per_pair=1.0))
    assert np.array_equal(player.current(0.0)[0], pair_images(0)[0])
    with pytest.raises(RecordingError, match=r"depth_b\.png: cannot decode"):
        player.current(1.0)
    assert np.array_equal(player.current(1.0)[0], pair_images(2)[0])  # c, right away
    assert np.array_equal(player.current(2.0)[0], pair_images(0)[0])  # round again


def test_the_camera_keeps_delivering_past_a_pair_that_fails(tmp_path):
    folder = write_pairs(tmp_path / "rec", names=("a", "b"))
    (folder / "depth_b.png").write_bytes((folder / "depth_b.png").read_bytes()[:60])
    camera = _connected(folder, fps=60.0, seconds_per_pair=0.05)
    try:
        first = camera.read()
        last = _read_until(camera, lambda f: f.timestamp_s - first.timestamp_s > 0.5)  # b came due ~5 times meanwhile
    finally:
        camera.close()
    assert np.array_equal(last.color_bgr, pair_images(0)[0])


@pytest.mark.parametrize(
    "damage, match",
    [
        (lambda f: cv2.imwrite(str(f / "depth_b.png"), np.zeros((48, 64), np.uint8)), r"depth_b\.png: depth must be single-channel 16-bit"),
        (lambda f: cv2.imwrite(str(f / "depth_b.png"), np.zeros((24, 32), np.uint16)), r"depth_b\.png: depth is 32x24 but image_b\.png is 64x48"),
        (lambda f: cv2.imwrite(str(f / "depth_a.png"), np.zeros((48, 64, 3), np.uint16)), r"depth_a\.png: depth must be single-channel"),
        (lambda f: (f / "image_a.png").write_bytes(b"not a png at all, just text" * 3), r"image_a\.png: not a PNG image"),
        (lambda f: [p.unlink() for p in f.glob("depth_*.png")], r"no recorded pairs: .*found 2 image_\*\.png and 0 depth_\*\.png"),
        (lambda f: (f / "intrinsics.json").unlink(), r"rec: no intrinsics: add intrinsics\.json .* or pass --intrinsics FILE"),
        (lambda f: (f / "intrinsics.json").write_text("{K: [1, 2"), r"intrinsics\.json: cannot read config"),
        (lambda f: (f / "intrinsics.json").write_text('{"K": [[1, 0], [0, 1]], "dist": [], "image_size": [64, 48]}'),
         r"intrinsics\.json: K: expected a 3x3 camera matrix"),
        (lambda f: write_intrinsics(f / "intrinsics.json", (1280, 720)), r"intrinsics\.json: intrinsics for 1280x720 images, but the frames are 64x48"),
        (lambda f: (f / "intrinsics.json").write_text('{"fx": 100}'), r"intrinsics\.json: no intrinsics: expected K \(3x3\), dist and image_size"),
    ],
    ids=["depth-8-bit", "depth-wrong-size", "depth-3-channels", "colour-not-png", "no-pairs", "no-intrinsics", "garbled-intrinsics",
         "bad-K", "intrinsics-other-size", "intrinsics-no-layout"],
)
def test_bad_recordings_are_refused_at_connect_naming_the_file(tmp_path, damage, match):
    folder = write_pairs(tmp_path / "rec")
    damage(folder)
    camera = _camera(folder)
    with pytest.raises(RecordingError, match=match):
        camera.connect()
    assert not camera.is_connected
    write_pairs(folder)  # repaired: the same camera connects (connect cleaned up after the failure)
    for stray in (folder / "depth_a.png", folder / "depth_b.png"):
        assert stray.exists()
    camera.connect()
    camera.close()


def test_missing_sources_and_names_are_refused_naming_them(tmp_path):
    with pytest.raises(RecordingError, match=r"nowhere: no such folder or bag"):
        _camera(tmp_path / "nowhere").connect()
    folder = write_pairs(tmp_path / "rec")
    with pytest.raises(RecordingError, match=r"no pair named 'c' \(pairs: a, b\)"):
        _camera(folder, frame="c").connect()
    with pytest.raises(RecordingError, match=r"missing\.json: intrinsics file not found"):
        _camera(folder, intrinsics=str(tmp_path / "missing.json")).connect()


def test_several_intrinsics_candidates_need_a_choice(tmp_path):
    folder = write_pairs(tmp_path / "rec", intrinsics=False)
    write_intrinsics(folder / "cam_a.json")
    write_intrinsics(folder / "cam_b.json")
    with pytest.raises(RecordingError, match=r"several files hold intrinsics \(cam_a\.json, cam_b\.json\): choose one with --intrinsics"):
        _camera(folder).connect()
    (folder / "cam_b.json").unlink()
    camera = _connected(folder)  # the one file holding intrinsics is used, and said so
    camera.close()
    assert "cam_a.json" in camera.description


def test_the_factory_builds_it_from_config_recorded_with_fields_checked(tmp_path):
    folder = write_pairs(tmp_path / "rec")
    camera = make_camera({"type": "recorded", "source": str(folder), "fps": 20})
    assert isinstance(camera, RecordedCamera)
    with pytest.raises(ConfigError, match=r"fps: Input should be greater than 0"):
        make_camera({"type": "recorded", "source": str(folder), "fps": 0})
    with pytest.raises(ConfigError, match=r"source: empty path"):
        make_camera({"type": "recorded", "source": "  "})


# -- ROS 2 bags ---------------------------------------------------------------------------------------


def test_a_ros2_bag_plays_its_pairs_with_camera_info_intrinsics(tmp_path):
    bag = write_bag(tmp_path / "bag", count=3, period_s=0.05)
    camera = _connected(bag, fps=60.0)
    try:
        frames = [_read_until(camera, lambda f, i=i: np.array_equal(f.color_bgr, pair_images(i)[0])) for i in range(3)]
        looped = _read_until(camera, lambda f: np.array_equal(f.color_bgr, pair_images(0)[0]))
        intrinsics = camera.intrinsics
    finally:
        camera.close()
    assert all(np.array_equal(f.depth_mm, pair_images(i)[1]) for i, f in enumerate(frames))  # each colour with its own depth
    assert looped.sequence > frames[-1].sequence
    assert (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy, intrinsics.dist) == (100.0, 101.0, 31.5, 23.5, tuple(DIST_TEST))
    assert "/camera/color/camera_info" in camera.description


def test_a_bag_without_camera_info_takes_the_intrinsics_file_or_is_refused(tmp_path):
    bag = write_bag(tmp_path / "bag", count=1, info=False)
    with pytest.raises(RecordingError, match=r"bag: no camera_info topic and no intrinsics file: pass --intrinsics FILE"):
        _camera(bag).connect()
    camera = _connected(bag, intrinsics=str(write_intrinsics(tmp_path / "intrinsics.json")))
    camera.close()


def test_bad_bags_are_refused_naming_the_bag(tmp_path):
    damaged = tmp_path / "damaged"
    shutil.copytree(write_bag(tmp_path / "good", count=1), damaged)
    (damaged / "metadata.yaml").write_text("rosbag2_bagfile_information: [this is not, a bag")
    with pytest.raises(RecordingError, match=r"damaged: not a readable ROS bag"):
        _camera(damaged).connect()
    garbage = tmp_path / "noise.db3"
    garbage.write_bytes(b"\x00\x01 not sqlite" * 100)
    with pytest.raises(RecordingError, match=r"noise\.db3: not a readable ROS bag"):
        _camera(garbage).connect()
    unaligned = write_bag(tmp_path / "unaligned", count=1, depth_size=(32, 24))
    with pytest.raises(RecordingError, match=r"unaligned: /camera/aligned_depth_to_color/image_raw is 32x24, /camera/color/image_raw is 64x48"):
        _camera(unaligned).connect()
    no_depth = write_bag(tmp_path / "nodepth", count=1, depth_topic="/camera/infra1/image_rect_raw")
    with pytest.raises(RecordingError, match=r"nodepth: no aligned depth topic found \(topics: .*\)"):
        _camera(no_depth).connect()
    with pytest.raises(RecordingError, match=r"frame: 'x' holds a pair of a folder"):
        _camera(write_bag(tmp_path / "bag", count=1), frame="x").connect()


def test_every_intrinsics_layout_reads_the_same_camera(tmp_path):
    import yaml

    from armlab.cli.vision_cmd import load_intrinsics
    from armlab.devices.recorded.intrinsics_file import read_intrinsics_file

    flat = [v for row in K_TEST for v in row]
    files = {
        "armlab.json": json.dumps({"K": K_TEST, "dist": DIST_TEST, "image_size": [64, 48]}),
        "ros_calibration.yaml": yaml.safe_dump({"image_width": 64, "image_height": 48, "camera_name": "c", "distortion_model": "plumb_bob",
                                                "camera_matrix": {"rows": 3, "cols": 3, "data": flat},
                                                "distortion_coefficients": {"rows": 1, "cols": 5, "data": DIST_TEST}}),
        "camera_info.yaml": yaml.safe_dump({"width": 64, "height": 48, "k": flat, "d": DIST_TEST}),
        "kept_camera_info.json": json.dumps({"K_from_camera_info": K_TEST, "D_from_camera_info_plumb_bob": DIST_TEST}),
    }
    expected = (64, 48, 100.0, 101.0, 31.5, 23.5, tuple(DIST_TEST))
    for name, text in files.items():
        (tmp_path / name).write_text(text)
        intrinsics, origin = read_intrinsics_file(tmp_path / name, (64, 48))
        assert (intrinsics.width, intrinsics.height, intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy, intrinsics.dist) == expected, name
        assert origin.startswith(name)
    cli = load_intrinsics(str(tmp_path / "armlab.json"))  # `armlab calibrate-extrinsics --intrinsics` reads the same file
    assert (cli.width, cli.height, cli.fx, cli.fy, cli.cx, cli.cy, cli.dist) == expected
    with pytest.raises(RecordingError, match=r"kept_camera_info\.json: the file gives no image size"):
        read_intrinsics_file(tmp_path / "kept_camera_info.json")
