"""The closed loop after a place on the real arm (issue 19 item 4; realism real, rig seed 1, the camera calibrated
from the board tags, then the arm from the camera: what that leaves, a few mm, is the drift). A job's
runner moves one block between two spots, twice to each (MuJoCo truth after every place): with the place check, the
second place on a spot is shifted by what the look after the first saw remain, and lands within 2 mm of its target;
without it, the second place misses by as much as the first. The residuals and corrections are in the event log."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.station.core import Station
from armlab.tasks.policy import Move, Plan
from armlab.tasks.runner import TaskRunner
from real_arm_station import calibrated_real_station

pytestmark = pytest.mark.slow

SPOTS_M = ((0.17, 0.11), (0.05, 0.25))
EDGE_M = 0.038
SCENE = {"objects": [{"id": "b", "type": "block", "color": "red", "size": "large", "position_m": [*SPOTS_M[0], EDGE_M / 2], "yaw_rad": 0.0}]}


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    with calibrated_real_station(1, SCENE, tmp_path_factory.mktemp("placecheck")) as calibrated:
        yield calibrated


def shuttle(station: Station, moves: int, place_check: bool) -> tuple[list[tuple[int, float]], dict]:
    """Run a job that moves the block to the other spot `moves` times; ([(spot index, truth error mm)], result)."""
    errors: list[tuple[int, float]] = []

    def job(ctx):
        runner = TaskRunner(station, ctx, "shuttle")
        runner.place_check.enabled = place_check

        def policy(objects, _given_up) -> Plan:
            blocks = [o for o in objects if o.is_cube]
            if len(errors) >= moves or not blocks:
                return Plan([], done=len(errors), left=0, finished=True)
            block = blocks[0]
            spot = 1 if math.dist(block.position_m[:2], SPOTS_M[0]) < math.dist(block.position_m[:2], SPOTS_M[1]) else 0

            def measured(_edge, spot=spot):
                truth = next(o for o in station.sim.truth()["objects"] if o["id"] == "b")["position_m"]
                errors.append((spot, 1000.0 * math.dist(truth[:2], SPOTS_M[spot])))

            return Plan([Move(block, (*SPOTS_M[spot], 0.0), "shuttle", on_placed=measured)], done=len(errors), left=moves - len(errors))

        return runner.run(policy)

    run = station.start_job("auto", "shuttle", job)
    assert run.wait(600) and run.state == "succeeded", run.message
    assert len(errors) == moves, errors
    return errors, run.result


def test_second_place_on_a_spot_lands_within_2_mm_with_the_loop_and_not_without(station):
    without, result_off = shuttle(station, 4, place_check=False)
    assert result_off["place_check"]["checked"] == 0
    before = station.events.last_seq
    with_loop, result_on = shuttle(station, 4, place_check=True)
    print("without the loop (spot, truth mm):", [(s, round(e, 2)) for s, e in without])
    print("with the loop (spot, truth mm):", [(s, round(e, 2)) for s, e in with_loop])
    for spot in (0, 1):
        first_off, second_off = [e for s, e in without if s == spot]
        first_on, second_on = [e for s, e in with_loop if s == spot]
        assert second_on <= 2.0, f"spot {spot}: corrected place {second_on:.2f} mm from its target (uncorrected {first_on:.2f} mm)"
        # Drift to remove (since the calibration stopped fitting wrist_rotate, spot 1 lands within 0.2 mm; since the waist
        # is settled before a release, settle.py, the uncorrected places miss by 1.0-1.6 mm here, 2+ mm before).
        if second_off > 1.0:
            assert second_on < second_off, (spot, without, with_loop)
    checks = result_on["place_check"]
    assert checks["checked"] == 4 and [r.get("correction") for r in checks["records"][:2]] == [1, 1]
    words = [e["message"] for e in station.events.since(before) if "place check" in e["message"]]
    assert any("later places here shifted by" in w for w in words), words


def test_clamped_correction_never_exceeds_the_clamp(station):
    """The corrected targets the runner sends stay within place_correction_max_m of the intended ones."""
    config = station.config
    assert config.place_correction_max_m == pytest.approx(0.006)
    _, result = shuttle(station, 2, place_check=True)
    for record in result["place_check"]["records"]:
        assert np.linalg.norm(record["shift_mm"]) <= 1000 * config.place_correction_max_m + 1e-6
