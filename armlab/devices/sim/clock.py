"""SimClock: the simulated workcell's clock, mixed into SimWorkcell. Fast mode (realtime=False): physics
advances only in step() and in blocking device calls (wait_for), so a seed and a sequence of calls always give
the same result. Real time: a physics thread paced to the wall clock, servo references updated every control
period."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

import mujoco

from armlab.devices.clock import Clock
from armlab.errors import InvalidInput

logger = logging.getLogger(__name__)

MAX_CATCH_UP_S = 0.1  # real time: if physics falls this far behind the wall clock, it drops the backlog


class SimulationTime(Clock):
    """A SimWorkcell's time as the Clock the station is given: simulated seconds, and waits that advance the
    physics in fast mode (or follow the physics thread in real time, at its time scale)."""

    def __init__(self, cell: SimClock) -> None:
        self._cell = cell

    def now_s(self) -> float:
        return self._cell.sim_time_s

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        if self._cell.realtime:  # the cell's wait is in wall seconds then
            return self._cell.wait_for(predicate, timeout_s / float(self._cell.config.time_scale))
        return self._cell.wait_for(predicate, timeout_s)


class SimClock:
    """Stepping the physics of a SimWorkcell (reads its _model/_data, devices and feeder under self.lock)."""

    @property
    def clock(self) -> Clock:
        """This simulation's time for the station (armlab.devices.clock.Clock)."""
        return SimulationTime(self)

    @property
    def realtime(self) -> bool:
        return self.config.realtime

    @property
    def control_period_s(self) -> float:
        """How often the servo references are updated (simulated seconds): the e-stop's halt bound."""
        return float(self._sim.physics.control_period_s)

    @property
    def sim_time_s(self) -> float:
        return float(self._data.time)

    @property
    def next_control_s(self) -> float:
        """When the next control tick runs (simulated s; now if it is due at the coming physics step)."""
        return max(float(self._data.time), float(self._next_control_s))

    def _step_once(self) -> None:
        data = self._data
        if data.time + 1e-9 >= self._next_control_s:
            self._next_control_s = data.time + self._sim.physics.control_period_s
            if self.arm.is_connected:
                self.arm.control(data.time)
                self._record_joints()
            self.gripper.control(data.time)
            if self._feeder is not None:
                self._feeder.tick(self._model, data)
        elif self._publisher is None and self.arm.is_connected:  # the ideal servos follow their trajectory at every step
            self.arm.servo_step(data.time)
        mujoco.mj_step1(self._model, data)  # mj_step in two halves (bit for bit the same): the ideal servos' feed-forward
        if self._publisher is None:         # takes the dynamics of the state this step integrates from
            self._apply_feed_forward()
        mujoco.mj_step2(self._model, data)
        if self._publisher is not None and self._publisher.due(data.time):
            self._publisher.publish(float(data.time), data.qpos[self._arm_qpos], data.qvel[self._arm_qvel])
        if self._path is not None and self._path.due(data.time):
            self._path.record(float(data.time), data.site_xpos[self._gripper_site])

    def _advance(self, duration_s: float) -> None:
        steps = int(round(duration_s / self._model.opt.timestep))
        with self.lock:
            for _ in range(steps):
                self._step_once()

    def step(self, duration_s: float) -> None:
        """Fast mode: advance the physics by duration_s of simulated time, as fast as possible."""
        if self.realtime:
            raise RuntimeError("SimWorkcell.step() is for fast mode; in real time the physics thread advances it")
        if not (isinstance(duration_s, (int, float)) and math.isfinite(duration_s) and 0.0 <= duration_s <= 3600.0):
            raise InvalidInput(f"step: duration_s must be finite and in [0, 3600], got {duration_s!r}")
        self._advance(float(duration_s))

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Block until predicate() (checked under the lock) holds; fast mode steps the physics meanwhile.
        timeout_s is simulated time in fast mode and wall time in real time. Returns predicate()."""
        chunk_s = self._sim.physics.control_period_s
        if not self.realtime:
            elapsed = 0.0
            while True:
                with self.lock:
                    if predicate():
                        return True
                if elapsed >= timeout_s:
                    return False
                self._advance(chunk_s)
                elapsed += chunk_s
        deadline = time.monotonic() + timeout_s
        while True:
            with self.lock:
                if predicate():
                    return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.002)

    def _physics_loop(self) -> None:
        """The real-time physics thread. If it dies, physics would freeze while reads and renders still succeed:
        instead the reason is kept in physics_fault and every device raises DeviceLost naming it (the station's
        device watch then faults and halts), and it is logged."""
        try:
            self._run_physics()
        except Exception as error:  # noqa: BLE001 - whatever ended it, it must not end silently
            self.physics_fault = f"{type(error).__name__}: {error}"
            logger.exception("simulation physics thread died: the simulated devices now report lost")

    def _run_physics(self) -> None:
        wall0 = time.monotonic()
        sim0 = self.sim_time_s
        timestep = self._model.opt.timestep
        scale = float(self.config.time_scale)
        while not self._stop_event.is_set():
            with self.lock:
                target = sim0 + scale * (time.monotonic() - wall0)
                steps = 0
                while self._data.time < target and steps < int(MAX_CATCH_UP_S / timestep):
                    self._step_once()
                    steps += 1
                if self._data.time < target - MAX_CATCH_UP_S:
                    wall0, sim0 = time.monotonic(), self._data.time
            time.sleep(0.001)
