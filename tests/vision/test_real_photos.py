"""Tags in real photographs (issue 11, Must show): armlab's detect_tags finds every tag the AprilTag
library itself finds, with corners within 1 px, on real photos with many same-id tags (the AprilTag
project's own test photos: rovers with 10-25 tag36h11 tags, all id 0, outdoors; licence and sources in
data/apriltag_photos/README.md), and on the same photos made harder: blurred, unevenly lit, noisy.

The reference is the raw library (pupil_apriltags.Detector with its defaults, at the decoder
thresholds the station is configured with: max_hamming, min_decision_margin), run on the same image.
Every tag in these photos is id 0 (the published reference lists, *.txt, made by the upstream
library), so any other id reported would be a false detection."""

from __future__ import annotations

import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from armlab.vision import load_perception_config
from armlab.vision.tags import detect_tags

PHOTOS = sorted((Path(__file__).parent / "data" / "apriltag_photos").glob("*.jpg"))
CORNER_TOLERANCE_PX = 1.0
# The library gives corners counter-clockwise from the tag's bottom-left with pixel centres at +0.5;
# armlab's Tag gives them in OpenCV's order (TL, TR, BR, BL) with pixel centres at integers.
LIBRARY_ORDER = [3, 2, 1, 0]


def library_corners(tag) -> np.ndarray:
    """An armlab Tag's corners in the library's order and pixel convention."""
    return tag.corners_px[LIBRARY_ORDER] + 0.5


def published(photo: Path) -> list[tuple[int, np.ndarray]]:
    """The photo's reference detections from the AprilTag project: (id, corners (4, 2))."""
    rows = []
    for line in photo.with_suffix(".txt").read_text().splitlines():
        numbers = [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?", line)]
        rows.append((int(numbers[0]), np.array(numbers[1:9]).reshape(4, 2)))
    return rows


def raw_library(grey: np.ndarray, cfg) -> list[tuple[int, np.ndarray]]:
    """What the AprilTag library finds on its own, at the configured decoder thresholds."""
    from pupil_apriltags import Detector

    from armlab.vision.tags import free_library_detector

    s = cfg.tag_detection
    detector = Detector(families="tag36h11", nthreads=1, quad_decimate=s.quad_decimate)
    found = detector.detect(grey)
    free_library_detector(detector)  # its own teardown can segfault
    return [(int(d.tag_id), np.asarray(d.corners, dtype=float)) for d in found
            if d.hamming <= s.max_hamming and d.decision_margin >= s.min_decision_margin]


def nearest_px(tag_id: int, corners: np.ndarray, others: list[tuple[int, np.ndarray]]) -> float:
    """Largest corner distance to the nearest detection of the same id among `others` (inf: none)."""
    errors = [float(np.linalg.norm(corners - c, axis=1).max()) for i, c in others if i == tag_id]
    return min(errors, default=float("inf"))


def harder(image: np.ndarray, how: str) -> np.ndarray:
    """The photo blurred, unevenly lit (a dark corner to full light, as a lamp at one side) or noisy."""
    if how == "blur":
        return cv2.GaussianBlur(image, (0, 0), 0.6)  # at 0.8-1.0 the library finds none of the small tags of one photo
    if how == "uneven_light":
        h, w = image.shape[:2]
        yy, xx = np.mgrid[0:h, 0:w]
        gain = 0.3 + 0.7 * np.clip(0.5 * xx / w + 0.5 * yy / h + 0.15 * np.cos(xx / 60.0), 0.0, 1.0)
        return np.clip(image * gain[..., None], 0, 255).astype(np.uint8)
    if how == "noise":
        noise = np.random.default_rng(7).normal(0.0, 6.0, image.shape)
        return np.clip(image + noise, 0, 255).astype(np.uint8)
    return image


@pytest.fixture(scope="module")
def tag36h11_cfg():
    cfg = load_perception_config()
    return cfg.model_copy(update={"tags": cfg.tags.model_copy(update={"dictionary": "tag36h11"})})


def test_the_real_photos_are_there():
    assert len(PHOTOS) == 3, PHOTOS
    assert sum(len(published(p)) for p in PHOTOS) >= 40  # 12 + 25 + 10 tags, every one id 0


@pytest.mark.parametrize("how", ["as_taken", "blur", "uneven_light", "noise"])
@pytest.mark.parametrize("photo", PHOTOS, ids=lambda p: p.stem.split("_")[0])
def test_every_tag_the_library_finds_is_found_with_corners_within_1px(photo, how, tag36h11_cfg):
    image = harder(cv2.imread(str(photo)), how)
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    library = raw_library(grey, tag36h11_cfg)
    ours = [(t.id, library_corners(t)) for t in detect_tags(image, dictionary="tag36h11", cfg=tag36h11_cfg)]
    assert len(library) >= 6, f"{how}: the library itself finds only {len(library)} tags"
    misses = [(i, round(nearest_px(i, c, ours), 2)) for i, c in library if nearest_px(i, c, ours) > CORNER_TOLERANCE_PX]
    assert not misses, f"{how}: {len(misses)} of the library's {len(library)} tags not found within 1 px: {misses}"
    # Every instance of the one id is its own detection: as many as the library's, or more (never fewer).
    assert len(ours) >= len(library)
    # Nothing invented: every tag in these photos is id 0 (the published reference lists), and 64 bits of
    # tag36h11 code make a wrongly decoded id 0 out of anything else very unlikely. armlab may find more
    # than the library: its second pass on a log-scaled image reads tags in shade the library misses.
    assert {tag_id for tag_id, _ in ours} == {0}
