"""The station's colour calibration: the colour model perception uses (armlab.vision.colors), made of
the config's defaults plus this station's samples. The operator clicks a block in the newest frame and
names its colour (add_sample), or the station fits the classes from a labelled frame (fit: a list of
(u, v, colour) replacing the samples); reset goes back to the defaults. Samples are stored in SQLite
(the newest row is in use) and restored at start.

Colour names: the config's classes (red ... violet) and its extra_names (pink, light_blue, black, ...).
An operator may teach a block of an extra name (a pink cube then reads `pink` instead of `unknown`;
jobs sorting by rainbow colour leave it alone), but not invent a name: a typo ("yelow") would make a
class no job knows. Any bad input (an unknown name, a pixel outside the image, a face that reads grey
for a chromatic class, no board around it) raises ValueError naming the field, and nothing changes:
perception keeps the model it had.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np

from armlab.errors import InvalidInput
from armlab.vision.colors import ColorModel, ColorSample, board_region_mask, chroma, measure_at

MAX_SAMPLES = 200


class StationColors:
    """Owned by the Station (station.colors). Thread-safe; `model` is an immutable ColorModel that the
    perception thread reads each frame."""

    def __init__(self, store: Any, events: Any, get_config, get_calibration=lambda: None) -> None:
        self._store, self._events, self._get_config = store, events, get_config
        self._get_calibration = get_calibration  # with one, board grey is looked for on the board's rectangle only
        self._lock = threading.Lock()
        self._write_lock = threading.Lock()  # one change at a time (read samples, store, swap)
        self._defaults: ColorModel | None = None
        self._model: ColorModel | None = None

    @property
    def defaults(self) -> ColorModel:
        if self._defaults is None:
            self._defaults = ColorModel.from_config(self._get_config())
        return self._defaults

    @property
    def model(self) -> ColorModel:
        """The model in use: the defaults with this station's samples."""
        with self._lock:
            model = self._model
        return model if model is not None else self.defaults

    def restore(self) -> None:
        """Use the newest stored samples (a row naming colours the config no longer knows is not used: warned)."""
        data = self._store.latest_color_calibration()
        if data is None:
            return
        try:
            samples = [ColorSample.from_dict(item) for item in data.get("samples", [])]
            model = self.defaults.with_samples(samples)
        except (KeyError, TypeError, ValueError) as error:
            self._events.add("warn", f"saved colour calibration not restored: {error}")
            return
        with self._lock:
            self._model = model
        if samples:
            self._events.add("info", f"colour calibration restored: {len(samples)} sample(s)")

    def info(self) -> dict:
        """GET /api/colors: classes, every name a sample may carry, the unknown threshold, the samples in use."""
        model = self.model
        return {
            "classes": list(model.classes),
            "names": list(model.names),
            "max_distance": model.max_distance,
            "samples": [sample.to_dict() for sample in model.samples],
            "references": {name: [list(ref) for ref in refs] for name, refs in model.references.items()},
        }

    def check_name(self, name: str, field: str = "color") -> None:
        if name not in self.defaults.names:
            raise InvalidInput(f"{field}: unknown colour '{name}' (known: {', '.join(self.defaults.names)})")

    def measure(self, color_bgr: np.ndarray, u: float, v: float, name: str, field: str = "") -> ColorSample:
        """A sample of colour `name` from the face at pixel (u, v) of a frame (not yet used)."""
        self.check_name(name, f"{field}color")
        h, w = color_bgr.shape[:2]
        if not 0 <= u < w:
            raise InvalidInput(f"{field}u: {u:g} is outside the image (0..{w - 1})")
        if not 0 <= v < h:
            raise InvalidInput(f"{field}v: {v:g} is outside the image (0..{h - 1})")
        defaults = self.defaults
        try:
            lab = measure_at(defaults, color_bgr, (u, v), board_mask=self._board_mask(color_bgr.shape[:2]))
        except ValueError as error:
            raise InvalidInput(f"{field}u, v: no board grey around ({u:g}, {v:g}) to measure against ({error})") from error
        if name in defaults.classes and chroma(lab) < defaults.min_chroma:
            raise InvalidInput(f"{field}u, v: the face at ({u:g}, {v:g}) reads grey (Lab {[round(float(x), 1) for x in lab]}), "
                             f"not {name}: click on the block's top")
        return ColorSample(name, tuple(round(float(x), 3) for x in lab), float(u), float(v), time.time())

    def _board_mask(self, shape_hw) -> np.ndarray | None:
        cal, board = self._get_calibration(), self._get_config().board
        if cal is None or (cal.height, cal.width) != tuple(shape_hw):
            return None
        return board_region_mask(shape_hw, cal.T_world_camera, cal.K, cal.dist, board.x_range_m, board.y_range_m)

    def add_sample(self, color_bgr: np.ndarray, u: float, v: float, name: str) -> dict:
        """Measure and add one sample, store and use it at once; returns {"sample", "samples", "reading_before"}."""
        sample = self.measure(color_bgr, u, v, name)
        with self._write_lock:
            before = self.model.classify_lab(sample.lab)
            samples = [*self.model.samples, sample][-MAX_SAMPLES:]
            self._use(samples)
        self._events.add("info", f"colour sample: {name} at ({u:.0f}, {v:.0f}) (read {before.name} before)")
        return {"sample": sample.to_dict(), "reading_before": before.to_dict(), "samples": len(samples)}

    def fit(self, color_bgr: np.ndarray, items: list[tuple[float, float, str]]) -> dict:
        """Replace the samples by those of a labelled frame (u, v, colour each); all checked before any is used."""
        if not items:
            raise InvalidInput("samples: at least one (u, v, color)")
        if len(items) > MAX_SAMPLES:
            raise InvalidInput(f"samples: at most {MAX_SAMPLES}")
        samples = [self.measure(color_bgr, u, v, name, field=f"samples[{i}].") for i, (u, v, name) in enumerate(items)]
        with self._write_lock:
            before = [self.model.classify_lab(s.lab).name for s in samples]
            self._use(samples)
        wrong = sum(b != s.name for b, s in zip(before, samples))
        self._events.add("info", f"colour calibration fitted from {len(samples)} labelled faces ({wrong} read otherwise before)")
        return {"samples": len(samples), "read_otherwise_before": wrong}

    def reset(self) -> dict:
        """Back to the config's defaults (stored, so a restart keeps it)."""
        with self._write_lock:
            self._use([])
        self._events.add("info", "colour calibration reset to the defaults")
        return {"samples": 0}

    def _use(self, samples: list[ColorSample]) -> None:
        model = self.defaults.with_samples(samples)  # checks the names again
        self._store.save_color_calibration({"samples": [s.to_dict() for s in samples]})  # stored first: a failed write changes nothing
        with self._lock:
            self._model = model
