"""sort_by_tag live over REST on the UR3 suction workcell (issue 12 item 5), through a real
`armlab serve --workcell ur3_suction` (real-time simulation, real HTTP): POST a scene, calibrate, POST the
auto job and wait for its result; the simulation's ground truth has each block within 15 mm of the place
config/workcells/ur3_suction.yaml (read here) gives its id, upright, and the server's own score agrees."""

from __future__ import annotations

import math

import yaml
from browser_helpers import REPO

FILE = yaml.safe_load((REPO / "config/workcells/ur3_suction.yaml").read_text())
PLACES_M = {int(k): tuple(v) for k, v in FILE["places_m"].items()}
DESTINATION = {int(k): int(v["destination"]) for k, v in FILE["block_tags"]["ids"].items()}
BLOCKS = [  # id 150 -> place 2, right behind the base; id 100 at 0.42 m, beyond the RX200's reach
    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.18, 0.26, 0.019], "yaw_rad": 0.4,
     "aruco_id": 150},
    {"id": "yellow", "type": "block", "color": "yellow", "size": "small", "position_m": [-0.36, 0.22, 0.0125],
     "yaw_rad": -0.2, "aruco_id": 100},
]


def tilt_deg(quat_wxyz) -> float:
    _w, x, y, _z = quat_wxyz
    return math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y)))))


def test_sort_by_tag_from_rest_on_the_ur3(ur3_server):
    server = ur3_server
    server.wait_status(lambda s: s["state"] == "idle", 30.0, "the station idle")
    server.post("/api/sim/scene", {"objects": BLOCKS})
    calibration = server.post("/api/calibrate?wait=true", timeout_s=120)
    assert calibration["job"]["state"] == "succeeded", calibration
    result = server.post("/api/auto?wait=true", {"job": "sort_by_tag", "level": 1}, timeout_s=300)
    assert result["job"]["state"] == "succeeded", result["job"]
    objects = {o["id"]: o for o in server.get("/api/sim/truth")["objects"]}
    for block in BLOCKS:
        place = DESTINATION[block["aruco_id"]]
        final = objects[block["id"]]
        distance_m = math.dist(final["position_m"][:2], PLACES_M[place])
        assert distance_m <= 0.015, f"{block['id']} {distance_m * 1000:.1f} mm from place {place}"
        assert tilt_deg(final["quat_wxyz"]) <= 15.0, f"{block['id']} tipped"
    score = result["score"]["score"]
    assert score["points"] == score["max_points"] == 2, result["score"]  # scored on the UR3's places
