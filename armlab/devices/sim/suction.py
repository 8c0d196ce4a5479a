"""SuctionGripper: the Gripper interface over the simulated vacuum cup (armlab.devices.sim.mjcf_dh).

grasp() turns the vacuum on, release() vents it. The vacuum only builds while the cup's lip seals on
one object: every lip point within the lip's compliance of that object's face (the workcell reads the
lip's contacts). Then MuJoCo's adhesion actuator pulls the object onto the cup with the configured
force, and friction at the lip carries it. A cup landing on an edge (part of the lip in the air),
tilted beyond what the lip conforms to, or off the block never seals: nothing is lifted. While
holding, a cup accelerating harder than the configured limit breaks the seal (latched until the next
grasp): the block swings off and falls. `holding` is the seal, read from the simulated contacts.
Like the finger gripper, control() runs under the workcell's lock at every control tick."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np

from armlab.devices.gripper import Gripper, GripperState
from armlab.devices.sim.device import SimDevice

if TYPE_CHECKING:
    from armlab.devices.sim.config import SuctionSimConfig
    from armlab.devices.sim.workcell import SimWorkcell


RAY_BACK_M = 0.01  # each lip point's ray starts this far behind it (outside a block even when pressed in)
MAX_PRESS_M = 0.005  # a face more than this far inside the lip plane is not a seal (something went through)
OBJECT_GROUP = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # rays see group 0: objects and the board


def seal_object(model, data, lip_geoms: dict[int, int], cup_body: int, body_to_object: dict[int, str],
                compliance_m: float, lip_margin_m: float) -> str | None:
    """The object whose face lies beneath every lip point along the cup's axis, no farther than compliance_m
    beyond the lip plane (the lip conforms that far), else None. A lip point over an edge or beside the
    block sees the board (or nothing) beneath it; a cup tilted too far leaves its far side out of reach."""
    import mujoco

    axis = data.xmat[cup_body].reshape(3, 3)[:, 0].copy()  # the approach axis (tool x)
    hit = np.zeros(1, dtype=np.int32)
    sealed_on = None
    for lip in lip_geoms:
        behind_plane = model.geom_size[lip][0] + 0.5 * lip_margin_m  # sphere centre -> lip plane along the axis
        origin = data.geom_xpos[lip] - RAY_BACK_M * axis
        distance = mujoco.mj_ray(model, data, origin, axis, OBJECT_GROUP, 1, -1, hit)
        obj_id = body_to_object.get(int(model.geom_bodyid[hit[0]])) if distance >= 0.0 else None
        gap = distance - RAY_BACK_M - behind_plane
        if obj_id is None or not -MAX_PRESS_M <= gap <= compliance_m or sealed_on not in (None, obj_id):
            return None
        sealed_on = obj_id
    return sealed_on


def lip_touching(model, data, lip_geoms: dict[int, int], body_to_object: dict[int, str]) -> list[str]:
    """Objects in contact with any lip sphere now (ground truth)."""
    touching = set()
    for contact in data.contact[: data.ncon]:
        for lip_geom, other_geom in ((contact.geom1, contact.geom2), (contact.geom2, contact.geom1)):
            if int(lip_geom) in lip_geoms:
                obj_id = body_to_object.get(int(model.geom_bodyid[other_geom]))
                if obj_id is not None:
                    touching.add(obj_id)
    return sorted(touching)


class SuctionGripper(SimDevice, Gripper):
    """The simulated vacuum suction cup. width_m is always 0 (a cup has no width)."""

    gripper_type = "suction"
    min_width_m = 0.0
    max_width_m = 0.0

    def __init__(self, cell: SimWorkcell, config: SuctionSimConfig, arm_name: str = "ur3") -> None:
        self._cell = cell
        self._config = config
        self._arm_name = arm_name
        self._command = "release"
        self._command_s = 0.0
        self._sealed_on: str | None = None  # the object id the lip seals on (vacuum on), else None
        self._seal_broken = False
        self._last_velocity: np.ndarray | None = None
        self._last_s = 0.0
        self._accel_m_s2 = np.zeros(3)  # low-passed cup acceleration (world, gravity excluded)
        self.seal_breaks = 0  # how many times a held object was lost to acceleration since start

    def __str__(self) -> str:
        return f"SuctionGripper({self._arm_name})"

    @property
    def command(self) -> str:
        """The last command: 'grasp' (vacuum on) or 'release' (vented)."""
        return self._command

    @property
    def holding_id(self) -> str | None:
        """The object the cup holds by vacuum now (sealed and vacuum on), else None."""
        return self._sealed_on

    @property
    def acceleration_m_s2(self) -> float:
        """Magnitude of the cup's low-passed acceleration (gravity excluded), m/s^2."""
        return float(np.linalg.norm(self._accel_m_s2))

    def _set_command(self, command: str) -> None:
        with self._cell.lock:
            self._command = command
            self._command_s = self._cell.sim_time_s
            self._seal_broken = False
            if command == "release":
                self._sealed_on = None
                self._cell.apply_suction(0.0)
            self._last_reading = self._measure()

    def grasp(self, wait: bool = True) -> None:
        """Vacuum on; with wait=True, block until the lip seals or settle_time_s passes (a miss)."""
        self._require()
        self._set_command("grasp")
        if wait:
            self._wait_settle(until=lambda: self._sealed_on is not None)

    def release(self, wait: bool = True) -> None:
        """Vent the cup; with wait=True, block settle_time_s (simulated) for the object to come free."""
        self._require()
        self._set_command("release")
        if wait:
            self._wait_settle()

    def _wait_settle(self, until=lambda: False) -> None:
        """Block until until() holds or settle_time_s of simulated time has passed since the last command."""
        start = self._command_s
        self._cell.wait_for(lambda: until() or self._cell.sim_time_s - start >= self._config.settle_time_s,
                            2.0 * self._config.settle_time_s + 1.0)

    def stop(self) -> None:
        """A cup has nothing to halt: the vacuum stays as commanded (dropping a held block is not a stop)."""
        self._require()

    def read_state(self) -> GripperState:
        """Now, or while the physics holds the workcell's lock the state at its last control tick (never waits)."""
        self._require()
        return self._fresh_or_last(self._measure)

    def _measure(self) -> GripperState:
        return GripperState(width_m=0.0, command=self._command, holding=self._sealed_on is not None, timestamp_s=time.time())

    def control(self, sim_time_s: float) -> None:
        """Seal, vacuum and the acceleration limit (called by the workcell under its lock every control tick)."""
        velocity = self._cell.cup_velocity_m_s()
        if self._last_velocity is not None and sim_time_s > self._last_s:
            dt = sim_time_s - self._last_s
            raw = (velocity - self._last_velocity) / dt
            self._accel_m_s2 += (raw - self._accel_m_s2) * (dt / (self._config.acceleration_filter_s + dt))
        self._last_velocity, self._last_s = velocity, sim_time_s
        sealed_on = self._cell.cup_seal_object() if self._command == "grasp" and not self._seal_broken else None
        if sealed_on is not None and self._sealed_on is not None and self.acceleration_m_s2 > self._config.max_acceleration_m_s2:
            self._seal_broken = True  # the inertial load peels the lip: air rushes in, the block is lost
            self.seal_breaks += 1
            sealed_on = None
        self._sealed_on = sealed_on
        self._cell.apply_suction(1.0 if sealed_on is not None else 0.0)
        self._last_reading = self._measure()
