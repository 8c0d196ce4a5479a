"""Every tag instance, AprilTag families through the AprilTag library and ArUco dictionaries through
OpenCV, with sub-pixel corners and the decoder's hamming / decision margin, on synthetic images whose
corner positions are exact (tags warped in perspective, supersampled)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from armlab.devices.sim.tag_bitmaps import tag_bitmap
from armlab.vision import detect_tags
from armlab.vision.config import TagDetectionConfig
from armlab.vision.tags import make_detector

SUPER = 4  # supersampling factor of the synthetic renderer


def _place(canvas: np.ndarray, cells: np.ndarray, edge_cells: int, corners_px: np.ndarray) -> np.ndarray:
    """Draw a tag bitmap so its detected square's corners (TL, TR, BR, BL) land at corners_px of the
    final image (supersampled: `canvas` is SUPER times larger). Returns nothing; edits canvas."""
    n = cells.shape[0]
    cell_px = 40
    big = cv2.resize(cells, (n * cell_px, n * cell_px), interpolation=cv2.INTER_NEAREST)
    margin = (n - edge_cells) / 2 * cell_px
    src = np.array([[margin, margin], [margin + edge_cells * cell_px, margin],
                    [margin + edge_cells * cell_px, margin + edge_cells * cell_px], [margin, margin + edge_cells * cell_px]]) - 0.5
    dst = (np.asarray(corners_px) * SUPER) + (SUPER - 1) / 2.0  # final-image coords -> supersampled coords
    H = cv2.getPerspectiveTransform(src.astype(np.float32), dst.astype(np.float32))
    mask = cv2.warpPerspective(np.full_like(big, 255), H, canvas.shape[::-1], flags=cv2.INTER_NEAREST)
    warped = cv2.warpPerspective(big, H, canvas.shape[::-1], flags=cv2.INTER_LINEAR)
    canvas[mask > 0] = warped[mask > 0]


def _scene(family: str, tags: list[tuple[int, np.ndarray]], shape=(480, 640), flip_cell: tuple[int, int] | None = None):
    """A white image holding each (id, corners_px) tag, with a one-cell quiet zone; BGR uint8."""
    canvas = np.full((shape[0] * SUPER, shape[1] * SUPER), 255, np.uint8)
    for tag_id, corners in tags:
        bitmap = tag_bitmap(family, tag_id)
        cells = bitmap.cells.copy()
        if flip_cell is not None:
            cells[flip_cell] = 255 - cells[flip_cell]
        _place(canvas, cells, bitmap.edge_cells, corners)
    image = cv2.resize(canvas, (shape[1], shape[0]), interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)


def _square(cx: float, cy: float, side: float, skew: float = 0.0) -> np.ndarray:
    """Corners TL, TR, BR, BL of a roughly square quad (skew: a perspective-like squeeze of the bottom)."""
    h = side / 2
    return np.array([[cx - h, cy - h], [cx + h, cy - h], [cx + h - skew, cy + h], [cx - h + skew, cy + h]])


def _grid(n: int, side: float = 34.0) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    quads = []
    for k in range(n):
        cx, cy = 90 + (k % 5) * 115 + rng.uniform(-8, 8), 90 + (k // 5) * 120 + rng.uniform(-8, 8)
        quads.append(_square(cx + 0.37, cy + 0.61, side, skew=rng.uniform(0, 3)))
    return quads


@pytest.mark.parametrize("family", ["DICT_APRILTAG_36h11", "tag36h11", "tagStandard41h12"])
def test_every_instance_of_a_repeated_id_is_reported_with_subpixel_corners(family):
    quads = _grid(12)
    image = _scene(family, [(100, q) for q in quads[:9]] + [(7, q) for q in quads[9:]])
    tags = detect_tags(image, dictionary=family)
    assert sorted(t.id for t in tags) == [7] * 3 + [100] * 9
    for quad in quads:
        match = min(tags, key=lambda t: np.linalg.norm(t.center_px - quad.mean(axis=0)))
        assert np.max(np.linalg.norm(match.corners_px - quad, axis=1)) < 0.5, family  # same order, sub-pixel


@pytest.mark.parametrize("family", ["tag36h11", "tagStandard41h12"])
def test_apriltag_reports_hamming_and_decision_margin(family):
    image = _scene(family, [(3, _square(200.3, 150.8, 40.0))])
    (tag,) = detect_tags(image, dictionary=family)
    assert tag.hamming == 0 and tag.decision_margin > 40
    assert tag.to_dict()["decision_margin"] == pytest.approx(tag.decision_margin)


def test_hamming_threshold_from_config():
    """A tag with one wrong data cell decodes with hamming 1; max_hamming 0 drops it."""
    image = _scene("tagStandard41h12", [(5, _square(200.0, 150.0, 50.0))], flip_cell=(4, 4))
    (tag,) = detect_tags(image, detector=make_detector("tagStandard41h12", TagDetectionConfig(max_hamming=1)))
    assert (tag.id, tag.hamming) == (5, 1)
    assert detect_tags(image, detector=make_detector("tagStandard41h12", TagDetectionConfig(max_hamming=0))) == []


def test_decision_margin_threshold_from_config():
    image = _scene("tag36h11", [(5, _square(200.0, 150.0, 40.0))])
    low_contrast = (128 + (image.astype(np.int16) - 128) // 12).astype(np.uint8)  # ~20 grey levels of contrast
    (tag,) = detect_tags(low_contrast, detector=make_detector("tag36h11", TagDetectionConfig(min_decision_margin=0)))
    assert tag.decision_margin < 25
    assert detect_tags(low_contrast, detector=make_detector("tag36h11", TagDetectionConfig(min_decision_margin=25))) == []


def test_families_do_not_cross_decode():
    image = _scene("tagStandard41h12", [(1, _square(200.0, 150.0, 40.0))])
    assert detect_tags(image, dictionary="tag36h11") == []
    assert detect_tags(image, dictionary="DICT_APRILTAG_36h11") == []
    assert [t.id for t in detect_tags(image, dictionary="tagStandard41h12")] == [1]


def test_malformed_family_name_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown tag family 'tag41h12'.*tagStandard41h12"):
        detect_tags(np.zeros((100, 100, 3), np.uint8), dictionary="tag41h12")


def test_apriltag_detectors_are_built_and_freed_safely_and_cheaply():
    """pupil-apriltags' own teardown frees the family before the detector (an intermittent segfault),
    and its fixed 2-bit decode table takes 0.2-1 s to build for 41h12: 40 detectors built, used and
    freed in a child process must exit cleanly (built for 1 corrected bit: the teardown is the same,
    and 20 tables for 2 bits would cost 4-20 s)."""
    import subprocess
    import sys

    code = ("import numpy as np\nfrom armlab.vision.tags import make_detector\n"
            "from armlab.vision.config import TagDetectionConfig\n"
            "for i in range(40):\n    d = make_detector('tagStandard41h12' if i % 2 else 'tag36h11', TagDetectionConfig(max_hamming=1))\n"
            "    d.detect(np.zeros((64, 64), np.uint8))\n    del d\nprint('ok')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]


def test_tags_command_prints_every_instance_of_the_chosen_family(tmp_path):
    import json
    import subprocess
    import sys
    from pathlib import Path

    quads = _grid(5)
    path = tmp_path / "tags41h12.png"
    cv2.imwrite(str(path), _scene("tagStandard41h12", [(100, q) for q in quads[:4]] + [(2, quads[4])]))
    run = lambda *a: subprocess.run([sys.executable, "-m", "armlab.cli", "tags", str(path), *a], capture_output=True,  # noqa: E731
                                    text=True, timeout=120, cwd=Path(__file__).resolve().parents[2])
    out = run("--family", "tagStandard41h12")
    assert out.returncode == 0, out.stderr
    tags = json.loads(out.stdout)
    assert [t["id"] for t in tags] == [2, 100, 100, 100, 100]
    assert all(t["hamming"] == 0 and t["decision_margin"] > 40 for t in tags)
    assert json.loads(run().stdout) == []  # the default board family (36h11) does not read them
    bad = run("--family", "tag41h12")
    assert bad.returncode == 2 and "unknown tag family" in bad.stderr
