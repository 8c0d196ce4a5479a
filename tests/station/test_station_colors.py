"""The station's colour keeper (armlab/station/colors.py) with a real SQLite file: a labelled frame's fit
replaces the samples; a bad item refuses the whole fit and changes nothing; a stored row naming a colour
the config no longer knows is not restored (warned), the defaults stay in use."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.station.colors import StationColors
from armlab.station.slots import EventLog
from armlab.store import Store
from armlab.vision import load_perception_config


@pytest.fixture(scope="module")
def cfg():
    return load_perception_config()


def _frame() -> np.ndarray:
    """A 1280x720 grey board with a pink and a yellow cube top (34 px squares, BGR) centred at (50, 60) and (140, 60)."""
    image = np.empty((720, 1280, 3), np.uint8)
    image[:] = (120, 130, 125)
    image[43:77, 33:67] = (150, 110, 230)  # pink
    image[43:77, 123:157] = (10, 190, 235)  # yellow
    return image


def test_fit_replaces_the_samples_all_or_nothing(tmp_path, cfg):
    store, events = Store(tmp_path / "db.sqlite3"), EventLog()
    colors = StationColors(store, events, lambda: cfg)
    assert colors.model.classify_lab(colors.measure(_frame(), 140, 60, "yellow").lab).name == "yellow"
    fitted = colors.fit(_frame(), [(50, 60, "pink"), (140, 60, "yellow")])
    assert fitted == {"samples": 2, "read_otherwise_before": 1}  # the pink face read as something else before
    assert [s.name for s in colors.model.samples] == ["pink", "yellow"]
    with pytest.raises(ValueError, match=r"samples\[1\]\.v: 900 is outside the image"):
        colors.fit(_frame(), [(50, 60, "red"), (140, 900, "yellow")])
    with pytest.raises(ValueError, match=r"samples\[0\]\.u, v: the face at \(600, 300\) reads grey"):
        colors.fit(_frame(), [(600, 300, "red")])
    assert [s.name for s in colors.model.samples] == ["pink", "yellow"]  # unchanged
    assert [s["name"] for s in store.latest_color_calibration()["samples"]] == ["pink", "yellow"]
    fresh = StationColors(store, EventLog(), lambda: cfg)
    fresh.restore()
    assert [s.name for s in fresh.model.samples] == ["pink", "yellow"]


def test_a_stored_sample_of_a_name_the_config_dropped_is_not_restored(tmp_path, cfg):
    store, events = Store(tmp_path / "db.sqlite3"), EventLog()
    store.save_color_calibration({"samples": [{"name": "magenta", "lab": [60.0, 60.0, 9.0]}]})
    colors = StationColors(store, events, lambda: cfg)
    colors.restore()
    assert colors.model.samples == () and colors.model is colors.defaults
    assert any("not restored" in e["message"] and "magenta" in e["message"] for e in events.since(0))
