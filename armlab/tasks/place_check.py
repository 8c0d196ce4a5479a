"""Closed loop at the block after a place (issue 19 item 4): a job's next look (the arm parked, nothing hidden)
measures each block it placed against the block's target, logs the residual (the station's event log and the
job's task result: the arm's drift shows), and shifts later places on the same spot (a stack, a column, a
slot used again) by what remains.

Bounded: at most `corrections` corrections a spot, each checked by the look after the place it shifted; the
shift is limited to `max_correction_m` (said so in the log), and a residual beyond NOT_DRIFT_FACTOR times that
is a block that slid or was knocked, not the arm's drift: logged, not chased. A corrected target is planned and
checked like any other (the runner falls back to the uncorrected target, saying why, when it is refused).
Switched by StationConfig.place_check (off by default until bench/competition.py shows job success unchanged with
it); bench/place_loop.py measures it (real arm, 3 rigs: 2.67 mm mean / 4.37 max after arm calibration -> 0.43 / 0.72
on the corrected places).

Why after the place and not before the pick's last descent: the overhead camera cannot see the gripper pointing
down. The gripper's tag (gripper.marker, the arm calibration's) faces sideways then: over 4 top-down hovers on rig 1
it was found once; a look pitched 0.6-0.8 rad (tag in view) measured the arm's error there, but shifting the top-down
descent by it left 1.8-4.2 mm against 2.1-5.4 mm uncorrected (the error does not carry across the pitch).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from armlab.errors import PLAN_REFUSALS
from armlab.tasks.seen import Seen, is_unseen
from armlab.vision.block import Block

SAME_SPOT_M = 0.015  # a target this close (x-y) to an earlier one is the same spot
FIND_RADIUS_M = 0.03  # the placed block is the cube detection nearest its target within this (x-y)...
TOP_TOLERANCE_M = 0.012  # ...whose top is this close to where the block's top should be
NOT_DRIFT_FACTOR = 2.5  # a residual beyond this many clamps is not drift (slid, knocked): not corrected


@dataclass
class Spot:
    """A place target used by the job; the shift its places get now (x-y metres) and its history."""

    target_m: np.ndarray
    correction_m: np.ndarray = field(default_factory=lambda: np.zeros(2))
    corrections: int = 0
    residuals_mm: list[float] = field(default_factory=list)


@dataclass
class _Pending:
    spot: Spot
    target_m: np.ndarray  # the intended target (x, y, surface z)
    top_z_m: float
    name: str
    shifted_m: np.ndarray


class PlaceCheck:
    """The job's places and their residuals; log(level, words) writes the station's event log."""

    def __init__(self, enabled: bool, max_corrections: int, max_correction_m: float, log: Callable[[str, str], None]) -> None:
        self.enabled = enabled
        self.max_corrections = max_corrections
        self.max_correction_m = max_correction_m
        self.log = log
        self.spots: list[Spot] = []
        self.pending: list[_Pending] = []
        self.records: list[dict] = []

    def spot_at(self, to_m) -> Spot | None:
        to = np.asarray(to_m, float)
        return next((s for s in self.spots if math.dist(s.target_m[:2], to[:2]) <= SAME_SPOT_M), None)

    def target_for(self, to_m) -> np.ndarray:
        """Where to place for the intended target to_m: shifted by its spot's correction (none off, or a new spot)."""
        to = np.asarray(to_m, float)
        spot = self.spot_at(to) if self.enabled else None
        if spot is None:
            return to.copy()
        return np.array([to[0] + spot.correction_m[0], to[1] + spot.correction_m[1], to[2]])

    def placed(self, to_m, placed_at_m, edge_m: float, name: str) -> None:
        """A block was released at placed_at_m (target_for(to_m)): the next look checks it."""
        if not self.enabled:
            return
        to = np.asarray(to_m, float)
        spot = self.spot_at(to)
        if spot is None:
            spot = Spot(target_m=to.copy())
            self.spots.append(spot)
        shifted = np.asarray(placed_at_m, float)[:2] - to[:2]
        self.pending.append(_Pending(spot, to, float(to[2] + edge_m), name, shifted))

    def check(self, objects: list[Seen]) -> list[dict]:
        """Measure every block placed since the last look against its target (detections `objects` of a fresh
        look); log each, update the spots' corrections. Returns the new records."""
        new = []
        for place in self.pending:
            new.append(self._check_one(place, objects))
        self.pending = []
        self.records += new
        return new

    def _check_one(self, place: _Pending, objects: list[Seen]) -> dict:
        target = place.target_m
        where = f"({target[0] * 1000:.0f}, {target[1] * 1000:.0f}, {target[2] * 1000:.0f}) mm"
        record = {"block": place.name, "target_m": [float(v) for v in target], "shift_mm": (1000 * place.shifted_m).round(2).tolist()}
        seen = _placed_block(objects, target, place.top_z_m)
        if seen is None:
            record.update(residual_mm=None, note="not found at its target")
            self.log("warn", f"place check: the {place.name} placed at {where} is not seen there (slid, knocked or hidden): no correction")
            return record
        residual = np.asarray(seen.position_m[:2], float) - target[:2]
        size_mm = float(np.linalg.norm(residual) * 1000)
        spot = place.spot
        spot.residuals_mm.append(round(size_mm, 2))
        record.update(residual_mm=round(size_mm, 2), residual_xy_mm=(1000 * residual).round(2).tolist())
        said = (f"place check: the {place.name} sits {size_mm:.1f} mm from its target {where} "
                f"(dx {1000 * residual[0]:+.1f}, dy {1000 * residual[1]:+.1f} mm; placed shifted by "
                f"{np.linalg.norm(place.shifted_m) * 1000:.1f} mm)")
        if self.max_correction_m <= 0.0 or self.max_corrections <= 0:
            record["note"] = "measured only (corrections off)"
            self.log("info", said)
            return record
        if size_mm > NOT_DRIFT_FACTOR * self.max_correction_m * 1000:
            record["note"] = "not drift: not corrected"
            self.log("warn", f"{said}: more than {NOT_DRIFT_FACTOR * self.max_correction_m * 1000:.0f} mm is not the arm's "
                             "drift (slid or knocked): not corrected")
            return record
        if spot.corrections >= self.max_corrections:
            record["note"] = "corrections used up"
            self.log("info", f"{said}; this spot had its {self.max_corrections} corrections: left as it is")
            return record
        wanted = spot.correction_m - residual
        limited = float(np.linalg.norm(wanted)) > self.max_correction_m
        if limited:
            wanted = wanted * (self.max_correction_m / float(np.linalg.norm(wanted)))
        spot.correction_m, spot.corrections = wanted, spot.corrections + 1
        record.update(correction_mm=(1000 * wanted).round(2).tolist(), correction=spot.corrections, limited=limited)
        self.log("info", f"{said}; later places here shifted by ({1000 * wanted[0]:+.1f}, {1000 * wanted[1]:+.1f}) mm "
                         f"(correction {spot.corrections} of {self.max_corrections}"
                         + (f", limited to {self.max_correction_m * 1000:.0f} mm" if limited else "") + ")")
        return record

    def summary(self) -> dict:
        """For the job's result: every place checked, and the residuals' mean and max (mm)."""
        sizes = [r["residual_mm"] for r in self.records if r.get("residual_mm") is not None]
        return {"checked": len(self.records), "found": len(sizes), "mean_mm": round(float(np.mean(sizes)), 2) if sizes else None,
                "max_mm": round(float(np.max(sizes)), 2) if sizes else None, "records": list(self.records)}


def _placed_block(objects: list[Seen], target_m: np.ndarray, top_z_m: float) -> Block | None:
    """The cube detection nearest target_m (x-y) within FIND_RADIUS_M whose top is within TOP_TOLERANCE_M of top_z_m."""
    near = [o for o in objects if o.is_cube and not is_unseen(o)
            and math.dist(o.position_m[:2], target_m[:2]) <= FIND_RADIUS_M and abs(o.position_m[2] - top_z_m) <= TOP_TOLERANCE_M]
    return min(near, key=lambda o: math.dist(o.position_m[:2], target_m[:2]), default=None)


def first_passing_target(plan: Callable[[np.ndarray], object], corrected_m, intended_m, say: Callable[[str], None]) -> np.ndarray:
    """The target to place at: the corrected one when plan(corrected) passes (planned and checked; nothing moves), else,
    saying why, the intended one; the intended one's refusal (PLAN_REFUSALS) propagates. Leaves plan's last call on the
    returned target."""
    corrected, intended = np.asarray(corrected_m, float), np.asarray(intended_m, float)
    try:
        plan(corrected)
        return corrected
    except PLAN_REFUSALS as error:
        if np.array_equal(corrected, intended):
            raise
        say(f"the corrected place target ({corrected[0] * 1000:.1f}, {corrected[1] * 1000:.1f}) mm is refused ({error}): "
            "placing at the uncorrected target")
    plan(intended)
    return intended
