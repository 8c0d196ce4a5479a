"""The Station on the real-time simulation: transition table, e-stop latching, reset, click-grab/drop.

One simulated workcell and one station serve the whole module (started once); each test leaves the
station idle. Ground truth comes from the sim, never from the station's perception.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "server"))
import live  # noqa: E402
from armlab import skills  # noqa: E402
from armlab.errors import CommandRefused  # noqa: E402
from armlab.scene import Scene  # noqa: E402
from armlab.station import COMMANDS, State, allowed_commands  # noqa: E402
from armlab.station.states import JOB_STATES, TRANSITIONS  # noqa: E402

JOB_COMMAND = {State.CALIBRATE: "calibrate", State.REPEAT: "repeat", State.CLICK_GRAB: "grab", State.CLICK_DROP: "drop", State.AUTO_SORT: "auto"}
FAR_Q = np.array([0.8, 0.3, 0.2, 0.4, 0.5])
# A halted arm settles by a few mrad under gravity; a move that kept going would travel ~0.1 rad or more.
HALT_TOL_RAD = 5e-3


@pytest.fixture(scope="module")
def cell():
    cell = live.start_cell(seed=3, time_scale=live.FAST_TIME_SCALE)
    yield cell
    cell.close()


@pytest.fixture(scope="module")
def station(cell, tmp_path_factory):
    station = live.make_station(cell, tmp_path_factory.mktemp("db") / "station.sqlite3")
    yield station
    station.close()


@pytest.fixture()
def idle(station):
    """The station idle at home, not moving, gripper open (restored after each test)."""
    _back_to_idle(station)
    station.move_joints(station.model.home_rad, moving_time_s=0.5, wait=True)
    yield station
    _back_to_idle(station)


def _back_to_idle(station) -> None:
    job = station.current_job()
    if station.state not in (State.IDLE,):
        station.estop()
        station.reset()
    if job is not None:
        job.wait(10)
    live.wait_for(lambda: not station.arm.is_moving(), 10)


def _joints(station) -> np.ndarray:
    return np.asarray(station.arm.read_joint_state().position_rad, dtype=float)


def _enter(station, state: State, program_id: int):
    """Put the station in `state` through its public commands; job states run a job that waits for cancel."""
    if state is State.TEACH:
        station.teach.start()
    elif state is State.ESTOP:
        station.estop()
    elif state is State.FAULT:
        def broken(ctx):
            raise ConnectionError("servo bus lost")

        station.start_job("auto", "broken", broken).wait(5)
    elif state in JOB_STATES:
        station.start_job(JOB_COMMAND[state], f"hold-{state.value}", lambda ctx: ctx.sleep(60))
    assert station.state is state


def _issue(station, command: str, program_id: int):
    """Issue `command` with valid arguments through the station's public API."""
    calls = {
        "estop": lambda: station.estop(),
        "reset": lambda: station.reset(),
        "home": lambda: station.home(moving_time_s=1.0),
        "sleep": lambda: station.sleep(moving_time_s=1.0),
        "move_joints": lambda: station.move_joints(FAR_Q, moving_time_s=1.0),
        "move_to": lambda: station.move_to([0.0, 0.3, 0.15]),
        "jog": lambda: station.jog([0.2, 0.0, 0.0, 0.0, 0.0]),
        "torque": lambda: station.set_torque(True),
        "gripper": lambda: station.gripper_command("release", wait=False),
        "calibrate": lambda: skills.calibrate(station),
        "grab": lambda: skills.grab(station, position_m=[0.0, 0.3, 0.03]),
        "drop": lambda: skills.drop(station, position_m=[0.0, 0.3, 0.0]),
        "teach_start": lambda: station.teach.start(),
        "teach_record": lambda: station.teach.record(),
        "teach_stop": lambda: station.teach.stop("never saved"),
        "repeat": lambda: skills.repeat(station, program_id),
        "auto": lambda: station.start_job("auto", "noop", lambda ctx: None),
        "cancel": lambda: station.cancel_job(),
        "set_scene": lambda: station.allowed_or_raise("set_scene"),
        "teach_undo": lambda: station.teach.undo(),
        "pause": lambda: station.pause_job(),
        "resume": lambda: station.resume_job(),
        "step": lambda: station.step_job(),
        "set_speed": lambda: station.set_job_speed(50),
    }
    assert set(calls) == set(COMMANDS)
    return calls[command]()


def test_table_covers_every_state_and_estop_is_always_allowed():
    assert set(TRANSITIONS) == set(State)
    for state in State:
        assert "estop" in allowed_commands(state)
        assert TRANSITIONS[state]["estop"] is State.ESTOP
    assert allowed_commands(State.ESTOP) == ["estop", "reset"]


@pytest.mark.parametrize("state", list(State), ids=lambda s: s.value)
def test_every_disallowed_command_is_refused_naming_the_allowed_ones(idle, state):
    station = idle
    program = station.store.save_program("p", [live_waypoint(station)])
    _enter(station, state, program.id)
    q_before = _joints(station)
    expected_allowed = allowed_commands(state)
    refused = [command for command in COMMANDS if command not in expected_allowed]
    assert refused, "every state refuses something"
    for command in refused:
        with pytest.raises(CommandRefused) as caught:
            _issue(station, command, program.id)
        assert caught.value.allowed == expected_allowed
        assert caught.value.state == state.value
        assert command in str(caught.value) and "allowed: " + ", ".join(expected_allowed) in str(caught.value)
        assert station.state is state, f"refused '{command}' changed the state"
    live.wait_sim(station.sim, 0.05)
    assert np.allclose(_joints(station), q_before, atol=2e-3), "a refused command moved the arm"


def live_waypoint(station):
    from armlab.store import Waypoint

    return Waypoint(tuple(float(v) for v in station.model.home_rad), "release")


def _start_motion(station, state: State):
    """Get the arm moving in `state` (a long move) — through a job in job states."""
    if state in (State.IDLE, State.TEACH):
        if state is State.TEACH:
            station.teach.start()
        station.move_joints(FAR_Q, moving_time_s=3.0)
    else:
        station.start_job(JOB_COMMAND[state], "long move", lambda ctx: station.move_in_job(ctx, FAR_Q, moving_time_s=3.0))
    live.wait_for(lambda: np.linalg.norm(station.arm.read_joint_state().velocity_rad_s) > 0.05, 5)
    assert station.state is state


@pytest.mark.parametrize("state", [s for s in State if s not in (State.ESTOP, State.FAULT)], ids=lambda s: s.value)
def test_estop_halts_motion_within_a_control_period_and_latches(idle, cell, state):
    station = idle
    _start_motion(station, state)
    t_stop_s = cell.sim_time_s
    station.estop()
    # The halt, in simulated time (applied by the next control tick when the workcell's lock was busy).
    live.wait_for(lambda: cell.arm.last_halt_sim_s[1] >= t_stop_s, 5, 0.001)
    requested_s, applied_s = cell.arm.last_halt_sim_s
    assert applied_s - requested_s <= cell.control_period_s + 1e-9
    live.wait_sim(cell, 0.02)  # the arm's momentum
    q_halted = _joints(station)
    live.wait_sim(cell, 0.4)
    assert np.abs(_joints(station) - q_halted).max() < HALT_TOL_RAD, "the arm kept moving after e-stop"
    assert not station.arm.is_moving()
    assert station.state is State.ESTOP
    # Latched: motion commands are refused, the arm stays put, the job is over.
    for command in ("home", "move_joints", "grab", "teach_start"):
        with pytest.raises(CommandRefused):
            _issue(station, command, 1)
    job = station.current_job()
    if job is not None:
        assert job.wait(3) and job.state in ("cancelled", "failed")
    live.wait_sim(cell, 0.2)
    assert np.abs(_joints(station) - q_halted).max() < HALT_TOL_RAD
    # Reset returns to idle without moving the arm.
    station.reset()
    assert station.state is State.IDLE
    live.wait_sim(cell, 0.3)
    assert np.abs(_joints(station) - q_halted).max() < HALT_TOL_RAD, "reset moved the arm"


def test_estop_in_estop_and_fault_latches(idle):
    station = idle
    _enter(station, State.FAULT, 0)
    assert "servo bus lost" in station.status()["detail"]
    station.estop()
    station.estop()
    assert station.state is State.ESTOP
    station.reset()
    assert station.state is State.IDLE


def test_cancel_stops_the_job_and_returns_to_idle(idle, cell):
    station = idle
    _start_motion(station, State.REPEAT)
    job = station.cancel_job()
    assert station.state is State.IDLE
    assert job.wait(3) and job.state == "cancelled"
    live.wait_sim(cell, 0.05)
    q = _joints(station)
    live.wait_sim(cell, 0.3)
    assert np.abs(_joints(station) - q).max() < HALT_TOL_RAD


def test_bad_input_is_refused_and_nothing_moves(idle):
    from armlab.kinematics import Unreachable

    station = idle
    q_before = _joints(station)
    bad_calls = [
        (lambda: station.move_joints([0.0, float("nan"), 0, 0, 0]), "finite"),
        (lambda: station.move_joints([0.0, 0, 0, 0]), "5 values"),
        (lambda: station.move_joints([0.0, 3.0, 0, 0, 0]), "shoulder"),
        (lambda: station.move_joints([0.0] * 5, moving_time_s=-1), "moving_time_s"),
        (lambda: station.move_to([float("inf"), 0.2, 0.1]), "finite"),
        (lambda: skills.grab(station, position_m=[0.0, 0.3]), "position_m"),
        (lambda: station.gripper_command("squeeze"), "grasp"),
    ]
    for call, message in bad_calls:
        with pytest.raises(ValueError, match=message):
            call()
    with pytest.raises(Unreachable):
        station.move_to([0.0, 0.9, 0.1])
    with pytest.raises(Unreachable):
        skills.grab(station, position_m=[0.0, 1.2, 0.02])
    assert station.state is State.IDLE
    live.wait_sim(station.sim, 0.1)
    assert np.allclose(_joints(station), q_before, atol=2e-3)


def test_telemetry_is_published_continuously(idle):
    """A condition, not a rate: the rate is a figure of bench/soak.py (configured 30 Hz)."""
    station = idle
    _, v0 = station.telemetry.get()
    live.wait_for(lambda: station.telemetry.get()[1] >= v0 + 15, 10, 0.01)
    snapshot, _ = station.telemetry.get()
    assert snapshot["state"] == "idle" and len(snapshot["joints_rad"]) == 5 and "detections" in snapshot


def test_teach_record_stop_saves_a_program_that_repeats(idle):
    station = idle
    station.teach.start()
    station.move_joints([0.3, 0.0, 0.0, 0.0, 0.0], moving_time_s=0.6, wait=True)
    first, count = station.teach.record()
    assert count == 1
    station.move_joints([-0.3, 0.1, 0.0, 0.0, 0.0], moving_time_s=0.6, wait=True)
    assert station.teach.record()[1] == 2
    program = station.teach.stop("two points")
    assert station.state is State.IDLE
    assert [w.joints_rad for w in program.waypoints][0] == first.joints_rad
    station.move_joints(station.model.home_rad, moving_time_s=0.6, wait=True)
    job = skills.repeat(station, program.id, cycles=1)
    assert station.state is State.REPEAT
    assert job.wait(30) and job.state == "succeeded", job.message
    assert job.extra["repeat"]["waypoint"] == 2  # it reached the last waypoint, then went home (issue 9)
    assert np.allclose(_joints(station), station.model.home_rad, atol=0.02)
    assert station.state is State.IDLE


def test_click_grab_lifts_the_block_and_drop_places_it_within_10_mm(idle, cell):
    from armlab.vision import world_to_pixel

    station = idle
    cell.set_scene(
        Scene.from_dict(
            {
                "objects": [
                    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.08, 0.22, 0.019], "yaw_rad": 0.35},
                    {"id": "blue", "type": "block", "color": "blue", "size": "large", "position_m": [-0.12, 0.18, 0.019], "yaw_rad": -0.2},
                ]
            }
        )
    )
    job = skills.calibrate(station)
    assert job.wait(20) and job.state == "succeeded", job.message
    live.wait_for(lambda: len(station.detections().blocks) == 2, 10)
    truth = {o["id"]: o for o in cell.truth()["objects"]}
    z_start = truth["red"]["position_m"][2]
    # Click slightly off the block's centre: the station snaps to the detected block (centre, top, yaw).
    u, v = world_to_pixel(station.calibration, np.array([[0.088, 0.215, 0.038]]))[0]
    job = skills.grab(station, pixel=(u, v))
    assert station.state is State.CLICK_GRAB
    assert job.wait(60) and job.state == "succeeded", job.message
    assert job.result["block"]["color"] == "red"
    red = {o["id"]: o for o in cell.truth()["objects"]}["red"]
    assert red["position_m"][2] > z_start + 0.04, f"block not lifted: {red['position_m']}"
    assert station.gripper.read_state().holding
    # Drop onto the blue block: the station stacks on what is there.
    job = skills.drop(station, position_m=[-0.12, 0.18, 0.0])
    assert station.state is State.CLICK_DROP
    assert job.wait(60) and job.state == "succeeded", job.message
    live.wait_sim(cell, 0.5)  # the block settles
    objects = {o["id"]: o for o in cell.truth()["objects"]}
    red, blue = objects["red"], objects["blue"]
    assert np.hypot(red["position_m"][0] - blue["position_m"][0], red["position_m"][1] - blue["position_m"][1]) < 0.010
    assert red["position_m"][2] == pytest.approx(blue["position_m"][2] + 0.038, abs=0.006)
    # Grab it again and drop it by a click on the free board: within 10 mm of the clicked point.
    job = skills.grab(station, position_m=red["position_m"][:2] + [red["position_m"][2] + 0.019])
    assert job.wait(60) and job.state == "succeeded", job.message
    target = [0.15, 0.05, 0.0]
    u, v = world_to_pixel(station.calibration, np.array([target]))[0]
    job = skills.drop(station, pixel=(u, v))
    assert job.wait(60) and job.state == "succeeded", job.message
    live.wait_sim(cell, 0.5)  # the block settles
    red = {o["id"]: o for o in cell.truth()["objects"]}["red"]
    error_m = np.hypot(red["position_m"][0] - target[0], red["position_m"][1] - target[1])
    assert error_m < 0.010, f"dropped {error_m * 1000:.1f} mm from the target"
    assert red["position_m"][2] == pytest.approx(0.019, abs=0.004)
