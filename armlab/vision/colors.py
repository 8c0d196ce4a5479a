"""Block colours that survive real light: a face's colour normalised by the board's own grey, in CIELAB,
matched to class references measured on real frames (and on the simulation's renders), with `unknown`
for a face far from every class.

Why: hue centres measured in the simulation call real yellow orange and real purple blue or red. The
board is a neutral grey under the same light as the blocks, so dividing a face's linear RGB by the
board's (von Kries white balance + exposure) leaves the face's reflectance relative to the board; that
is turned into CIELAB (sRGB primaries, D65) as if the board had `board_reflectance`. Distances are
CIE94-like with lightness and chroma down-weighted (k_L, k_C): shading and exposure errors change a
face's lightness and chroma far more than its hue. A face farther than `max_distance` from every class
reference, or achromatic (chroma below `min_chroma`) where the nearest reference is chromatic, is
reported as `unknown` with its measured colour, never forced into a class (black, pink, light-blue
cubes exist on real boards). Station colour calibration adds operator samples as references
(ColorModel.with_samples); the defaults come from config/vision.yaml (color_model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import cv2
import numpy as np

from armlab.errors import InvalidInput
from armlab.vision.board_grey import (  # the board's grey, re-exported: part of the colour model's interface
    BOARD_CHROMATICITY_BAND,
    BOARD_LUMINANCE_BAND,
    BOARD_MAX_SATURATION,
    MIN_BOARD_PIXELS,
    BoardGrey,
    board_reference_bgr,
)
from armlab.vision.geometry import project_points

UNKNOWN = "unknown"

# sRGB (linear) -> CIE XYZ, D65; the white point is the matrix's row sums.
_RGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
_WHITE_XYZ = _RGB_TO_XYZ.sum(axis=1)
CLIPPED = 250  # an 8-bit channel at or above this may be clipped: the face is compared with references as the camera would clip them
# A camera that scales its channels after the sensor clipped (white balance, digital gain) and adds noise
# shows a clipped channel as a noisy plateau below 255 (the simulated L515 at a red gain of 0.92: an orange
# face's red at 234 +- 2). Where each channel clips in a frame: CLIP_TOP_PIXELS from its brightest pixel
# (a small cube's top is ~25 pixels at the detector's resolution), less CLIP_MARGIN (~4 sigma of the noise),
# when that is at least MIN_CLIP_LEVEL (a frame with nothing overexposed keeps CLIPPED).
CLIP_TOP_PIXELS = 8
CLIP_MARGIN = 8
MIN_CLIP_LEVEL = 215
MAX_FACE_GAIN = 2.0  # a clipped face's exposure against its board grey, fitted on >= 2 unclipped channels, within this factor


def srgb_to_linear(values: np.ndarray) -> np.ndarray:
    """8-bit sRGB values (any shape) -> linear light 0..1 (IEC 61966-2-1)."""
    c = np.asarray(values, dtype=float) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _lab_f(t: np.ndarray) -> np.ndarray:
    d = 6.0 / 29.0
    return np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)


def lab_from_relative_rgb(relative_rgb: np.ndarray, board_reflectance: float) -> np.ndarray:
    """CIELAB (D65) of linear RGB relative to the board (1 = the board's own), the board taken as a
    neutral grey of board_reflectance; (..., 3) -> (..., 3). Lightness may exceed 100 for faces brighter than white."""
    xyz = (np.asarray(relative_rgb, dtype=float) * board_reflectance) @ _RGB_TO_XYZ.T
    f = _lab_f(np.maximum(xyz, 0.0) / _WHITE_XYZ)
    fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
    lab = np.empty_like(f)
    lab[..., 0] = 116.0 * fy - 16.0
    lab[..., 1] = 500.0 * (fx - fy)
    lab[..., 2] = 200.0 * (fy - fz)
    return lab


_XYZ_TO_RGB = np.linalg.inv(_RGB_TO_XYZ)


def relative_rgb_from_lab(lab, board_reflectance: float) -> np.ndarray:
    """lab_from_relative_rgb's inverse: linear RGB relative to the board of board-normalised CIELAB, (..., 3)."""
    lab = np.asarray(lab, dtype=float)
    fy = (lab[..., 0] + 16.0) / 116.0
    f = np.stack([fy + lab[..., 1] / 500.0, fy, fy - lab[..., 2] / 200.0], axis=-1)
    d = 6.0 / 29.0
    xyz = np.where(f > d, f**3, 3 * d * d * (f - 4.0 / 29.0)) * _WHITE_XYZ
    return xyz @ _XYZ_TO_RGB.T / board_reflectance


MAX_FACE_SAMPLES = 512  # a face's median from at most this many of its pixels (evenly spread): as good, faster


def face_median_rgb(face_bgr: np.ndarray) -> np.ndarray:
    """The per-channel median (3,) RGB of a face's pixels (N, 3) BGR uint8; ValueError when there are none."""
    face = np.asarray(face_bgr).reshape(-1, 3)
    if face.shape[0] == 0:
        raise InvalidInput("the face has no pixels")
    if face.shape[0] > MAX_FACE_SAMPLES:
        face = face[:: face.shape[0] // MAX_FACE_SAMPLES]
    return channel_medians(face)[::-1]


def channel_medians(pixels: np.ndarray) -> np.ndarray:
    """np.median(pixels, axis=0) of (N, 3) pixels (N >= 1), the same values (the mean of the two middle ones
    for an even N) by one partial sort of the channels as rows: a third of np.median's time on a face."""
    rows = pixels.T.copy()  # (3, N) contiguous: each channel's partition runs along memory
    n = rows.shape[1]
    k = n // 2
    if n % 2:
        return np.partition(rows, k, axis=1)[:, k].astype(np.float64)
    middle = np.partition(rows, (k - 1, k), axis=1)[:, k - 1 : k + 1].astype(np.float64)
    return (middle[:, 0] + middle[:, 1]) / 2.0


def _board_grey(board_bgr) -> np.ndarray:
    """board_bgr as (3,) floats; ValueError unless 3 finite positive values."""
    board = np.asarray(board_bgr, dtype=float).reshape(3)
    b, g, r = board.tolist()
    if not (math.isfinite(b + g + r) and min(b, g, r) > 0):
        raise InvalidInput(f"normalised_rgb: board grey must be 3 positive values (BGR), got {[b, g, r]}")
    return board


def normalised_rgb(face_bgr: np.ndarray, board_bgr: np.ndarray, face_rgb: np.ndarray | None = None) -> np.ndarray:
    """The face's linear RGB relative to the board's (per channel; 1 = as bright as the board): the
    median of the face's pixels (N, 3) BGR uint8 (or face_rgb, that median if at hand), divided channel
    by channel by the board's."""
    board = _board_grey(board_bgr)
    face_rgb = face_median_rgb(face_bgr) if face_rgb is None else face_rgb
    return srgb_to_linear(face_rgb) / np.maximum(srgb_to_linear(board[::-1]), 1e-4)


def lab_distance(lab: np.ndarray, reference: np.ndarray, k_lightness: float, k_chroma: float) -> float:
    """CIE94-like colour difference with lightness and chroma down-weighted by k_lightness, k_chroma
    (hue keeps weight 1): lab and reference are (3,) CIELAB."""
    l1, a1, b1 = (float(x) for x in lab)
    l2, a2, b2 = (float(x) for x in reference)
    c1, c2 = math.hypot(a1, b1), math.hypot(a2, b2)
    dc = c1 - c2
    dh2 = max((a1 - a2) ** 2 + (b1 - b2) ** 2 - dc * dc, 0.0)
    cm = math.sqrt(c1 * c2)
    return math.sqrt(((l1 - l2) / k_lightness) ** 2 + (dc / (k_chroma * (1 + 0.045 * cm))) ** 2 + dh2 / (1 + 0.015 * cm) ** 2)


def lab_distances(lab: np.ndarray, references: np.ndarray, k_lightness: float, k_chroma: float) -> np.ndarray:
    """lab_distance of one CIELAB colour (3,) to each of references (M, 3), or of each lab (M, 3) to its reference."""
    lab, references = np.asarray(lab, dtype=float), np.asarray(references, dtype=float)
    c1, c2 = np.hypot(lab[..., 1], lab[..., 2]), np.hypot(references[..., 1], references[..., 2])
    dc = c1 - c2
    dh2 = np.maximum((lab[..., 1] - references[..., 1]) ** 2 + (lab[..., 2] - references[..., 2]) ** 2 - dc * dc, 0.0)
    cm = np.sqrt(c1 * c2)
    return np.sqrt(((lab[..., 0] - references[..., 0]) / k_lightness) ** 2 + (dc / (k_chroma * (1 + 0.045 * cm))) ** 2
                   + dh2 / (1 + 0.015 * cm) ** 2)


def chroma(lab) -> float:
    return math.hypot(float(lab[1]), float(lab[2]))


@dataclass(frozen=True)
class ColorReading:
    """A face's colour: name (a class, or UNKNOWN), its measured CIELAB (board-normalised), the distance
    to the nearest reference (of `name`; for UNKNOWN: of `nearest`) and the nearest class."""

    name: str
    measured_lab: tuple[float, float, float]
    distance: float
    nearest: str

    def to_dict(self) -> dict:
        return {"name": self.name, "measured_lab": [round(float(x), 2) for x in self.measured_lab],
                "distance": round(float(self.distance), 3), "nearest": self.nearest}


@dataclass(frozen=True)
class ColorSample:
    """An operator's (or a labelled frame's) sample: a face of colour `name` measured as `lab` (board-normalised)."""

    name: str
    lab: tuple[float, float, float]
    u: float | None = None
    v: float | None = None
    time_s: float | None = None

    def to_dict(self) -> dict:
        return {"name": self.name, "lab": [round(float(x), 3) for x in self.lab], "u": self.u, "v": self.v, "time_s": self.time_s}

    @classmethod
    def from_dict(cls, data: dict) -> ColorSample:
        lab = tuple(float(x) for x in data["lab"])
        if len(lab) != 3 or not all(math.isfinite(x) for x in lab):
            raise InvalidInput(f"colour sample lab must be 3 finite numbers, got {data['lab']!r}")
        return cls(str(data["name"]), lab, data.get("u"), data.get("v"), data.get("time_s"))


@dataclass(frozen=True)
class ColorModel:
    """Nearest-reference colour classes in board-normalised CIELAB (see the module doc). Immutable:
    with_samples returns a new model, so a perception thread can keep using the old one meanwhile.

    references: class -> default reference colours (CIELAB); samples: the station's own, each a
    reference of its name; names: every colour name a sample may carry (the classes + config extras)."""

    references: dict[str, tuple[tuple[float, float, float], ...]]
    board_reflectance: float = 0.5
    k_lightness: float = 2.0
    k_chroma: float = 2.0
    max_distance: float = 15.0
    min_chroma: float = 10.0
    names: tuple[str, ...] = ()
    samples: tuple[ColorSample, ...] = field(default=())
    shadowed: frozenset = field(default=frozenset())  # (class, index) of default references a sample of another name overrides

    @classmethod
    def from_config(cls, cfg) -> ColorModel:
        """The defaults of a PerceptionConfig (its color_model section) or of a ColorModelConfig."""
        global _LAST_MODEL
        section = getattr(cfg, "color_model", cfg)
        last_section, last_model = _LAST_MODEL
        if last_section is section:  # config sections are frozen: the same section, the same model (and its tables)
            return last_model
        model = _model_from_section(section)
        _LAST_MODEL = (section, model)
        return model

    @property
    def classes(self) -> tuple[str, ...]:
        return tuple(self.references)

    def with_samples(self, samples) -> ColorModel:
        """This model with the station's samples (replacing any it had); ValueError naming a sample's
        colour name the model does not know. The station's word wins over the defaults: a default
        reference closer than max_distance / 2 to a sample of another name is no longer used (a cube
        this station's operator calls pink is not red here, whatever another station's red looked like)."""
        samples = tuple(samples)
        for i, sample in enumerate(samples):
            if sample.name not in self.names:
                raise InvalidInput(f"samples[{i}].color: unknown colour '{sample.name}' (known: {', '.join(self.names)})")
        shadowed = frozenset(
            (name, index) for name, refs in self.references.items() for index, ref in enumerate(refs)
            if any(s.name != name and lab_distance(s.lab, ref, self.k_lightness, self.k_chroma) < 0.5 * self.max_distance
                   for s in samples))
        return ColorModel(self.references, self.board_reflectance, self.k_lightness, self.k_chroma, self.max_distance,
                          self.min_chroma, self.names, samples, shadowed)

    def measure(self, face_bgr: np.ndarray, board_bgr: np.ndarray, face_rgb: np.ndarray | None = None) -> np.ndarray:
        """The face's board-normalised CIELAB (3,) (face_rgb: face_median_rgb(face_bgr), if at hand)."""
        return lab_from_relative_rgb(normalised_rgb(face_bgr, board_bgr, face_rgb), self.board_reflectance)

    def classify(self, face_bgr: np.ndarray, board_bgr: np.ndarray, clip_from_rgb=None) -> ColorReading:
        """The colour of a block face: face_bgr (N, 3) uint8 BGR pixels of the top face, board_bgr the
        board's grey near it (board_reference_bgr). A face with a channel at the camera's ceiling
        (overexposed: its true colour is unknown in that channel) is compared with each reference as the
        camera would show it, clipped the same way: its hue and chroma at the exposure that best fits the
        face's unclipped channels (a top face may be lit more than the board near it: a highlight, the
        board's ring in the cube's shadow), its lightness at the board's exposure (so a dim yellow is not
        a bright orange). clip_from_rgb (3,): the level from which each channel is clipped in this frame
        (frame_clip_levels_rgb; default CLIPPED)."""
        face_rgb = face_median_rgb(face_bgr)
        board = _board_grey(board_bgr)
        linear = srgb_to_linear(np.concatenate([face_rgb, board[::-1]]))  # the face's and the board's RGB in one call
        face_lin, board_lin = linear[:3], np.maximum(linear[3:], 1e-4)
        clip_from = np.full(3, float(CLIPPED)) if clip_from_rgb is None else np.asarray(clip_from_rgb, dtype=float).reshape(3)
        if (face_rgb >= clip_from).any():
            # The face's CIELAB and the references as clipped (both of _clipped_rgb's tables) in one conversion.
            labs = lab_from_relative_rgb(np.concatenate([(face_lin / board_lin)[None], *self._clipped_rgb(board_lin, face_rgb, face_lin, clip_from)]),
                                         self.board_reflectance)
            m = (len(labs) - 1) // 2
            seen = labs[1 + m :]
            seen[:, 0] = labs[1 : 1 + m, 0]  # hue and chroma at the face's exposure, lightness at the board's
            return self.classify_lab(labs[0], seen=seen)
        return self.classify_lab(lab_from_relative_rgb(face_lin / board_lin, self.board_reflectance))

    def _clipped_rgb(self, board_lin: np.ndarray, face_rgb: np.ndarray, face_lin: np.ndarray,
                     clip_from: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The references (M, 3) as this camera shows them on a face whose channels at or above clip_from (3,)
        are clipped at the face's value, the others at 255, before CIELAB (linear RGB relative to the board):
        at the board's exposure (classify takes their lightness), and with hue and chroma scaled to the face's
        unclipped channels (least squares in linear light, within MAX_FACE_GAIN). board_lin: the board's
        linear RGB (floored at 1e-4); face_lin: the face's."""
        free = face_rgb < clip_from
        ceiling = np.where(free, 1.0, face_lin)  # 255 is 1.0 in linear light
        ref_lin = self._table[2] * board_lin  # (M, 3)
        at_board = np.minimum(ref_lin, ceiling) / board_lin
        if np.count_nonzero(free) >= 2:
            free_refs = ref_lin.compress(free, axis=1)  # boolean indexing's columns, cheaper
            norm = np.einsum("ij,ij->i", free_refs, free_refs)
            fit = free_refs @ face_lin.compress(free)
            # np.clip's values (no NaN here), without its overhead.
            gain = np.minimum(np.maximum(np.where(norm > 1e-12, fit / np.maximum(norm, 1e-12), 1.0), 1.0 / MAX_FACE_GAIN), MAX_FACE_GAIN)
            ref_lin = ref_lin * gain[:, None]
        return at_board, np.minimum(ref_lin, ceiling) / board_lin

    def classify_lab(self, lab, seen: np.ndarray | None = None) -> ColorReading:
        """The class of a board-normalised CIELAB colour (nearest reference; UNKNOWN when too far, or
        achromatic against a chromatic reference). seen: the references (M, 3) as the camera shows them."""
        lab = np.asarray(lab, dtype=float)
        names, refs, _ = self._table
        refs = refs if seen is None else seen
        d = lab_distances(lab, refs, self.k_lightness, self.k_chroma)
        l_star, a_star, b_star = lab.tolist()
        measured = (round(l_star, 2), round(a_star, 2), round(b_star, 2))
        if len(d) == 0:
            return ColorReading(UNKNOWN, measured, math.inf, UNKNOWN)
        nearest = int(d.argmin())
        allowed = d.copy()
        if chroma(lab) < self.min_chroma:  # a grey, black or white face is never a chromatic class
            allowed[np.hypot(refs[:, 1], refs[:, 2]) >= self.min_chroma] = np.inf
        best = int(allowed.argmin())
        if allowed[best] <= self.max_distance:
            return ColorReading(names[best], measured, float(allowed[best]), names[best])
        return ColorReading(UNKNOWN, measured, float(d[nearest]), names[nearest])

    @cached_property
    def _table(self) -> tuple[list[str], np.ndarray, np.ndarray]:
        """(names, CIELAB (M, 3), relative linear RGB (M, 3)) of the references in use: the defaults not
        shadowed, then the samples. Computed once per model (models are immutable)."""
        names, labs = [], []
        for name, refs in self.references.items():
            for index, ref in enumerate(refs):
                if (name, index) not in self.shadowed:
                    names.append(name)
                    labs.append(ref)
        for sample in self.samples:
            names.append(sample.name)
            labs.append(sample.lab)
        lab_array = np.asarray(labs, dtype=float).reshape(-1, 3)
        return names, lab_array, relative_rgb_from_lab(lab_array, self.board_reflectance)


_LAST_MODEL: tuple[object, ColorModel | None] = (None, None)  # from_config's last (section, model), swapped whole


def _model_from_section(section) -> ColorModel:
    references = {name: tuple(tuple(float(x) for x in ref) for ref in refs) for name, refs in section.references.items()}
    names = tuple(dict.fromkeys([*references, *section.extra_names]))
    return ColorModel(references, section.board_reflectance, section.k_lightness, section.k_chroma, section.max_distance,
                      section.min_chroma, names)


def board_mask_near(shape: tuple[int, int], center_px, radius_px: int, exclude_px: int) -> np.ndarray:
    """(H, W) bool: a square window of radius_px around center_px without its middle (exclude_px): where
    to look for board pixels around a clicked face when no depth says which are the board."""
    h, w = shape
    u, v = int(round(float(center_px[0]))), int(round(float(center_px[1])))
    mask = np.zeros((h, w), bool)
    mask[max(0, v - radius_px) : v + radius_px + 1, max(0, u - radius_px) : u + radius_px + 1] = True
    mask[max(0, v - exclude_px) : v + exclude_px + 1, max(0, u - exclude_px) : u + exclude_px + 1] = False
    return mask


def face_patch(color_bgr: np.ndarray, center_px, radius_px: int) -> np.ndarray:
    """(N, 3) pixels of a square patch of radius_px around center_px (clipped to the image)."""
    h, w = color_bgr.shape[:2]
    u, v = int(round(float(center_px[0]))), int(round(float(center_px[1])))
    patch = color_bgr[max(0, v - radius_px) : min(h, v + radius_px + 1), max(0, u - radius_px) : min(w, u + radius_px + 1)]
    return patch.reshape(-1, 3)


def board_region_mask(shape_hw: tuple[int, int], T_world_camera: np.ndarray, K: np.ndarray, dist, x_range_m, y_range_m,
                      scale: float = 1.0) -> np.ndarray:
    """(H, W) bool: the pixels inside the board's rectangle (z = 0) as the calibration sees it, in an
    image `scale` times smaller than the camera's: board grey is looked for there only (the table
    beside the board, wood or cloth, is at the board's height too)."""
    (x0, x1), (y0, y1) = x_range_m, y_range_m
    corners = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])
    pixels = project_points(np.asarray(T_world_camera, float), np.asarray(K, float), np.asarray(dist, float), corners) / scale
    mask = np.zeros(shape_hw, np.uint8)
    cv2.fillConvexPoly(mask, np.round(pixels).astype(np.int32), 1)
    return mask.view(bool)


CLICK_FACE_SIDE_PX = 34.0  # a large cube's top at ~1 m under a ~900 px focal length (1280 px wide L515 frame)
PATCH_FRACTION = 0.18  # the face patch's half-width, as a fraction of the face's side (its middle third)
RING_FACES = (0.6, 1.8)  # the board ring around a face: from 0.6 to 1.8 face sides from its centre


def face_and_board_at(color_bgr: np.ndarray, center_px, side_px: float | None = None,
                      board_mask: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(face pixels (N, 3), board grey (3,)) of the face centred at center_px: its middle patch, and the
    board's grey in the ring around it (RING_FACES; within board_mask if given: e.g. board-height pixels).
    side_px: the face's side in pixels (default: a large cube's, scaled with the image width).
    ValueError when the centre is outside the image or the ring holds no board."""
    h, w = color_bgr.shape[:2]
    u, v = float(center_px[0]), float(center_px[1])
    if not (0 <= u < w and 0 <= v < h):
        raise InvalidInput(f"pixel ({u:g}, {v:g}) is outside the {w}x{h} image")
    side = float(side_px) if side_px is not None else CLICK_FACE_SIDE_PX * w / 1280.0
    patch = face_patch(color_bgr, (u, v), max(2, int(round(PATCH_FRACTION * side))))
    ring = board_mask_near((h, w), (u, v), int(RING_FACES[1] * side), int(RING_FACES[0] * side))
    if board_mask is not None:
        ring &= board_mask
    return patch, board_reference_bgr(color_bgr, ring)


def frame_clip_levels_rgb(color_bgr: np.ndarray) -> np.ndarray:
    """(3,) RGB: the level from which each channel counts as clipped in this BGR frame (the CLIP_TOP_PIXELS-th
    brightest value less CLIP_MARGIN, never above CLIPPED; CLIPPED where that is below MIN_CLIP_LEVEL)."""
    blue, green, red = cv2.split(np.ascontiguousarray(color_bgr))
    return np.array([_clip_level(red), _clip_level(green), _clip_level(blue)])


def _clip_level(plane: np.ndarray) -> float:
    """frame_clip_levels_rgb of one 8-bit channel. The CLIP_TOP_PIXELS-th brightest value is the highest v with
    that many pixels at v or above: counted from the channel's maximum down (a few whole-image counts, cheaper
    than its histogram), and only down to the lowest value that gives a level (MIN_CLIP_LEVEL + CLIP_MARGIN)."""
    lowest = MIN_CLIP_LEVEL + CLIP_MARGIN
    brightest = int(cv2.minMaxLoc(plane)[1])
    for value in range(brightest, max(brightest - 3, lowest - 1), -1):
        if cv2.countNonZero(cv2.compare(plane, value, cv2.CMP_GE)) >= CLIP_TOP_PIXELS:
            return float(min(CLIPPED, value - CLIP_MARGIN))
    bright = plane[plane >= lowest]  # more levels to go: the bright values' own CLIP_TOP_PIXELS-th largest
    if bright.size < CLIP_TOP_PIXELS:
        return float(CLIPPED)
    bright.partition(bright.size - CLIP_TOP_PIXELS)
    return float(min(CLIPPED, int(bright[bright.size - CLIP_TOP_PIXELS]) - CLIP_MARGIN))


def measure_at(model: ColorModel, color_bgr: np.ndarray, center_px, side_px: float | None = None,
               board_mask: np.ndarray | None = None) -> np.ndarray:
    """Board-normalised CIELAB of the face centred at center_px (face_and_board_at)."""
    return model.measure(*face_and_board_at(color_bgr, center_px, side_px, board_mask))


def classify_at(model: ColorModel, color_bgr: np.ndarray, center_px, side_px: float | None = None,
                board_mask: np.ndarray | None = None) -> ColorReading:
    """The model's reading of the face centred at center_px (face_and_board_at), as detection reads a face."""
    return model.classify(*face_and_board_at(color_bgr, center_px, side_px, board_mask))


__all__ = ["BOARD_CHROMATICITY_BAND", "BOARD_LUMINANCE_BAND", "BOARD_MAX_SATURATION", "MIN_BOARD_PIXELS", "UNKNOWN", "BoardGrey",
           "ColorModel", "ColorReading", "ColorSample", "board_mask_near", "board_reference_bgr", "board_region_mask", "classify_at",
           "frame_clip_levels_rgb", "face_and_board_at", "face_patch", "lab_distance", "lab_from_relative_rgb", "measure_at",
           "normalised_rgb", "relative_rgb_from_lab", "srgb_to_linear"]
