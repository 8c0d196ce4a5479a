"""Scores for the jobs §7 does not judge (sort_by_tag, clear_table, stack_here): pure functions of
the final ground truth, in the judge's Score form, for `armlab eval` and the competition bench.

- sort_by_tag (issue 12): +1 per upright block whose ArUco id names a place and whose centre is within
  15 mm (x-y) of that place.
- clear_table: +1 per object whose centre lies in the bin rectangle.
- stack_here: +1 per wanted upright block in the column standing on the point (bottom block within
  15 mm of it).
"""

from __future__ import annotations

import math

from armlab.scene import as_workcell
from armlab.tasks.judge import Rule, Score, columns, upright

PLACE_TOLERANCE_M = 0.015
TIME_LIMIT_S = 600.0
SCORED_JOBS = ("sort_by_tag", "clear_table", "stack_here")


def score_job(job: str, truth: dict, *, sim_time_s: float, params: dict | None = None, workcell=None) -> Score:
    """The score of a non-competition job's final ground truth on `workcell` (a Workcell or its name: its
    places, block tags, bin and block sizes; None = the default workcell). ValueError for another job."""
    workcell = as_workcell(workcell)
    objects = truth["objects"]
    rules: list[Rule] = []
    if job == "sort_by_tag":
        for obj in objects:
            entry = workcell.block_tags.ids.get(obj.get("aruco_id")) if obj.get("aruco_id") is not None else None
            if obj["type"] != "block" or entry is None:
                continue
            place = workcell.places_m[entry.destination]
            distance = math.dist(obj["position_m"][:2], place)
            ok = distance <= PLACE_TOLERANCE_M and upright(obj)
            rules.append(Rule("at its place", int(ok), f"id {obj['aruco_id']} {distance * 1000:.0f} mm from place "
                              f"{entry.destination}" + ("" if upright(obj) else ", tipped"), (obj["id"],)))
    elif job == "clear_table":
        for obj in objects:
            ok = workcell.bin.contains(*obj["position_m"][:2])
            rules.append(Rule("in the bin", int(ok), f"{obj['type']} at ({obj['position_m'][0] * 1000:.0f}, "
                              f"{obj['position_m'][1] * 1000:.0f}) mm", (obj["id"],)))
    elif job == "stack_here":
        params = params or {}
        default = min(workcell.places_m.values(), key=lambda xy: xy[0] ** 2 + xy[1] ** 2)  # as stack_here's
        point = (params.get("x_m", default[0]), params.get("y_m", default[1]))

        def wanted(obj) -> bool:
            return obj["type"] == "block" and params.get("color") in (None, obj["color"]) and params.get("size") in (None, obj["size"])

        column = next((c for c in columns([o for o in objects if upright(o)], workcell.name)
                       if math.dist(c[0].position_m[:2], point) <= PLACE_TOLERANCE_M), ())
        in_column = {obj.id for obj in column}
        for obj in objects:
            if wanted(obj):
                rules.append(Rule("in the stack", int(obj["id"] in in_column), f"{obj['color']} {obj['size']}", (obj["id"],)))
    else:
        raise ValueError(f"score_job scores {', '.join(SCORED_JOBS)}, not {job!r}")
    points, max_points = sum(r.points for r in rules), len(rules)
    within = sim_time_s <= TIME_LIMIT_S
    return Score(points, max_points, within, points == max_points and within, tuple(rules), TIME_LIMIT_S)
