"""The workcell config (config/workcells/*.yaml): the default file states DESIGN §3's facts, bad files
fail with an error naming the file and the field, ARMLAB_CONFIG_DIR is honoured and edits are seen."""

import json
import os

import pytest
import yaml

from armlab.config import config_dir
from armlab.errors import ConfigError
from armlab.workcell import load_workcell
from armlab.workcell.loading import block_edge_m

DEFAULT_FILE = config_dir() / "workcells" / "rx200_armlab.yaml"


def write_workcell(directory, mutate, name="rx200_armlab"):
    data = yaml.safe_load(DEFAULT_FILE.read_text())
    mutate(data)
    (directory / "workcells").mkdir(exist_ok=True)
    path = directory / "workcells" / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_default_workcell_states_the_design_facts():
    cell = load_workcell()
    assert cell.board.corners_m == ((-0.5, -0.175), (0.5, -0.175), (0.5, 0.475), (-0.5, 0.475))
    assert cell.board_tags.dictionary == "DICT_APRILTAG_36h11" and cell.board_tags.size_m == 0.025
    assert cell.board_tags.centres_m == {1: (-0.25, -0.025), 2: (0.25, -0.025), 3: (0.25, 0.275), 4: (-0.25, 0.275)}
    assert (block_edge_m("large"), block_edge_m("small")) == (0.038, 0.025)
    assert {k: (v.color, v.destination) for k, v in cell.block_tags.ids.items()} == {
        100: ("yellow", 1), 150: ("red", 2), 200: ("blue", 3)}
    grid = cell.board.grid_points_m()
    assert grid[:, 0].min() == pytest.approx(-0.45) and grid[:, 1].max() == pytest.approx(0.475) and len(grid) == 19 * 14
    assert cell.object_dimensions_m("cylinder", "small") == pytest.approx((0.025, 0.025, 0.025))
    assert all(y < 0 for _, y in cell.places_m.values()), "sort_by_tag places are in the negative half"
    assert cell.feeder.count > 0 and cell.bin.contains(*cell.bin.centre_m)


def test_wire_form_is_json_and_carries_the_geometry_the_browser_needs():
    wire = json.loads(json.dumps(load_workcell().to_wire()))
    assert wire["board"]["x_range_m"] == [-0.5, 0.5] and wire["board"]["y_range_m"] == [-0.175, 0.475]
    assert wire["block_edges_m"] == {"large": 0.038, "small": 0.025}
    assert wire["board_tags"]["centres_m"]["3"] == [0.25, 0.275]


@pytest.mark.parametrize(
    "mutate,field",
    [
        (lambda d: d["board"].update(x_range_m=[0.5, -0.5]), "board.x_range_m"),
        (lambda d: d["board"]["grid"].update(step_m=0.0), "board.grid.step_m"),
        (lambda d: d["board"]["grid"].update(x_m=[-0.6, 0.45]), "board"),
        (lambda d: d["board_tags"].update(dictionary="DICT_NOT_A_DICT"), "board_tags.dictionary"),
        (lambda d: d["board_tags"].update(centres_m={1: [0.0, 0.1]}), "board_tags"),
        (lambda d: d["board_tags"]["centres_m"].update({2: [0.9, 0.0]}), "board_tags.centres_m.2"),
        (lambda d: d["board_tags"].update(size_m=float("nan")), "board_tags.size_m"),
        (lambda d: d["blocks"]["edges_m"].update(small=0.05), "blocks"),
        (lambda d: d["blocks"]["edges_m"].pop("small"), "blocks"),
        (lambda d: d["distractors"]["shapes"].pop("arch"), "distractors"),
        (lambda d: d["block_tags"]["ids"].update({300: {"color": "red", "destination": 1}}), "block_tags"),
        (lambda d: d["block_tags"]["ids"].update({120: {"color": "red", "destination": 9}}), "block_tags.ids.120.destination"),
        (lambda d: d["places_m"].update({4: [0.0, 0.9]}), "places_m.4"),
        (lambda d: d["feeder"].update(count=-1), "feeder.count"),
        (lambda d: d["feeder"].update(spot_m=[2.0, 0.1]), "feeder.spot_m"),
        (lambda d: d["bin"].update(y_range_m=[-0.3, -0.1]), "bin"),
        (lambda d: d.update(wobble=1), "wobble"),
        (lambda d: d.pop("feeder"), "feeder"),
        (lambda d: d["gripper"]["marker"].update(id=3), "gripper.marker.id"),  # a board tag's id
        (lambda d: d["gripper"]["marker"].update(id=600), "gripper.marker.id"),  # beyond tag36h11's 587
        (lambda d: d["gripper"]["marker"].update(size_m=0.0), "gripper.marker.size_m"),
    ],
)
def test_bad_workcell_names_the_file_and_the_field(tmp_path, mutate, field):
    path = write_workcell(tmp_path, mutate, name="bad_cell")
    with pytest.raises(ConfigError, match=field.replace(".", ".*")) as error:
        load_workcell(path)
    assert str(path) in str(error.value)


def test_config_dir_is_honoured_and_edits_are_seen(tmp_path, monkeypatch):
    monkeypatch.setenv("ARMLAB_CONFIG_DIR", str(tmp_path))
    path = write_workcell(tmp_path, lambda d: d["blocks"]["edges_m"].update(large=0.040))
    assert block_edge_m("large") == 0.040
    data = yaml.safe_load(path.read_text())
    data["blocks"]["edges_m"]["large"] = 0.042
    path.write_text(yaml.safe_dump(data))
    os.utime(path, ns=(os.stat(path).st_atime_ns, os.stat(path).st_mtime_ns + 10**9))  # a later version
    assert load_workcell().block_edge_m("large") == 0.042


def test_unknown_workcell_and_bad_lookups_are_clear_errors():
    with pytest.raises(ConfigError, match="no config 'nope'.*available: .*rx200_armlab"):
        load_workcell("nope")
    with pytest.raises(ValueError, match="block size"):
        block_edge_m("huge")
    with pytest.raises(ValueError, match="unknown object type"):
        load_workcell().object_dimensions_m("sphere", None)
    with pytest.raises(ValueError, match="no place 7"):
        load_workcell().place_m(7)
