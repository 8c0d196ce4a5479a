"""Shared fixtures. MuJoCo renders offscreen on the CPU through EGL."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
# The simulation's default is config/sim.yaml's `realism` (camera: the camera shows a real L515's offset,
# noise, holes and drifting colour; real: the arm droops too). The suite's tests assert exact perception, so they run the ideal
# simulation whatever that default is, and so do the stations they start in subprocesses (the variable is inherited); a test of
# the realistic simulation asks for it explicitly (SimWorkcellConfig(realism="real"), `--realism real`).
os.environ["ARMLAB_REALISM"] = "ideal"
