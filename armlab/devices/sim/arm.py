"""SimArm: the Arm interface over the workcell's joint servos. Commands are validated (dof, finite,
joint limits) before anything changes; the workcell calls control() at each control tick, where the servos
take the trajectory commanded since, and (the ideal servos) servo_step() at every physics step between ticks,
where they follow the trajectory taken (servo_reference says how). stop() never waits for the workcell's lock:
when the lock is busy (a physics batch, a scene swap) the halt is latched and the next control tick applies
it, so the arm holds within one control period of simulated time either way."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING

import numpy as np

from armlab.devices.arm import Arm, JointState, JointTrajectory
from armlab.devices.sim.device import SimDevice
from armlab.devices.sim.servo_reference import (
    Followed,
    TrajectoryReference,
    followed_at,
    segment_middle_s,
    servo_reference,
)
from armlab.errors import InvalidInput

if TYPE_CHECKING:
    from armlab.devices.sim.workcell import SimWorkcell

LIMIT_TOLERANCE_RAD = 1e-6


def sample_trajectory(trajectory: JointTrajectory, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(position, velocity, acceleration) of a piecewise-linear trajectory at t_s (clamped; zero velocity and
    acceleration outside it), the servos' references. The position interpolates the samples linearly; the velocity
    runs linearly between the segments' midpoints, where it is their slopes (each sample's change of slope spread
    over the half-segments around it, down to rest at the last sample), and the acceleration is its slope: the
    three agree, so the velocity and acceleration feed-forward do not fight (the segments' own slopes, a staircase,
    kicked the joints at every sample through the velocity gain: up to 1.1x the limit with the acceleration fed
    forward). The first half-segment continues the next change: a trajectory that takes over a moving arm starts
    at its velocity, one from rest at rest."""
    times = trajectory.times_s
    positions = trajectory.positions_rad
    dof = positions.shape[1]
    if t_s < times[0]:
        return positions[0].copy(), np.zeros(dof), np.zeros(dof)
    if t_s >= times[-1]:
        return positions[-1].copy(), np.zeros(dof), np.zeros(dof)
    i = int(np.searchsorted(times, t_s, side="right")) - 1
    dt = times[i + 1] - times[i]
    slope = (positions[i + 1] - positions[i]) / dt
    accel = _segment_accel(times, positions, i, slope, t_s)
    return positions[i] + slope * (t_s - times[i]), slope + accel * (t_s - _middle(times, i)), accel


_middle = segment_middle_s


def _segment_accel(times: np.ndarray, positions: np.ndarray, i: int, slope: np.ndarray, t_s: float) -> np.ndarray:
    """sample_trajectory's acceleration inside segment i (slope: its velocity)."""
    last = len(times) - 2
    if last == 0:  # two samples: no change of slope to spread
        return np.zeros_like(slope)
    middle = _middle(times, i)
    if t_s < middle and i > 0:
        before = (positions[i] - positions[i - 1]) / (times[i] - times[i - 1])
        return (slope - before) / (middle - _middle(times, i - 1))
    if i == last:  # toward rest at the last sample
        return -slope / (times[i + 1] - middle)
    after = (positions[i + 2] - positions[i + 1]) / (times[i + 2] - times[i + 1])
    return (after - slope) / (_middle(times, i + 1) - middle)


class SimArm(SimDevice, Arm):
    """The simulated RX200 arm (joint order = the arm config's joint_names)."""

    def __init__(self, cell: SimWorkcell, joint_names: tuple[str, ...], lower_rad: np.ndarray, upper_rad: np.ndarray,
                 settle_tolerance_rad: float, settle_timeout_s: float) -> None:
        self._cell = cell
        self.joint_names = tuple(joint_names)
        self.lower_rad = np.asarray(lower_rad, dtype=float)
        self.upper_rad = np.asarray(upper_rad, dtype=float)
        self._settle_tolerance_rad = settle_tolerance_rad
        self._settle_timeout_s = settle_timeout_s
        self._trajectory: JointTrajectory | None = None
        self._start_s = 0.0
        self._taken_over: tuple[JointTrajectory, float] | None = None  # the running trajectory a new one replaced, its start
        # what the ideal servos follow between control ticks, as the last tick took it: the trajectory, the one it took over
        self._servo: tuple[Followed, Followed | None] | None = None
        self._hold_next_step = False  # the ideal servos braked a trajectory's end to rest this tick: hold from the next step
        self._took_over = False  # the trajectory commanded last took over one still running (bench seed 10: one ended did not)
        self._hold_rad: np.ndarray | None = None
        self._torque = True
        self._halt_requested = threading.Event()  # set by stop() without the lock; applied under it
        self._halt_requested_s = 0.0
        self._last_halt_s: tuple[float, float] | None = None

    def __str__(self) -> str:
        return "SimArm(rx200)"

    def _on_connect(self) -> None:
        """Hold where the arm is, torque on."""
        with self._cell.lock:
            self._hold_rad = self._cell.arm_positions()
            self._trajectory = None
            self._cell.set_arm_torque(True)
            self._torque = True

    def close(self) -> None:
        if self._connected and self._cell.physics_fault is None:  # with the physics dead there is nothing to stop
            self.stop()
        super().close()

    def read_joint_state(self) -> JointState:
        """Now, or while the physics holds the workcell's lock the state at its last control tick (never waits)."""
        self._require()
        return self._fresh_or_last(self._measure)

    def _measure(self) -> JointState:
        """What the driver reports now (under the lock; stamped with the reading's own age)."""
        position, velocity, age_s = self._cell.arm_reading()
        return JointState(position_rad=position, velocity_rad_s=velocity, timestamp_s=time.time() - age_s)

    def validate_positions(self, positions_rad: np.ndarray) -> None:
        """ValueError unless positions_rad is (N, dof), finite and inside the joint limits."""
        positions = np.asarray(positions_rad, dtype=float)
        dof = len(self.joint_names)
        if positions.ndim != 2 or positions.shape[1] != dof:
            raise ValueError(f"{self}: expected joint positions of shape (N, {dof}), got {positions.shape}")
        if not np.all(np.isfinite(positions)):
            raise ValueError(f"{self}: joint positions must be finite")
        for j, name in enumerate(self.joint_names):
            low = positions[:, j].min()
            high = positions[:, j].max()
            if low < self.lower_rad[j] - LIMIT_TOLERANCE_RAD or high > self.upper_rad[j] + LIMIT_TOLERANCE_RAD:
                raise ValueError(
                    f"{self}: joint '{name}' commanded to [{low:.4f}, {high:.4f}] rad, outside its limits "
                    f"[{self.lower_rad[j]:.4f}, {self.upper_rad[j]:.4f}] rad"
                )

    def command_trajectory(self, trajectory: JointTrajectory, wait: bool = False, start_time_s: float | None = None) -> float:
        """See Arm.command_trajectory; the clock is the simulation's (the start is taken under the physics lock,
        so a command held up by a physics batch still starts where start_time_s says). The servos follow it from
        the next control tick (within one control period)."""
        self._require()
        if not isinstance(trajectory, JointTrajectory):
            raise ValueError(f"{self}: expected a JointTrajectory, got {type(trajectory).__name__}")
        if start_time_s is not None and not np.isfinite(start_time_s):
            raise ValueError(f"{self}: start_time_s must be finite, got {start_time_s!r}")
        self.validate_positions(trajectory.positions_rad)
        with self._cell.lock:
            self._apply_halt()  # a stop requested before this command came first
            if not self._torque:
                raise InvalidInput(f"{self}: torque is off; enable it before commanding motion")
            now_s = self._cell.sim_time_s
            running = self._trajectory
            self._taken_over = (running, self._start_s) if running is not None and now_s - self._start_s < running.duration_s else None
            self._took_over = self._taken_over is not None  # (_taken_over is let go at the handover; this stays)
            self._trajectory = trajectory
            if start_time_s is not None:
                self._start_s = float(start_time_s)
            elif self._cell.ideal_servos:  # from rest: it starts when the servos take it (begun at now, the tick up to 4 ms
                self._start_s = self._cell.next_control_s  # later took it that far in: a step to v(4 ms) at 1.5x the limit)
            else:
                self._start_s = now_s
            # The servos take it at their next control tick, as a servo takes a new goal at its next cycle. Applied
            # here, between ticks, the reference sampled now was held for the rest of the tick, ahead of the one the
            # tick had set by the time since: a one-physics-step kick (a takeover at 3 rad/s: the joints at 1.2x the
            # acceleration limit over 20 ms).
            started_s = self._start_s
        if wait:
            self.wait_until_done()
        return started_s

    def clock_s(self) -> float:
        """The simulation's time (the clock start_time_s is on)."""
        return self._cell.sim_time_s

    def is_moving(self) -> bool:
        """Tracking a trajectory (a halt requested counts as done); never waits for a physics batch."""
        self._require()
        if self._cell.lock.acquire(blocking=False):
            try:
                self._apply_halt()
            finally:
                self._cell.lock.release()
        return self._trajectory is not None and not self._halt_requested.is_set()

    def wait_until_done(self, timeout_s: float | None = None) -> bool:
        self._require()
        with self._cell.lock:
            remaining_s = 0.0
            if self._trajectory is not None:
                remaining_s = self._trajectory.duration_s - (self._cell.sim_time_s - self._start_s)
        limit = timeout_s if timeout_s is not None else max(0.0, remaining_s) + self._settle_timeout_s + 1.0
        return self._cell.wait_for(lambda: self._trajectory is None, limit)

    def stop(self) -> None:
        """Halt: at once if the workcell's lock is free, else at the next control tick (never waits)."""
        self._require()
        if not self._halt_requested.is_set():  # a halt already pending keeps its (earlier) request time
            self._halt_requested_s = self._cell.sim_time_s
        self._halt_requested.set()
        if self._cell.lock.acquire(blocking=False):
            try:
                self._apply_halt()
            finally:
                self._cell.lock.release()

    @property
    def reference_rad(self) -> np.ndarray:
        """The position the servos are commanded to hold now (the trajectory's current sample): what the
        station commanded, even where the physical arm is blocked (by the board, say). Between control ticks (a
        command just sent, which the servos take at the next tick) the trajectory's sample at the clock."""
        self._require()
        with self._cell.lock:
            if self._trajectory is not None and self._torque and not self._halt_requested.is_set():
                return sample_trajectory(self._trajectory, self._cell.sim_time_s - self._start_s)[0]
            return self._cell.arm_reference()

    @property
    def last_halt_sim_s(self) -> tuple[float, float] | None:
        """(requested, applied) simulated times of the last stop(), or None: the halt latency in sim time."""
        return self._last_halt_s

    def _apply_halt(self) -> None:
        """Under the lock: apply a latched stop() (drop the trajectory, hold the measured position)."""
        if not self._halt_requested.is_set():
            return
        self._halt_requested.clear()
        self._trajectory = None
        self._servo = None
        self._hold_rad = self._cell.arm_reading()[0]  # as the driver holds: where the arm last read
        self._cell.apply_arm_reference(self._hold_rad, np.zeros_like(self._hold_rad))
        self._last_halt_s = (self._halt_requested_s, self._cell.sim_time_s)

    def set_torque(self, enabled: bool) -> None:
        self._require()
        with self._cell.lock:
            self._trajectory = None
            self._servo = None
            self._hold_rad = self._cell.arm_reading()[0]
            self._cell.apply_arm_reference(self._hold_rad, np.zeros_like(self._hold_rad))
            self._cell.set_arm_torque(bool(enabled))
            self._torque = bool(enabled)

    def control(self, sim_time_s: float) -> None:
        """Feed the servos (called by the workcell under its lock at every control tick): the servos take the trajectory
        commanded since the last tick; the ideal servos are fed its references for the physics step that starts now
        (servo_reference) and follow it at every step until the next tick (servo_step); the real arm's firmware gets
        the position goal once per tick."""
        self._apply_halt()
        self._last_reading = self._measure()
        self._hold_next_step = False
        trajectory = self._trajectory
        if trajectory is None or not self._torque:
            self._servo = None
            return
        t = sim_time_s - self._start_s
        if self._taken_over is not None and not (len(trajectory.times_s) >= 3 and t < _middle(trajectory.times_s, 0)):
            self._taken_over = None
        moving = bool(np.any(self._cell.arm_reference_velocity()))  # the step before this tick's (see below)
        if self._cell.ideal_servos:
            self._servo = self._take(trajectory, sim_time_s)
            position = self._feed(sim_time_s)
        else:
            position, velocity, accel = sample_trajectory(trajectory, t)
            if self._taken_over is not None:
                running, running_start_s = self._taken_over
                _, velocity, accel = sample_trajectory(running, sim_time_s - running_start_s)
            self._cell.apply_arm_reference(position, velocity, accel)
        if t >= trajectory.duration_s:
            error = np.max(np.abs(self._cell.arm_positions() - position))
            if error <= self._settle_tolerance_rad or t >= trajectory.duration_s + self._settle_timeout_s:
                self._trajectory = None
                self._hold_rad = position
                if self._servo is not None:  # the ideal servos hold at rest at the last sample, no acceleration fed
                    # forward (the last one fed was a bit of the braking: left on, it pushed the held arm ~1.3 mrad away)
                    self._servo = None
                    if moving:  # the step before still moved (a joint moves over a step with the velocity at its middle:
                        # a*h/2 at a braking trajectory's end): this tick's feed brakes it to rest and the next step holds
                        # (released at once, the joint crept on for ~6 ticks and the next move's servos took that out)
                        self._hold_next_step = True
                    else:
                        self._cell.apply_arm_reference(position, np.zeros_like(position), np.zeros_like(position))

    def servo_step(self, sim_time_s: float) -> None:
        """The ideal servos between control ticks (called by the workcell under its lock at every other physics step):
        follow the trajectory the last tick took."""
        if self._hold_next_step:
            self._hold_next_step = False
            self._cell.apply_arm_reference(self._hold_rad, np.zeros_like(self._hold_rad), np.zeros_like(self._hold_rad))
        elif self._servo is not None and self._torque and not self._halt_requested.is_set():
            self._feed(sim_time_s)

    def _take(self, trajectory: JointTrajectory, sim_time_s: float) -> tuple[Followed, Followed | None]:
        """The ideal servos' _servo for the current trajectory at the tick at sim_time_s (references computed once, when a
        trajectory is first taken; the one taken over is the one followed until now). A trajectory taken while the servos
        follow another carries on from the position reference they have reached: from the one it took over at the
        handover (its first midpoint), else from the one followed at this tick."""
        before = self._servo
        known = () if before is None else tuple(f for f in before if f is not None)

        def followed(of: JointTrajectory, start_s: float) -> Followed | None:
            return next((f for f in known if f.reference.trajectory is of and f.start_s == start_s), None)

        current = followed(trajectory, self._start_s)
        taken_over = None
        if self._taken_over is not None:
            taken_over = followed(*self._taken_over)
            if taken_over is None:  # replaced before a tick took it
                taken_over = Followed(TrajectoryReference(self._taken_over[0]), self._taken_over[1])
                taken_over = taken_over if before is None else self._continuing(taken_over, before, sim_time_s)
        if current is None:  # from rest unless it took over one still running when commanded (one that had ended since
            # the last tick: from rest; taken as moving, a first segment that holds had its velocity extrapolated back)
            current = Followed(TrajectoryReference(trajectory, from_rest=before is None or not self._took_over), self._start_s)
            if taken_over is not None:
                handover_s = current.handover_s()
                current = current.continuing(taken_over, taken_over.position(handover_s), handover_s)
            elif before is not None:
                current = self._continuing(current, before, sim_time_s)
        return current, taken_over

    @staticmethod
    def _continuing(new: Followed, servo: tuple[Followed, Followed | None], sim_time_s: float) -> Followed:
        """`new` going on at sim_time_s from the references of the servos following `servo`."""
        before = followed_at(*servo, sim_time_s)
        return new.continuing(before, before.position(sim_time_s), sim_time_s)

    def _feed(self, sim_time_s: float) -> np.ndarray:
        """Under the lock: the ideal servos' references for the physics step starting at sim_time_s (servo_reference),
        and the acceleration fed forward: the change from the velocity reference of the step before to this one's over
        a step, the velocity change the integrator must make (the instantaneous acceleration was up to one 10 ms
        sample's change early or late at a sample's corner). Returns the position reference."""
        followed, taken_over = self._servo
        timestep_s = self._cell.timestep_s
        position, velocity = servo_reference(followed, taken_over, sim_time_s, timestep_s)
        accel = (velocity - self._cell.arm_reference_velocity()) / timestep_s
        self._cell.apply_arm_reference(position, velocity, accel)
        return position

