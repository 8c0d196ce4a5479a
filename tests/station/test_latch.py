"""The latch on its own (armlab.station.latch.Latch), without a station or a simulation: the flag, the halt that stops
the arm and the gripper (or the arm alone) and never raises, the halt count a send compares, the hook that runs
before the devices stop, and the lost-device bookkeeping the device watch and reset use."""

from __future__ import annotations

from armlab.station.latch import Latch


class FakeDevice:
    """A device that records stop() calls into a shared log; `fails` makes stop() raise a device error."""

    def __init__(self, name: str, log: list, fails: bool = False) -> None:
        self.name, self.log, self.fails = name, log, fails

    def stop(self) -> None:
        self.log.append(f"{self.name}.stop")
        if self.fails:
            raise ConnectionError("unplugged")

    def __str__(self) -> str:
        return self.name


def make_latch(arm_fails: bool = False) -> tuple[Latch, list]:
    log: list = []
    latch = Latch(FakeDevice("arm", log, arm_fails), FakeDevice("gripper", log), on_halt=lambda: log.append("on_halt"))
    return latch, log


def test_the_flag_sets_and_clears():
    latch, _ = make_latch()
    assert not latch.is_set()
    latch.set()
    assert latch.is_set()
    latch.clear()
    assert not latch.is_set()


def test_a_halt_counts_then_forgets_the_motion_then_stops_arm_and_gripper():
    latch, log = make_latch()
    assert latch.halts == 0
    assert latch.halt_devices() == []
    assert log == ["on_halt", "arm.stop", "gripper.stop"]
    assert latch.halts == 1


def test_a_halt_of_the_arm_alone_leaves_the_gripper_holding():
    latch, log = make_latch()
    latch.halt_devices(gripper=False)
    assert log == ["on_halt", "arm.stop"]
    assert latch.halts == 1


def test_a_device_that_fails_to_stop_is_reported_and_the_other_still_stops():
    latch, log = make_latch(arm_fails=True)
    failures = latch.halt_devices()
    assert failures == ["arm: unplugged"]
    assert log == ["on_halt", "arm.stop", "gripper.stop"]


def test_the_halt_is_counted_before_the_devices_are_told_to_stop():
    """A send that compares the count after its device call must see a halt that is stopping the devices (motion.py _sending)."""
    seen, latches = [], []

    class CountingDevice:
        def stop(self) -> None:
            seen.append(latches[0].halts)

    latches.append(Latch(CountingDevice(), CountingDevice()))
    latches[0].halt_devices()
    assert seen == [1, 1]


def test_the_watch_report_tells_new_losses_and_recoveries():
    latch, _ = make_latch()
    assert latch.note_problems({"camera": "no frames"}) == ({"camera": "no frames"}, [])
    assert latch.note_problems({"camera": "no frames", "arm": "timeout"}) == ({"arm": "timeout"}, [])  # camera not new
    assert latch.note_problems({"arm": "timeout"}) == ({}, ["camera"])
    assert latch.lost() == {"arm": "timeout"}


def test_reset_forgets_the_lost_devices_and_its_own_look_adds_to_them():
    latch, _ = make_latch()
    latch.note_problems({"camera": "no frames"})
    latch.add_lost({"gripper": "timeout"})
    assert latch.lost() == {"camera": "no frames", "gripper": "timeout"}
    assert sorted(latch.forget_lost()) == ["camera", "gripper"]
    assert latch.lost() == {}


def test_lost_is_a_copy():
    latch, _ = make_latch()
    latch.note_problems({"camera": "no frames"})
    latch.lost()["arm"] = "edited by a reader"
    assert latch.lost() == {"camera": "no frames"}
