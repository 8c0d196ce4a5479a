"""Shared fixtures. MuJoCo renders offscreen on the CPU through EGL."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
