"""The device watch: a thread that checks the arm, the gripper and the camera at a fixed rate.

`probe()` returns {device: reason} for every device that is not answering right now (empty when all
are fine); `on_problems(problems)` is called with each result, so the station can fault on a new loss
and log a recovery. Device loss is never silent: a lost device shows as a fault with its reason.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from armlab.station.perception import DEVICE_ERRORS, _Worker

log = logging.getLogger(__name__)


class DeviceWatch(_Worker):
    """Calls on_problems(probe()) every period_s on its own thread."""

    name = "station-watch"

    def __init__(self, probe: Callable[[], dict[str, str]], on_problems: Callable[[dict[str, str]], None], period_s: float) -> None:
        super().__init__()
        self.probe = probe
        self.on_problems = on_problems
        self.period_s = period_s

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            self.on_problems(self.probe())


def device_problems(arm: Any, gripper: Any, camera_problem: Callable[[], str | None] = lambda: None) -> dict[str, str]:
    """{device: reason} for each device not answering now (reads the arm and gripper, then asks camera_problem(): why
    the camera thread gets no frames, None when it does or none runs); empty when all answer."""
    problems: dict[str, str] = {}
    for name, read in (("arm", arm.read_joint_state), ("gripper", gripper.read_state)):
        try:
            read()
        except DEVICE_ERRORS as error:
            problems[name] = f"{type(error).__name__}: {error}"
    camera = camera_problem()
    if camera is not None:
        problems["camera"] = camera
    return problems
