"""SimDevice: the connection plumbing every simulated device shares (arm, grippers, camera).

A simulated device lives inside a SimWorkcell: connecting only marks it usable (the workcell owns the
physics), and every command first checks the mark. Mix it in before the device's interface class
(`class SimGripper(SimDevice, Gripper)`) so its connect/close/is_connected stand for the abstract ones;
a device with more to do on connect overrides _on_connect(); on close, close() calling super()."""

from __future__ import annotations

from armlab.errors import DeviceAlreadyConnectedError, DeviceLost, DeviceNotConnectedError


class SimDevice:
    """connect()/close()/is_connected and the not-connected guard for a device owned by a SimWorkcell."""

    _connected = False

    @property
    def is_connected(self) -> bool:
        return self._connected

    def connect(self) -> None:
        if self._connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        self._on_connect()
        self._connected = True

    def _on_connect(self) -> None:
        """What the device does when connected, before it is marked connected (nothing by default)."""

    def close(self) -> None:
        self._connected = False

    def _require(self) -> None:
        """DeviceNotConnectedError unless connected, DeviceLost once the simulation's physics thread died (every
        command and read calls this first)."""
        if not self._connected:
            raise DeviceNotConnectedError(f"{self} is not connected: call connect() (or SimWorkcell.start()) first")
        fault = getattr(getattr(self, "_cell", None), "physics_fault", None)
        if fault is not None:
            raise DeviceLost(f"{self}: the simulation's physics stopped ({fault}); restart the station")
