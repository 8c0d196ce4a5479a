"""Stacks from a top face's height: which piles of large and small cubes explain it, and, where two fit
about equally, whether a large block's exposed ring shows. Pure functions of the config's cube sizes."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from armlab.vision.config import PerceptionConfig


def stack_candidates(top_m: float, top_size: str, cfg: PerceptionConfig) -> list[tuple[float, tuple[str, ...]]]:
    """(height mismatch m, sizes bottom..top) of every pile explaining a top face at top_m, best first.

    Piles hold large blocks below small ones, so the blocks under a large block are large. Piles up to
    the configured max_height_m are considered (a to_the_sky tower of 14 large blocks is 0.53 m).
    """
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    below = top_m - (large if top_size == "large" else small)
    n_large = int(cfg.blocks.max_height_m // large) + 1  # 0 .. n_large - 1 large blocks below
    n_small = int(cfg.blocks.max_height_m // small) + 1 if top_size == "small" else 1
    errors = np.abs(below - _pile_heights(large, small, n_large, n_small))
    order = errors.argsort(kind="stable")[:6].tolist()
    best = errors.take(order).tolist()
    return [(e, ("large",) * (i // n_small) + ("small",) * (i % n_small) + (top_size,)) for e, i in zip(best, order)]


@lru_cache(maxsize=16)
def _pile_heights(large: float, small: float, n_large: int, n_small: int) -> np.ndarray:
    """Heights of piles of 0..n_large-1 large then 0..n_small-1 small blocks, flattened (read-only)."""
    heights = np.add.outer(np.arange(n_large) * large, np.arange(n_small) * small).ravel()
    heights.flags.writeable = False
    return heights


def stack_from_height(top_m: float, top_size: str, cfg: PerceptionConfig) -> tuple[int, tuple[str, ...], float]:
    """(stack level, sizes bottom..top, height mismatch m) of the pile that best explains the top height."""
    err, sizes = stack_candidates(top_m, top_size, cfg)[0]
    return len(sizes), sizes, err


def _transition_m(sizes: tuple[str, ...], cfg: PerceptionConfig) -> float | None:
    """Height of the last large block's top when small blocks sit on it (an exposed ring), else None."""
    if "large" not in sizes or sizes[-1] == "large":
        return None
    return sizes.count("large") * cfg.blocks.large_size_m


def choose_stack(
    top_m: float, top_size: str, cfg: PerceptionConfig, z_roi: np.ndarray | None, ring_px: float,
    candidates: list[tuple[float, tuple[str, ...]]] | None = None,
) -> tuple[str, ...]:
    """The pile (sizes bottom..top) for a top face: by height, and where two piles fit about equally
    (e.g. 2 large + 1 small vs 4 small under a small top), by whether a large block's ring shows.
    candidates: stack_candidates(top_m, top_size, cfg) if the caller already has them."""
    candidates = candidates or stack_candidates(top_m, top_size, cfg)
    best_err = candidates[0][0]
    close = [c for c in candidates if c[0] <= best_err + 0.0025][:4]
    if len(close) == 1 or z_roi is None:
        return close[0][1]

    def ring_seen(height_m: float) -> bool:
        return int(np.count_nonzero(np.abs(z_roi - height_m) < 0.0015)) >= ring_px

    transitions = {c[1]: _transition_m(c[1], cfg) for c in close}
    seen = {h: ring_seen(h) for h in transitions.values() if h is not None}
    for _err, sizes in close:
        h = transitions[sizes]
        consistent = seen[h] if h is not None else not any(seen.values())
        if consistent:
            return sizes
    return close[0][1]
