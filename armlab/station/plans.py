"""Motion plans kept for "plan, then execute" (issue 22 item 2): a small, bounded, thread-safe store of the
trajectories the station planned without moving, keyed by id.

A plan remembers who made it (the controller), the joints it was planned from, what the world looked like
(`world`: the station's counters of motions, halts, scene, calibrations, held block and speed override when it
was made; planned_moves.py compares them) and whether it was executed. The store does no I/O and calls nothing
outside itself, so the station may use it under its own lock.
"""

from __future__ import annotations

import secrets
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PlanNotFound, PlanStale

PLAN_MEMORY = 16  # plans kept; a newer plan pushes the oldest out (its id is then unknown)
PLAN_LIFETIME_S = 300.0  # wall seconds a plan may be executed after it was made


@dataclass
class MovePlan:
    """One planned motion: the exact trajectory Execute sends (already paced at speed_percent); or a skill's steps
    (grab, drop), `trajectory` then their motions joined for showing and `start()` the job that runs exactly them."""

    plan_id: str
    command: str  # the station command it executes as (move_joints, move_to, home, sleep)
    controller: str | None
    trajectory: JointTrajectory
    measured_rad: np.ndarray  # the measured joints it was planned from
    gripper_command: str | None  # the gripper's last command (grasp/release) when it was made
    world: tuple  # the station's world snapshot when it was made (planned_moves.world_snapshot)
    speed_percent: float
    created_s: float = field(default_factory=time.time)
    lifetime_s: float = PLAN_LIFETIME_S
    executed: bool = False
    start: Callable[[], object] | None = None  # a skill's plan: starts its job with the planned steps (returns the Job)
    goal_rad: np.ndarray | None = None  # where the gripper acts (a skill's grasp or release); None: the trajectory's end
    steps: tuple[str, ...] = ()  # a skill's plan: its steps' names, in order

    @property
    def expires_s(self) -> float:
        return self.created_s + self.lifetime_s


def new_plan_id() -> str:
    return "plan-" + secrets.token_hex(6)


class PlanStore:
    """At most `capacity` plans by id, oldest pushed out first. Thread-safe (its own lock); no I/O."""

    def __init__(self, capacity: int = PLAN_MEMORY) -> None:
        self._capacity = int(capacity)
        self._plans: OrderedDict[str, MovePlan] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        with self._lock:
            return len(self._plans)

    def add(self, plan: MovePlan) -> MovePlan:
        with self._lock:
            self._plans[plan.plan_id] = plan
            while len(self._plans) > self._capacity:
                self._plans.popitem(last=False)
        return plan

    def get(self, plan_id: str) -> MovePlan:
        """The plan (PlanNotFound if unknown)."""
        with self._lock:
            plan = self._plans.get(plan_id)
        if plan is None:
            raise PlanNotFound(f"no plan {plan_id!r}: it was never made, was discarded, or newer plans pushed it out "
                               f"(the station keeps the last {self._capacity}); plan again")
        return plan

    def claim(self, plan_id: str) -> MovePlan:
        """Mark the plan executed (PlanStale 'executed' if it already was, PlanNotFound if unknown)."""
        with self._lock:
            plan = self._plans.get(plan_id)
            if plan is not None and not plan.executed:
                plan.executed = True
                return plan
        if plan is None:
            self.get(plan_id)  # raises PlanNotFound
        raise PlanStale(f"plan {plan_id!r} was executed already: plan again to move again", "executed")

    def unclaim(self, plan_id: str) -> None:
        """Undo claim() when the send was refused after all (nothing moved)."""
        with self._lock:
            plan = self._plans.get(plan_id)
            if plan is not None:
                plan.executed = False

    def discard(self, plan_id: str) -> MovePlan:
        """Forget the plan (PlanNotFound if unknown)."""
        with self._lock:
            plan = self._plans.pop(plan_id, None)
        if plan is None:
            self.get(plan_id)
        return plan
