"""Scenes: data round trips, validation, and the event/random generators (reproducible, reachable,
non-overlapping, composed as DESIGN §7 says)."""

import math

import numpy as np
import pytest

from armlab.scene import (
    COLORS,
    EVENTS,
    REACH_MAX_M,
    REACH_MIN_M,
    TAG_CENTRES_M,
    Scene,
    SceneObject,
    generate_scene,
    quat_from_yaw,
    random_scene,
)

ALL_EVENT_LEVELS = [(event, level) for event, levels in EVENTS.items() for level in levels]


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
    from armlab.scene import ARUCO_IDS_BY_COLOR

    scene = random_scene(seed=2, n_blocks=12, n_distractors=2, aruco=True)
    for obj in scene.objects:
        expected = ARUCO_IDS_BY_COLOR.get(obj.color) if obj.type == "block" else None
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
