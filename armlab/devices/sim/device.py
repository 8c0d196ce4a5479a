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
    _last_reading = None  # the newest reading (_fresh_or_last), refreshed at every control tick too

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

    def _fresh_or_last(self, read):
        """read() under the workcell's lock when it is free, else the reading of the last control tick (at most one
        control period of simulated time old): a status or a waiting request never waits for a physics batch, which
        a CPU-starved physics thread may hold for tens of milliseconds. Devices refresh it in control()."""
        cell = self._cell
        if self._last_reading is None or cell.lock.acquire(blocking=False):
            if self._last_reading is None:
                cell.lock.acquire()
            try:
                self._last_reading = read()
            finally:
                cell.lock.release()
        return self._last_reading
