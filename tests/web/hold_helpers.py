"""Helpers of the hold-to-run page tests: ground truth of the simulated arm (sim time, joints), the deadman's
stopping bound from the station's own limits, and a held jog button in a page."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from browser_helpers import ready_idle

START_RAD = [-1.0, 0.0, 0.0, 0.0, 0.0]  # waist turned right: a + waist jog sweeps over the board, away from limits
CRUISE_TRAVEL_RAD = 0.4  # held this far before the event: longer than one hold could carry it without heartbeats
SERVO_LAG_RAD = 0.01  # the simulated servo trails its reference a little; it catches up after the stop


@dataclass
class Truth:
    time_s: float
    q_rad: np.ndarray


def truth(server) -> Truth:
    t = server.get("/api/sim/truth")
    return Truth(float(t["time_s"]), np.asarray(t["arm"]["position_rad"], dtype=float))


def wait_truth(server, predicate, timeout_s: float, what: str, page=None) -> Truth:
    """Poll the ground truth until predicate(truth) holds (a condition, not a sleep). With a page, the poll interval
    is spent in Playwright (page.wait_for_timeout), whose sync API runs the test's routes and websocket proxies only
    while it is called."""
    deadline = time.monotonic() + timeout_s
    current = truth(server)
    while not predicate(current):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}; last truth: t={current.time_s:.3f} q={current.q_rad.round(4)}")
        if page is not None:
            page.wait_for_timeout(50)
        else:
            time.sleep(0.05)
        current = truth(server)
    return current


@dataclass
class Limits:
    """The deadman's numbers: top jog speed at 100 %, hold after the last heartbeat, control period, braking accel."""

    top_rad_s: float
    hold_s: float
    control_period_s: float
    accel_rad_s2: float

    def stop_bound_rad(self, speed_rad_s: float, event_window_s: float) -> float:
        """How far the joint may still go after the truth read before an event: at speed until the event (somewhere in
        event_window_s of sim time), one control period plus the hold at speed, then braking v²/2a, plus the servo lag."""
        v = speed_rad_s
        return v * (event_window_s + self.control_period_s + self.hold_s) + v * v / (2 * self.accel_rad_s2) + SERVO_LAG_RAD


def station_limits(page) -> Limits:
    from armlab.devices.sim.config import load_sim_config
    from armlab.motion.blend import arm_limits
    from armlab.workcell import load_workcell_arm

    served = page.evaluate("window.armlab.holdJog.maxRadS")
    hold_s = page.evaluate("window.armlab.holdLimits && window.armlab.holdLimits.jog_hold_s")
    accel = float(arm_limits(load_workcell_arm("rx200_armlab")).accel_rad_s2[0])
    return Limits(float(served), float(hold_s), load_sim_config().physics.control_period_s, accel)


def to_start(server) -> Truth:
    ready_idle(server)
    server.post("/api/arm/joints?wait=true", {"q_rad": START_RAD, "moving_time_s": 1.0})
    ready_idle(server)
    return truth(server)


def hold_button_ready(page, selector: str = "[data-hold='0+']") -> None:
    page.wait_for_function(f"(() => {{ const b = document.querySelector(\"{selector}\"); return b && !b.disabled; }})()", timeout=15_000)


def held_until_cruising(server, start: Truth, speed_rad_s: float, what: str, page=None) -> tuple[Truth, float]:
    """Wait until the held jog has carried the waist CRUISE_TRAVEL_RAD (more than one hold without heartbeats could)
    and moves at (nearly) speed_rad_s between two truth reads: (the last read, the fastest speed seen between reads
    at least 0.05 s of sim time apart)."""
    samples = [start]

    def cruising(t: Truth) -> bool:
        previous = samples[-1]
        if t.time_s - previous.time_s < 0.05:
            return False
        samples.append(t)
        return t.q_rad[0] - start.q_rad[0] >= CRUISE_TRAVEL_RAD and speed_between(previous, t) >= 0.8 * speed_rad_s

    try:
        last = wait_truth(server, cruising, 20.0, f"the waist to move at {speed_rad_s:.2f} rad/s while {what}", page)
    except AssertionError as error:
        if page is None:
            raise
        log = page.evaluate("document.getElementById('event-log').innerText")
        hold = page.evaluate("[window.armlab.holdJog.lastStop, Boolean(window.armlab.holdJog.active), window.armlab.holdJog.resent]")
        raise AssertionError(f"{error}\npage log: {log}\nhold (last stop, active, jogs re-sent): {hold}") from None
    fastest = max(speed_between(a, b) for a, b in zip(samples, samples[1:]))
    return last, fastest


def speed_between(a: Truth, b: Truth) -> float:
    return float((b.q_rad[0] - a.q_rad[0]) / (b.time_s - a.time_s))


def stopped_after(server, event_before: Truth) -> tuple[Truth, Truth]:
    """Wait until the arm is still (status), then until 0.5 s more of sim time has passed; (stopped, later) truths."""
    server.wait_status(lambda s: not s["moving"], 20.0, "the arm to stop")
    stopped = truth(server)
    later = wait_truth(server, lambda t: t.time_s >= stopped.time_s + 0.5, 20.0, "0.5 s of sim time")
    return stopped, later


def mouse_down_on(page, selector: str) -> None:
    """Press the mouse button on the element (scrolled into view) and keep it pressed."""
    button = page.locator(selector)
    button.scroll_into_view_if_needed()
    box = button.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()


def report(what: str, v: float, before, after_event, stopped, bound: float) -> str:
    travel = stopped.q_rad[0] - before.q_rad[0]
    return (f"{what}: {v:.2f} rad/s, event window {after_event.time_s - before.time_s:.3f} s sim, travelled {travel:.3f} rad "
            f"after the last read before it, at rest {stopped.time_s - before.time_s:.3f} s sim after it; bound {bound:.3f} rad")


def assert_stopped(what, limits, v, before, after_event, stopped, later):
    """The waist's travel after the last truth read before an event is within the deadman's bound, and it stays still."""
    bound = limits.stop_bound_rad(v, after_event.time_s - before.time_s)
    message = report(what, v, before, after_event, stopped, bound)
    print(message)
    assert stopped.q_rad[0] - before.q_rad[0] <= bound, message
    assert abs(later.q_rad - stopped.q_rad).max() < 2e-3, f"{what}: the arm moved again after it stopped: {later.q_rad - stopped.q_rad}"
