"""Tags in real photographs: armlab's detect_tags against the raw AprilTag library on the AprilTag
project's three test photos (tests/vision/data/apriltag_photos: rovers with 10-25 tag36h11 tags, all
id 0), as taken and made harder (blur, uneven light, noise): tags found by each, the library's tags
armlab missed, corner agreement, and the time per photo.

    .venv/bin/python bench/real_photos.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests" / "vision"))

from test_real_photos import PHOTOS, harder, library_corners, nearest_px, raw_library  # noqa: E402

from armlab.vision import load_perception_config  # noqa: E402
from armlab.vision.tags import detect_tags, make_detector  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timing repeats per photo")
    args = parser.parse_args(argv)
    cfg = load_perception_config()
    cfg = cfg.model_copy(update={"tags": cfg.tags.model_copy(update={"dictionary": "tag36h11"})})
    detector = make_detector("tag36h11", cfg.tag_detection)
    print(f"{'photo':>12} {'variant':>13} {'library':>8} {'armlab':>7} {'missed':>7} {'corner px mean/max':>19} "
          f"{'armlab ms':>10} {'library ms':>11}")
    totals = {"library": 0, "armlab": 0, "missed": 0}
    errors_all = []
    for photo in PHOTOS:
        for how in ("as_taken", "blur", "uneven_light", "noise"):
            image = harder(cv2.imread(str(photo)), how)
            grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
            library = raw_library(grey, cfg)
            ours = [(t.id, library_corners(t)) for t in detect_tags(image, cfg=cfg, detector=detector)]
            errors = [nearest_px(i, c, ours) for i, c in library]
            missed = sum(e > 1.0 for e in errors)
            matched = [e for e in errors if e <= 1.0]
            errors_all += matched
            t0 = time.perf_counter()
            for _ in range(args.repeats):
                detect_tags(image, cfg=cfg, detector=detector)
            ours_ms = (time.perf_counter() - t0) / args.repeats * 1000
            t0 = time.perf_counter()
            for _ in range(args.repeats):
                raw_library(grey, cfg)
            library_ms = (time.perf_counter() - t0) / args.repeats * 1000  # includes building the detector
            totals["library"] += len(library)
            totals["armlab"] += len(ours)
            totals["missed"] += missed
            corner = f"{np.mean(matched):.3f}/{np.max(matched):.3f}" if matched else "-"
            print(f"{photo.stem.split('_')[0]:>12} {how:>13} {len(library):>8} {len(ours):>7} {missed:>7} {corner:>19} "
                  f"{ours_ms:>10.1f} {library_ms:>11.1f}")
    print(f"total: library {totals['library']} tags, armlab {totals['armlab']}, library's tags armlab missed "
          f"{totals['missed']}; corner difference on the matched ones {np.mean(errors_all):.4f} px mean, "
          f"{np.max(errors_all):.4f} px max")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
