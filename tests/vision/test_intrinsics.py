"""Intrinsic calibration on OpenCV's own chessboard samples against OpenCV's reference result."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from armlab.vision import calibrate_intrinsics
from armlab.vision.intrinsics import parse_pattern

DATA = Path(__file__).parent / "data" / "chessboard"


@pytest.fixture(scope="module")
def reference():
    fs = cv2.FileStorage(str(DATA / "left_intrinsics.yml"), cv2.FILE_STORAGE_READ)
    ref = {
        "K": fs.getNode("camera_matrix").mat(),
        "dist": fs.getNode("distortion_coefficients").mat().ravel(),
        "avg_error": fs.getNode("avg_reprojection_error").real(),
        "nframes": int(fs.getNode("nframes").real()),
        "per_view": fs.getNode("per_view_reprojection_errors").mat().ravel(),
    }
    fs.release()
    return ref


@pytest.fixture(scope="module")
def result():
    return calibrate_intrinsics(sorted(DATA.glob("left*.jpg")), pattern=(9, 6), square_m=0.025)


def test_matches_opencv_reference(result, reference):
    assert len(result.views) == reference["nframes"] == 13
    assert np.abs(result.K - reference["K"]).sum() < 10.0
    assert np.abs(result.dist - reference["dist"]).sum() < 0.05
    assert result.K[0, 0] == pytest.approx(result.K[1, 1])  # CALIB_FIX_ASPECT_RATIO, as the reference
    # RMS as OpenCV defines it (sqrt of the mean squared point error), against the reference's figure.
    assert result.rms == pytest.approx(reference["avg_error"], abs=0.03)
    overall = np.sqrt(np.average(np.square(result.per_view_errors)))
    assert overall == pytest.approx(result.rms, rel=1e-3)
    # The per-view errors single out the same worst view (left02) as the reference.
    assert int(np.argmax(result.per_view_errors)) == int(np.argmax(reference["per_view"]))


def test_bad_input(tmp_path):
    blank = np.full((480, 640), 128, np.uint8)
    with pytest.raises(ValueError, match="found in 0 image"):
        calibrate_intrinsics([blank] * 4)
    with pytest.raises(ValueError, match="square size"):
        calibrate_intrinsics([blank], square_m=float("nan"))
    with pytest.raises(ValueError, match="cannot read"):
        calibrate_intrinsics([tmp_path / "missing.jpg"])
    with pytest.raises(ValueError, match="differs"):
        calibrate_intrinsics([blank, np.zeros((100, 100), np.uint8)])
    assert parse_pattern("9x6") == (9, 6)
    with pytest.raises(ValueError, match="9x6"):
        parse_pattern("nine by six")
