"""Process memory: hand the heap's freed pages back to the OS (after a scene change frees a whole MuJoCo model)."""

from __future__ import annotations

import ctypes
import ctypes.util


def return_freed_memory() -> None:
    """Hand freed heap memory back to the OS (glibc's malloc_trim; nothing elsewhere). A scene change frees a
    whole MuJoCo model and its GL upload; without this the process keeps the freed pages and its resident
    size ratchets up by ~5-25 MB per scene change (bench/soak.py)."""
    name = ctypes.util.find_library("c")
    try:
        trim = ctypes.CDLL(name).malloc_trim if name else None
    except (OSError, AttributeError):
        trim = None
    if trim is not None:
        trim(0)
