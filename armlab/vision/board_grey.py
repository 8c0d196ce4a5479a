"""The board's grey in a frame: the colour model's white (colors.py divides a face's colour by it). The
dominant grey of board pixels near a face (board_reference_bgr), and per frame the grey near each face
of a detection pass, falling back to the whole board's (BoardGrey)."""

from __future__ import annotations

import numpy as np

from armlab.errors import InvalidInput

BOARD_MAX_SATURATION = 128  # HSV saturation (0..255) above which a pixel is not the board even under a strong colour cast
BOARD_LUMINANCE_BAND = 0.2  # board pixels within this fraction of the median brightness (drops grid lines, tags' white, shadows)
BOARD_CHROMATICITY_BAND = 0.03  # ... and within this of the median chromaticity (r, b of r + g + b; drops wood, paper, cables)
MIN_BOARD_PIXELS = 20


def board_reference_bgr(color_bgr: np.ndarray, board_mask: np.ndarray) -> np.ndarray:
    """The board's grey (3,) BGR in this light: per-channel median of the masked pixels that are not
    strongly coloured (HSV saturation <= BOARD_MAX_SATURATION) and, twice from the medians, within
    BOARD_LUMINANCE_BAND of the median brightness and BOARD_CHROMATICITY_BAND of the median
    chromaticity: the dominant grey (grid lines, tags' white, shadows, wood and paper dropped; a colour
    cast of the light is kept, it is what the reference measures).
    color_bgr: (H, W, 3) uint8; board_mask: (H, W) bool, e.g. board-height pixels around a block.
    ValueError when fewer than MIN_BOARD_PIXELS such pixels remain."""
    if color_bgr.ndim != 3 or board_mask.shape != color_bgr.shape[:2]:
        raise InvalidInput(f"board_reference_bgr: mask {board_mask.shape} does not match image {color_bgr.shape}")
    # np.compress: the same rows as boolean indexing, several times faster on (N, 3) arrays.
    pixels = np.ascontiguousarray(color_bgr).reshape(-1, 3).compress(np.ravel(board_mask).astype(bool, copy=False), axis=0)
    if len(pixels) < MIN_BOARD_PIXELS:
        raise InvalidInput(f"board_reference_bgr: only {len(pixels)} board pixels (needs {MIN_BOARD_PIXELS})")
    # Saturation (hi - lo) / hi <= BOARD_MAX_SATURATION / 255, in whole numbers (_GREY_SPREAD_MAX) on the 8-bit channels.
    b, g, r = pixels[:, 0], pixels[:, 1], pixels[:, 2]
    hi = np.maximum(np.maximum(b, g), r)
    is_grey = hi - np.minimum(np.minimum(b, g), r) <= _GREY_SPREAD_MAX[hi]
    if np.count_nonzero(is_grey) < MIN_BOARD_PIXELS:
        raise InvalidInput(f"board_reference_bgr: only {np.count_nonzero(is_grey)} grey board pixels (needs {MIN_BOARD_PIXELS})")
    grey = pixels.T.astype(np.float32).compress(is_grey, axis=1)  # (3, N) B, G, R
    total = grey[0] + grey[1] + grey[2]  # whole numbers: exact in float32
    # Rows: brightness and chromaticity (b, r of b + g + r), so each round's three medians are one partial sort.
    stats = np.empty((3, total.size), np.float32)
    stats[0] = total
    np.divide(grey[0], np.maximum(total, 1.0), out=stats[1])
    np.divide(grey[2], np.maximum(total, 1.0), out=stats[2])
    keep = None
    for _ in range(2):
        medians = _row_medians(stats.copy() if keep is None else stats.compress(keep, axis=1))
        # Each row within its band of its median, all three rows at once in float32 (as float32 rows compare with
        # Python floats: the bands rounded to float32).
        bands = np.array([BOARD_LUMINANCE_BAND * max(medians[0], 3.0), BOARD_CHROMATICITY_BAND, BOARD_CHROMATICITY_BAND], np.float32)
        keep = np.logical_and.reduce(np.abs(stats - np.array(medians, np.float32)[:, None]) <= bands[:, None])
        if np.count_nonzero(keep) < MIN_BOARD_PIXELS:
            raise InvalidInput("board_reference_bgr: the board pixels have no dominant grey")
    reference = np.array(_row_medians(grey.compress(keep, axis=1)), dtype=float)
    if np.any(reference <= 0):
        raise InvalidInput("board_reference_bgr: the board reads black (no light?)")
    return reference


# Per brightest channel value hi: the largest hi - lo with (hi - lo) * 255 <= BOARD_MAX_SATURATION * max(hi, 1).
_GREY_SPREAD_MAX = (BOARD_MAX_SATURATION * np.maximum(np.arange(256), 1) // 255).astype(np.uint8)


def _row_medians(rows: np.ndarray) -> list[float]:
    """The median of each row of a (R, N) array (N >= 1; the upper middle for an even N) as floats, by one
    partial sort in place (pass a fresh array): far cheaper than np.median on a board window's few hundred pixels."""
    k = rows.shape[1] // 2
    rows.partition(k, axis=1)
    return rows[:, k].tolist()


class BoardGrey:
    """The board's grey for the faces of one frame: measured from board pixels (board_mask) in a window
    around each face, else over the whole board, else over the whole image (the board is its largest
    grey), else a mid grey (no normalisation: a frame with no grey at all). Cheap at the resolution
    given (detect_blocks passes its quarter-resolution image)."""

    def __init__(self, color_bgr: np.ndarray, board_mask: np.ndarray, scale: float = 1.0, window_px: int = 24) -> None:
        self.color_bgr, self.board_mask, self.scale, self.window_px = color_bgr, board_mask, scale, window_px
        self._global: np.ndarray | None = None

    def overall(self) -> np.ndarray:
        if self._global is None:
            image = self.color_bgr[::4, ::4]  # thousands of pixels are plenty for a median
            for mask in (self.board_mask[::4, ::4], np.ones(image.shape[:2], bool)):
                try:
                    self._global = board_reference_bgr(image, mask)
                    break
                except ValueError:
                    continue
            else:
                self._global = np.array([128.0, 128.0, 128.0])
        return self._global

    def near(self, center_px) -> np.ndarray:
        """The board's grey around a full-resolution pixel (falls back to the whole board's)."""
        u, v = int(round(float(center_px[0]) / self.scale)), int(round(float(center_px[1]) / self.scale))
        r = self.window_px
        h, w = self.board_mask.shape
        y0, y1, x0, x1 = max(0, v - r), min(h, v + r + 1), max(0, u - r), min(w, u + r + 1)
        try:
            # Every other pixel of the window: ~600 board pixels, a quarter of the work.
            return board_reference_bgr(self.color_bgr[y0:y1:2, x0:x1:2], self.board_mask[y0:y1:2, x0:x1:2])
        except ValueError:
            return self.overall()


__all__ = ["BOARD_CHROMATICITY_BAND", "BOARD_LUMINANCE_BAND", "BOARD_MAX_SATURATION", "MIN_BOARD_PIXELS", "BoardGrey",
           "board_reference_bgr"]
