"""ArmLab Control Station: library for a desktop robot arm with an overhead RGB-D camera.

The library knows nothing about HTTP and keeps no module-level state. Conventions (frames, units)
are in docs/DESIGN.md §3: world = board frame, SI units everywhere.
"""

__version__ = "0.1.0"
