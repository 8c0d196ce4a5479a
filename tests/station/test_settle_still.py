"""When settle.py calls the real arm's waist still: not at the turn of a swing. The P-only waist swings at ~2 Hz
after a short fast move; at each turn its readings stand within a count for the 0.05 s the still check asks, and a
check on the position alone called it still there, up to 0.02 rad from where it came to rest, beyond what settling
corrects: rig 0's arm-accuracy bench had one point 8.5 mm off with it. Scripted readings, as the driver publishes
them (encoder counts, velocity units, 100 Hz)."""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointState
from armlab.station.settle import SETTLE_DEADBAND_RAD, _still_check

COUNT_RAD, VELOCITY_UNIT_RAD_S = 2 * math.pi / 4096, 0.0239809
SWING_RAD, SWING_HZ, DECAY_S = 0.03, 2.0, 0.5


class SwingingWaist:
    """A station whose waist swings about 0, decaying; its clock is set by the test."""

    def __init__(self) -> None:
        self.t = 0.0
        self.arm = self

    def clock_s(self) -> float:
        return self.t

    def read_joint_state(self) -> JointState:
        w, t = 2 * math.pi * SWING_HZ, math.floor(self.t * 100) / 100  # the last 100 Hz sample
        amplitude = SWING_RAD * math.exp(-t / DECAY_S)
        position = amplitude * math.cos(w * t)
        velocity = -amplitude * (w * math.sin(w * t) + math.cos(w * t) / DECAY_S)
        return JointState(np.array([round(position / COUNT_RAD) * COUNT_RAD]),
                          np.array([round(velocity / VELOCITY_UNIT_RAD_S) * VELOCITY_UNIT_RAD_S]), t)

    def joints_rad(self) -> np.ndarray:
        return self.read_joint_state().position_rad


def test_the_waist_is_still_only_once_it_has_stopped_swinging():
    station = SwingingWaist()
    is_still = _still_check(station, np.array([0]))
    while not is_still():
        station.t += 0.002  # the physics' step
        assert station.t < 5.0
    # Called still at the turn of what swing is left, 0.0107 rad out on the position alone; with the velocities the
    # swing left is within two encoder counts of the deadband (0.0031 rad here): a correction from that reading is
    # that far off at most.
    assert abs(station.joints_rad()[0]) <= SETTLE_DEADBAND_RAD + 2 * COUNT_RAD, (station.t, station.joints_rad())
