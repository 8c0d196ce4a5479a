"""Scenes: data round trips, validation, and the event/random generators (reproducible, reachable,
non-overlapping, composed as DESIGN §7 says)."""

import math
from pathlib import Path

import numpy as np
import pytest

from armlab.scene import COLORS, Scene, SceneObject, generate_scene, quat_from_yaw
from armlab.scene.events import JOBS
from armlab.scene.layout import REACH_MAX_M, REACH_MIN_M
from armlab.scene.model import Feeder
from armlab.scene.random_layout import random_scene
from armlab.workcell import load_workcell

WORKCELL = load_workcell()
TAG_CENTRES_M = list(WORKCELL.board_tags.centres_m.values())
ALL_EVENT_LEVELS = [(event, level) for event, levels in JOBS.items() for level in levels]


def bottoms(scene: Scene) -> list[SceneObject]:
    """Objects resting on the board (the bottom of each pile)."""
    return [obj for obj in scene.objects if abs(obj.position_m[2] - obj.dimensions_m[2] / 2) < 1e-9]


@pytest.mark.parametrize("event,level", ALL_EVENT_LEVELS)
def test_event_scenes_are_reproducible_reachable_and_disjoint(event, level):
    scene = generate_scene(event, level=level, seed=11)
    assert scene.to_dict() == generate_scene(event, level=level, seed=11).to_dict()
    assert scene.to_dict() != generate_scene(event, level=level, seed=12).to_dict()
    assert scene.overlapping_pairs() == []
    for obj in bottoms(scene):
        r = math.hypot(*obj.position_m[:2])
        assert REACH_MIN_M <= r <= REACH_MAX_M, (obj.id, r)
        assert -0.5 < obj.position_m[0] < 0.5 and -0.175 < obj.position_m[1] < 0.475
        for tag in TAG_CENTRES_M:
            assert math.dist(obj.position_m[:2], tag) > obj.footprint_radius_m, (obj.id, tag)
    # Every object above the board sits exactly on the one below it (same footprint centre).
    for obj in scene.objects:
        if obj not in bottoms(scene):
            below = [o for o in scene.objects if o.position_m[:2] == obj.position_m[:2] and o.position_m[2] < obj.position_m[2]]
            top_of_below = max(o.position_m[2] + o.dimensions_m[2] / 2 for o in below)
            assert obj.position_m[2] - obj.dimensions_m[2] / 2 == pytest.approx(top_of_below)


def test_event_compositions_follow_the_rules():
    sort1 = generate_scene("pick_sort", 1, seed=3)
    assert sorted(o.color for o in sort1.objects) == ["blue", "green", "red"]
    assert all(o.size == "large" and o.position_m[1] > 0 for o in sort1.objects)
    sort2 = generate_scene("pick_sort", 2, seed=3)
    assert sorted(o.size for o in sort2.objects) == ["large"] * 3 + ["small"] * 3
    stack = generate_scene("pick_stack", 2, seed=3)
    assert all(-0.25 < o.position_m[0] < 0.25 and -0.025 < o.position_m[1] < 0.275 for o in stack.objects)
    line1 = generate_scene("line_up", 1, seed=3)
    assert sorted(o.color for o in line1.objects) == sorted(COLORS)
    assert {o.type for o in generate_scene("line_up", 3, seed=3).objects} - {"block"}, "L3 adds distractors"
    high2 = generate_scene("stack_high", 2, seed=3)
    assert sorted(o.size for o in high2.objects) == ["large"] * 6 + ["small"] * 6
    sky = generate_scene("to_the_sky", 1, seed=3)
    assert all(o.type == "block" and o.size == "large" for o in sky.objects) and len(sky.objects) >= 9


def test_level_3_and_level_2_scenes_include_prestacked_blocks_for_some_seed():
    def stacked(scene):
        return len(bottoms(scene)) < len(scene.objects)

    assert any(stacked(generate_scene("pick_sort", 3, seed=s)) for s in range(10))
    assert any(stacked(generate_scene("stack_high", 2, seed=s)) for s in range(10))
    assert not stacked(generate_scene("line_up", 1, seed=0))


def test_unknown_event_or_level_is_refused():
    with pytest.raises(ValueError, match="unknown event"):
        generate_scene("juggle", 1, seed=0)
    with pytest.raises(ValueError, match="levels"):
        generate_scene("stack_high", 3, seed=0)


def test_random_scenes_are_reproducible_and_respect_counts():
    scene = random_scene(seed=5, n_blocks=8, n_distractors=2, max_stack=2)
    assert scene.to_dict() == random_scene(seed=5, n_blocks=8, n_distractors=2, max_stack=2).to_dict()
    assert sum(o.type == "block" for o in scene.objects) == 8
    assert sum(o.type != "block" for o in scene.objects) == 2
    assert scene.overlapping_pairs() == []
    with pytest.raises(ValueError):
        random_scene(seed=0, n_blocks=-1)


def test_round_trip_through_the_truth_format():
    scene = generate_scene("line_up", 3, seed=8)
    again = Scene.from_dict(scene.to_dict())
    assert again == scene
    entry = scene.objects[0].to_dict()
    assert set(entry) >= {"id", "type", "color", "size", "position_m", "yaw_rad", "quat_wxyz"}
    assert entry["yaw_rad"] == pytest.approx(SceneObject.from_dict({**entry, "quat_wxyz": None}).yaw_rad)


def test_yaw_only_objects_get_the_matching_quaternion():
    obj = SceneObject.from_dict({"id": "a", "type": "block", "color": "red", "size": "small",
                                 "position_m": [0.1, 0.2, 0.0125], "yaw_rad": 0.4})
    assert obj.quat_wxyz == pytest.approx(quat_from_yaw(0.4))
    assert obj.yaw_rad == pytest.approx(0.4)


@pytest.mark.parametrize(
    "change,message",
    [
        ({"position_m": [0.1, float("nan"), 0.0]}, "finite"),
        ({"position_m": [0.1, 0.2]}, "3 values"),
        ({"type": "sphere"}, "type"),
        ({"color": "pink"}, "color"),
        ({"size": "huge"}, "size"),
        ({"quat_wxyz": [0, 0, 0, 0]}, "non-zero"),
        ({"wobble": 1}, "unknown fields"),
        ({"id": 'a"/><geom'}, "id must be"),
    ],
)
def test_bad_objects_are_refused_with_a_clear_error(change, message):
    good = {"id": "a", "type": "block", "color": "red", "size": "large", "position_m": [0.1, 0.2, 0.019]}
    with pytest.raises(ValueError, match=message):
        SceneObject.from_dict({**good, **change})


def test_duplicate_ids_are_refused():
    obj = {"id": "a", "type": "block", "color": "red", "size": "large", "position_m": [0.1, 0.2, 0.019]}
    with pytest.raises(ValueError, match="unique"):
        Scene.from_dict({"objects": [obj, obj]})


def test_aruco_tops_go_on_blocks_of_the_mapped_colours_only():
    ids_by_color = {"yellow": 100, "red": 150, "blue": 200}  # the workcell's block_tags (UR3 write-up)
    scene = random_scene(seed=2, n_blocks=12, n_distractors=2, aruco=True)
    for obj in scene.objects:
        expected = ids_by_color.get(obj.color) if obj.type == "block" else None
        assert obj.aruco_id == expected
    assert Scene.from_dict(scene.to_dict()) == scene
    with pytest.raises(ValueError, match="aruco_id"):
        SceneObject("c", "cylinder", "red", None, (0.1, 0.2, 0.019), aruco_id=3)


def test_every_generated_object_is_reachable_by_the_arm_and_bottom_ones_from_straight_above():
    from armlab.kinematics import load_arm

    arm = load_arm("rx200")
    for event, level in ALL_EVENT_LEVELS:
        for seed in range(3):
            scene = generate_scene(event, level, seed=seed)
            floor = bottoms(scene)
            for obj in scene.objects:
                centre = np.array(obj.position_m)
                if obj in floor:
                    q = arm.ik(centre, pitch=math.pi / 2, yaw=obj.yaw_rad)
                else:
                    q = arm.ik(centre, yaw=obj.yaw_rad)  # stacked: the steepest reachable approach
                assert np.linalg.norm(arm.fk(q)[:3, 3] - centre) < 1e-4, (event, level, seed, obj.id)


# --- DESIGN §7 compositions of the new and changed generators, the feeder, sort_by_tag and clear_table


def piles(scene: Scene) -> list[list[SceneObject]]:
    """Objects grouped by footprint centre, bottom first."""
    groups: dict[tuple, list[SceneObject]] = {}
    for obj in scene.objects:
        groups.setdefault(tuple(round(v, 9) for v in obj.position_m[:2]), []).append(obj)
    return [sorted(group, key=lambda o: o.position_m[2]) for group in groups.values()]


def blocks_of(scene: Scene) -> list[SceneObject]:
    return [o for o in scene.objects if o.type == "block"]


@pytest.mark.parametrize("seed", range(8))
def test_pick_stack_level_3_starts_with_six_blocks_piled_at_most_two_high_inside_the_tags(seed):
    scene = generate_scene("pick_stack", 3, seed=seed)
    assert sorted(o.size for o in scene.objects) == ["large"] * 3 + ["small"] * 3
    assert all(o.type == "block" for o in scene.objects)
    assert max(len(p) for p in piles(scene)) <= 2
    assert all(abs(o.position_m[0]) <= 0.25 and -0.025 <= o.position_m[1] <= 0.275 for o in scene.objects)


def test_pick_stack_level_3_is_prestacked_for_some_seed():
    assert any(max(len(p) for p in piles(generate_scene("pick_stack", 3, seed=s))) == 2 for s in range(10))


@pytest.mark.parametrize("seed", range(6))
def test_sort_stack_levels_follow_section_7(seed):
    l1, l2, l3 = (generate_scene("sort_stack", level, seed=seed) for level in (1, 2, 3))
    assert sorted((o.size, o.color) for o in l1.objects) == [("large", "blue"), ("large", "green"), ("large", "red")]
    assert sorted(o.size for o in l2.objects) == ["large"] * 3 + ["small"] * 3
    assert all(o.type == "block" for o in l2.objects) and max(len(p) for p in piles(l2)) == 1
    assert sorted(o.size for o in blocks_of(l3)) == ["large"] * 3 + ["small"] * 3
    assert sum(o.type != "block" for o in l3.objects) == 2
    assert max(len(p) for p in piles(l3)) <= 2
    for scene in (l1, l2, l3):
        assert all(o.position_m[1] > 0 for o in scene.objects)


def test_sort_stack_level_3_is_prestacked_for_some_seed():
    assert any(max(len(p) for p in piles(generate_scene("sort_stack", 3, seed=s))) == 2 for s in range(10))


@pytest.mark.parametrize("level", [1, 2, 3])
def test_sort_by_tag_blocks_carry_the_workcell_ids_in_their_colours_away_from_the_places(level):
    tags = WORKCELL.block_tags.ids
    for seed in range(5):
        scene = generate_scene("sort_by_tag", level, seed=seed)
        assert len(scene.objects) == {1: 3, 2: 6, 3: 8}[level]
        for obj in scene.objects:
            assert obj.type == "block" and obj.aruco_id in tags
            assert obj.color == tags[obj.aruco_id].color
            assert obj.position_m[1] > 0
            for place in WORKCELL.places_m.values():
                assert math.dist(obj.position_m[:2], place) > 0.04 + obj.footprint_radius_m
        ids = [o.aruco_id for o in scene.objects]
        if level == 1:
            assert sorted(ids) == sorted(tags)
        else:
            assert len(set(ids)) < len(ids), "several blocks share an id"
        if level < 3:
            assert max(len(p) for p in piles(scene)) == 1
    assert any(max(len(p) for p in piles(generate_scene("sort_by_tag", 3, seed=s))) == 2 for s in range(10))


@pytest.mark.parametrize("level,blocks,distractors", [(1, 3, 1), (2, 5, 2), (3, 6, 3)])
def test_clear_table_scenes_mix_blocks_and_distractors_outside_the_bin(level, blocks, distractors):
    kinds, colours = set(), set()
    for seed in range(6):
        scene = generate_scene("clear_table", level, seed=seed)
        assert len(blocks_of(scene)) == blocks and len(scene.objects) - blocks == distractors
        for obj in scene.objects:
            x, y, _ = obj.position_m
            r = obj.footprint_radius_m
            (x0, x1), (y0, y1) = WORKCELL.bin.x_range_m, WORKCELL.bin.y_range_m
            assert not (x0 - r < x < x1 + r and y0 - r < y < y1 + r), (seed, obj.id)
            kinds.add(obj.type)
            colours.add(obj.color)
    assert len(kinds) >= 3 and len(colours) >= 4, "any shape, any colour"


def test_to_the_sky_names_the_workcell_feeder_and_keeps_its_spot_clear():
    for seed in range(6):
        scene = generate_scene("to_the_sky", 1, seed=seed)
        assert scene.feeder == Feeder(spot_m=WORKCELL.feeder.spot_m, count=WORKCELL.feeder.count)
        for obj in scene.objects:
            assert math.dist(obj.position_m[:2], scene.feeder.spot_m) > WORKCELL.feeder.clear_radius_m + obj.footprint_radius_m
    again = Scene.from_dict(scene.to_dict())
    assert again == scene and again.to_dict()["feeder"]["remaining"] == WORKCELL.feeder.count


def test_feed_spot_is_reachable_top_down_for_a_large_block():
    from armlab.kinematics import load_arm

    arm = load_arm("rx200")
    centre = np.array([*WORKCELL.feeder.spot_m, WORKCELL.block_edge_m("large") / 2])
    q, pitch = arm.ik_with_pitch(centre)
    assert pitch == pytest.approx(math.pi / 2) and np.linalg.norm(arm.fk(q)[:3, 3] - centre) < 1e-4


@pytest.mark.parametrize(
    "data,message",
    [
        ({"spot_m": [0.2], "count": 3}, "spot_m"),
        ({"spot_m": [0.2, 0.1], "count": -1}, "count"),
        ({"spot_m": [0.2, 0.1], "count": 3, "fed": 4}, "fed"),
        ({"spot_m": [0.2, 0.1], "count": 3, "fed": 1, "remaining": 1}, "remaining"),
        ({"spot_m": [0.2, 0.1]}, "count"),
    ],
)
def test_bad_feeders_are_refused(data, message):
    with pytest.raises(ValueError, match=message):
        Scene.from_dict({"objects": [], "feeder": data})


def test_feeder_ids_not_yet_fed_are_reserved():
    obj = {"id": "feed_1", "type": "block", "color": "red", "size": "large", "position_m": [0.1, 0.2, 0.019]}
    with pytest.raises(ValueError, match="reserved"):
        Scene.from_dict({"objects": [obj], "feeder": {"spot_m": [0.2, 0.1], "count": 3, "fed": 1}})
    fed = Scene.from_dict({"objects": [obj], "feeder": {"spot_m": [0.2, 0.1], "count": 3, "fed": 2}})
    assert fed.feeder.waiting_ids() == ["feed_2"]


def test_object_sizes_come_from_the_workcell_config(tmp_path, monkeypatch):
    import yaml

    data = yaml.safe_load((Path(__file__).resolve().parents[1] / "config/workcells/rx200_armlab.yaml").read_text())
    data["blocks"]["edges_m"] = {"large": 0.040, "small": 0.020}
    (tmp_path / "workcells").mkdir()
    (tmp_path / "workcells/rx200_armlab.yaml").write_text(yaml.safe_dump(data))
    monkeypatch.setenv("ARMLAB_CONFIG_DIR", str(tmp_path))
    block = SceneObject("a", "block", "red", "small", (0.1, 0.2, 0.01))
    assert block.dimensions_m == pytest.approx((0.020, 0.020, 0.020))
    arch = SceneObject("b", "arch", "red", "small", (0.1, 0.2, 0.01))
    assert arch.dimensions_m == pytest.approx((0.060 * 0.5, 0.025 * 0.5, 0.030 * 0.5))
    scene = generate_scene("pick_sort", 1, seed=0)
    assert all(o.position_m[2] == pytest.approx(0.020) for o in scene.objects)


def test_every_generated_scene_can_stand():
    """check_can_stand (what POST /api/sim/scene asks of explicit objects) passes every generated scene:
    stacks touch, nothing is under the board (issue 18 item 8)."""
    from armlab.scene.events import JOBS
    from armlab.scene.model import check_can_stand

    checked = 0
    for event in JOBS:
        for level in (1, 2, 3):
            for seed in range(3):
                try:
                    scene = generate_scene(event, level, seed)
                except ValueError:  # a job without that level or without a scene generator
                    continue
                check_can_stand(scene)
                checked += 1
    assert checked >= 30
