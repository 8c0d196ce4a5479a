"""The Gripper interface: a parallel two-finger gripper. Units: metres, seconds."""

from __future__ import annotations

import abc
from dataclasses import dataclass


@dataclass(frozen=True)
class GripperState:
    """width_m: measured span between the pad faces; command: last command ('grasp'|'release');
    holding: the gripper's evidence of an object: fingers driven closed that something stops short of fully
    closed (not fingers halted mid-stroke), or a suction cup's seal. The station's status and its jobs read it."""

    width_m: float
    command: str
    holding: bool
    timestamp_s: float


class Gripper(abc.ABC):
    """A parallel gripper. Same connect/close/error contract as Arm."""

    @abc.abstractmethod
    def connect(self) -> None: ...

    @abc.abstractmethod
    def close(self) -> None: ...

    @property
    @abc.abstractmethod
    def is_connected(self) -> bool: ...

    @abc.abstractmethod
    def grasp(self, wait: bool = True) -> None:
        """Close the fingers with the configured effort; with wait=True, block until they stop (≤ 2 s)."""

    @abc.abstractmethod
    def release(self, wait: bool = True) -> None:
        """Open the fingers fully; with wait=True, block until open (≤ 2 s)."""

    @abc.abstractmethod
    def read_state(self) -> GripperState: ...

    @abc.abstractmethod
    def stop(self) -> None:
        """Halt the fingers where they are; fingers closed on something (holding) keep squeezing it: an
        e-stop never drops what is held (a cup keeps its vacuum)."""
