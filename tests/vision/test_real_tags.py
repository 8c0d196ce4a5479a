"""Real tags at the AprilTag library's quality (issue 17 item 5).

On the AprilTag project's real photos (data/apriltag_photos: 47 tag36h11 tags, all id 0) the shipped
settings find >= 44 of the 47 published tags at <= 0.6 px mean corner error, in the library's
convention. The published corners are the reference: the library's own output (quad_decimate 1,
refine_edges off), not a surveyed truth; the error therefore includes the library's own edge refinement
(refine_edges, on in the library's defaults and here), which moves corners by ~0.37 px on these photos.
On the real ROB 550 frames nothing but the board's four tagStandard41h12 tags is read: no other id, no
tag of another family, none on the blocks."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from armlab.devices.sim.tag_bitmaps import tag_bitmap
from armlab.vision import detect_tags, load_perception_config
from armlab.vision.config import TagDetectionConfig
from armlab.vision.tags import free_library_detector, make_detector
from rob550_dev import dev_images, needs_dev_frames, rob550_config
from test_real_photos import PHOTOS, published
from test_tag_families import _place, _square

PHOTO_TAGS = 47
MIN_FOUND = 44  # what the AprilTag library finds with its defaults at full resolution (quad_decimate 1)
MAX_MEAN_CORNER_PX = 0.6


def _library_convention(corners_opencv: np.ndarray) -> np.ndarray:
    """OpenCV order (TL, TR, BR, BL), pixel centres at integers -> the library's (counter-clockwise
    from bottom-left, pixel centres at +0.5). Written out here, independently of armlab.vision.tags."""
    c = np.asarray(corners_opencv, dtype=float)
    return np.array([c[3], c[2], c[1], c[0]]) + 0.5


def _match(reference: list[tuple[int, np.ndarray]], found: list[tuple[int, np.ndarray]]):
    """(per reference tag: mean corner distance px or None, unmatched detections). A detection matches a
    reference tag of its id whose centre is within a quarter of the tag's side (one printed tag)."""
    errors, used = [], set()
    for tag_id, ref in reference:
        side = float(np.linalg.norm(ref[0] - ref[1]))
        best = None
        for k, (found_id, corners) in enumerate(found):
            if found_id == tag_id and k not in used and np.linalg.norm(corners.mean(axis=0) - ref.mean(axis=0)) < 0.25 * side:
                error = float(np.linalg.norm(corners - ref, axis=1).mean())
                if best is None or error < best[0]:
                    best = (error, k)
        errors.append(None if best is None else best[0])
        if best is not None:
            used.add(best[1])
    return errors, [f for k, f in enumerate(found) if k not in used]


def test_the_real_photos_reach_the_librarys_quality_with_the_shipped_settings():
    cfg = load_perception_config()
    errors, false_tags = [], []
    for photo in PHOTOS:
        found = [(t.id, _library_convention(t.corners_px)) for t in detect_tags(cv2.imread(str(photo)), cfg, dictionary="tag36h11")]
        photo_errors, unmatched = _match(published(photo), found)
        errors += photo_errors
        false_tags += [(photo.stem, i, np.round(c.mean(axis=0))) for i, c in unmatched]
    assert len(errors) == PHOTO_TAGS
    matched = [e for e in errors if e is not None]
    assert len(matched) >= MIN_FOUND, f"found {len(matched)} of {PHOTO_TAGS} published tags"
    assert np.mean(matched) <= MAX_MEAN_CORNER_PX, f"mean corner error {np.mean(matched):.3f} px"
    assert not false_tags, f"detections that are no published tag: {false_tags}"


def _two_bits_wrong(family: str, tag_id: int) -> np.ndarray:
    """A 60 px tag of `family` with two of its code cells inverted (a scuff, a glare spot), BGR."""
    canvas = np.full((480 * 4, 640 * 4), 255, np.uint8)
    bitmap = tag_bitmap(family, tag_id)
    cells = bitmap.cells.copy()
    n = cells.shape[0]
    data_cells = [(r, c) for r in range(n) for c in range(n) if (r, c) != (n // 2, n // 2)
                  and min(r, c, n - 1 - r, n - 1 - c) == (n - bitmap.edge_cells) // 2 + 1]  # the ring just inside the border
    for r, c in data_cells[1:3]:
        cells[r, c] = 255 - cells[r, c]
    _place(canvas, cells, bitmap.edge_cells, _square(300.2, 200.7, 60.0))
    return cv2.cvtColor(cv2.resize(canvas, (640, 480), interpolation=cv2.INTER_AREA), cv2.COLOR_GRAY2BGR)


@pytest.mark.parametrize("family", ["tag36h11", "tagStandard41h12"])
def test_a_tag_with_two_wrong_cells_is_read_as_the_library_reads_it(family):
    """The library corrects up to 2 bits by default (a real tag on these photos needs it: the shipped
    max_hamming 1 dropped it); the shipped settings do the same, and 1 bit drops it."""
    image = _two_bits_wrong(family, 5)
    (tag,) = detect_tags(image, load_perception_config(), dictionary=family)
    assert (tag.id, tag.hamming) == (5, 2)
    assert detect_tags(image, detector=make_detector(family, TagDetectionConfig(max_hamming=1))) == []


def test_tags_command_gives_corners_in_the_librarys_convention(capsys):
    from pupil_apriltags import Detector

    from armlab.cli import main

    photo = PHOTOS[0]
    assert main(["tags", str(photo), "--family", "tag36h11", "--corners", "apriltag"]) == 0
    ours = [np.array(t["corners_px"]) for t in json.loads(capsys.readouterr().out)]
    detector = Detector(families="tag36h11", nthreads=1, quad_decimate=1.0)
    library = detector.detect(cv2.cvtColor(cv2.imread(str(photo)), cv2.COLOR_BGR2GRAY))  # the grey the command makes
    free_library_detector(detector)  # its own teardown can segfault
    assert len(library) >= 9
    for det in library:  # the same corners as the library's, in its order and pixel convention
        assert min(np.abs(c - det.corners).max() for c in ours) < 0.01
    assert main(["tags", str(photo), "--family", "tag36h11"]) == 0  # the default: OpenCV's convention
    opencv = [np.array(t["corners_px"]) for t in json.loads(capsys.readouterr().out)]
    assert np.allclose([_library_convention(c) for c in opencv], ours, atol=2e-3)
    with pytest.raises(SystemExit):
        main(["tags", str(photo), "--corners", "upside-down"])
    assert "--corners" in capsys.readouterr().err


@needs_dev_frames
def test_no_false_tags_on_the_real_frames(tmp_path):
    """Only the board's tags 1-4 (tagStandard41h12, the shipped settings), each where its label puts
    it; no block-top tag (the workcell's block dictionary) anywhere, blocks included."""
    cfg = rob550_config(tmp_path)
    assert cfg.tags.dictionary == "tagStandard41h12"
    board = make_detector(cfg.tags.dictionary, cfg.tag_detection)
    block_tops = make_detector(cfg.tags.block_tag_dictionary, cfg.tag_detection)
    images = dev_images()
    assert len(images) >= 8
    for image_path in images:
        image = cv2.imread(str(image_path))
        labels = json.loads(image_path.with_name(image_path.stem + ".labels.json").read_text())["apriltags"]
        where = {t["id"]: (t["u"], t["v"]) for t in labels}
        tags = detect_tags(image, cfg, detector=board)  # with the shaded-tag retry when a board tag is missing
        ids = [t.id for t in tags]
        assert len(ids) == len(set(ids)) and set(ids) <= {1, 2, 3, 4}, f"{image_path.name}: {ids}"
        for tag in tags:
            assert np.linalg.norm(tag.center_px - where[tag.id]) < 8.0, f"{image_path.name}: tag {tag.id} at {tag.center_px}"
        visible = {t["id"] for t in labels if not t.get("occluded")}
        assert visible <= set(ids), f"{image_path.name}: missed {visible - set(ids)}"
        assert detect_tags(image, detector=block_tops) == [], image_path.name
