"""The control lease on its own (armlab.station.lease.ControlLease), without a station: a free lease goes to the first
controller that commands, anyone else is refused naming the holder until it is released or taken over, in-process
callers (source None) are never refused, a take-over is announced to everyone and refused while shutting down."""

from __future__ import annotations

import pytest

from armlab.errors import InvalidInput, NotController, ShuttingDown
from armlab.station.lease import ControlLease


class Events:
    def __init__(self) -> None:
        self.items: list[tuple[str, str]] = []

    def add(self, level: str, message: str) -> None:
        self.items.append((level, message))


def test_a_free_lease_goes_to_the_first_controller_that_commands():
    events = Events()
    lease = ControlLease(events)
    assert lease.holder is None and lease.to_dict() == {"controller": None, "since_s": None}
    assert lease.require("page-1", "move") is True
    assert lease.holder == "page-1" and lease.to_dict()["since_s"] is not None
    assert lease.require("page-1", "move") is False  # already its own
    assert events.items == [("info", "control taken by 'page-1' (the lease was free)")]


def test_anyone_else_is_refused_naming_the_holder_and_checking_takes_nothing():
    lease = ControlLease(Events())
    lease.check("page-2", "move")  # free: allowed, not taken
    assert lease.holder is None
    lease.require("page-1", "move")
    for ask in (lease.check, lease.require):
        with pytest.raises(NotController, match="page-1"):
            ask("page-2", "home")
    assert lease.holder == "page-1"


def test_in_process_callers_are_never_refused_and_never_hold_it():
    lease = ControlLease(Events())
    lease.require("page-1", "move")
    lease.check(None, "move")
    assert lease.require(None, "move") is False and lease.holder == "page-1"


def test_release_only_by_the_holder():
    events = Events()
    lease = ControlLease(events)
    lease.require("page-1", "move")
    assert lease.release("page-2") is False and lease.holder == "page-1"
    assert lease.release("page-1", "disconnected") is True and lease.holder is None
    assert events.items[-1] == ("info", "control disconnected: 'page-1' no longer controls the station")
    assert lease.release(None) is False


def test_a_take_over_is_announced_and_returns_the_previous_holder():
    events = Events()
    lease = ControlLease(events)
    lease.require("page-1", "move")
    assert lease.take("script") == "page-1" and lease.holder == "script"
    assert events.items[-1] == ("warn", "control taken by 'script' from 'page-1'")
    assert lease.take("script") == "script" and len(events.items) == 2  # taking one's own lease says nothing
    with pytest.raises(InvalidInput):
        lease.take("no spaces allowed")
    assert lease.holder == "script"


def test_no_take_over_while_shutting_down():
    closing = [False]
    lease = ControlLease(Events(), lambda: closing[0])
    closing[0] = True
    with pytest.raises(ShuttingDown):
        lease.take("page-1")
    assert lease.holder is None
