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


# Cartesian holds (the gripper point along a world axis) --------------------------------------------------------------

POINTING_DOWN_M = [0.0, 0.25, 0.12]  # over the board, the gripper straight down: x, y and z are open both ways
CARTESIAN_LAG_M = 0.003  # the simulated servos trail the command a little and catch up after the stop
OFF_AXIS_TOL_M = 0.003


@dataclass
class GripperTruth:
    time_s: float
    point_m: np.ndarray


def gripper_truth(server) -> GripperTruth:
    t = server.get("/api/sim/truth")
    return GripperTruth(float(t["time_s"]), np.asarray(t["gripper"]["position_m"], dtype=float))


def to_pointing_down(server) -> GripperTruth:
    """The idle arm with its gripper straight down at POINTING_DOWN_M (a pose move); its truth."""
    ready_idle(server)
    server.post("/api/arm/pose?wait=true", {"position_m": POINTING_DOWN_M, "pitch_rad": float(np.pi / 2), "yaw_rad": 0.0})
    ready_idle(server)
    return gripper_truth(server)


def cartesian_limits(page) -> tuple[float, float, float, float]:
    """(top speed m/s at 100 %, acceleration m/s², hold s, control period s): the station's, as the page got them."""
    from armlab.devices.sim.config import load_sim_config

    limits = page.evaluate("window.armlab.holdLimits")
    return (float(limits["jog_max_speed_m_s"]), float(limits["jog_accel_m_s2"]), float(limits["jog_hold_s"]),
            load_sim_config().physics.control_period_s)


def held_along(server, start: GripperTruth, axis: int, speed_m_s: float, page, travel_m: float = 0.03) -> tuple[GripperTruth, list]:
    """Wait until the held Cartesian jog has carried the gripper point travel_m along `axis` (0, 1, 2; + direction) and
    moves at (nearly) speed_m_s between two truth reads at least 0.05 s of sim time apart: (the last read, all reads)."""
    samples = [start]
    deadline = time.monotonic() + 20.0
    while True:
        page.wait_for_timeout(50)
        current = gripper_truth(server)
        previous = samples[-1]
        if current.time_s - previous.time_s < 0.05:
            continue
        samples.append(current)
        speed = (current.point_m[axis] - previous.point_m[axis]) / (current.time_s - previous.time_s)
        if current.point_m[axis] - start.point_m[axis] >= travel_m and speed >= 0.8 * speed_m_s:
            return current, samples
        if time.monotonic() > deadline:
            log = page.evaluate("document.getElementById('event-log').innerText")
            raise AssertionError(f"the gripper did not move along axis {axis} at {speed_m_s:.3f} m/s; last {current}; log: {log}")


def assert_cartesian_stop(what: str, page, server, axis: int, speed_m_s: float, start, samples, before, after_event) -> None:
    """After the event (truth `before` just before it, `after_event` just after): at rest within the deadman's bound
    v·(event window + one control period + hold) + v²/2a (+ the servos' lag) along the axis, still 0.5 s of sim time
    later, and the whole path on the axis' line (the other two coordinates kept within OFF_AXIS_TOL_M)."""
    top, accel, hold_s, period_s = cartesian_limits(page)
    server.wait_status(lambda s: not s["moving"], 20.0, "the arm to stop")
    stopped = gripper_truth(server)
    later_deadline = time.monotonic() + 20.0
    while (later := gripper_truth(server)).time_s < stopped.time_s + 0.5:
        assert time.monotonic() < later_deadline, "the simulation stalled"
        page.wait_for_timeout(50)
    window_s = after_event.time_s - before.time_s
    bound = speed_m_s * (window_s + period_s + hold_s) + speed_m_s**2 / (2 * accel) + CARTESIAN_LAG_M
    travel = stopped.point_m[axis] - before.point_m[axis]
    message = (f"{what}: {speed_m_s:.3f} m/s, event window {window_s:.3f} s sim, travelled {travel * 1000:.1f} mm after the last "
               f"read before it; bound {bound * 1000:.1f} mm")
    print(message)
    assert travel <= bound, message
    assert np.abs(later.point_m - stopped.point_m).max() < 1e-3, f"{what}: the gripper moved again after it stopped"
    others = [i for i in range(3) if i != axis]
    off = max(np.abs(t.point_m[others] - start.point_m[others]).max() for t in [*samples, stopped, later])
    assert off < OFF_AXIS_TOL_M, f"{what}: the gripper point left the line by {off * 1000:.1f} mm"


def open_counting_page(browser, url: str, **context_options):
    """A page at `url` (its own context) whose websocket messages to the station are collected in page.sent (parsed
    JSON text frames), and page errors in page.errors; the caller closes page.context."""
    import json

    context = browser.new_context(**({"viewport": {"width": 1600, "height": 1000}} | context_options))
    page = context.new_page()
    page.errors, page.sent = [], []
    page.on("pageerror", lambda error: page.errors.append(str(error)))

    def watch(ws) -> None:
        ws.on("framesent", lambda payload: page.sent.append(json.loads(payload)) if isinstance(payload, str) else None)

    page.on("websocket", watch)
    page.goto(url)
    return page
