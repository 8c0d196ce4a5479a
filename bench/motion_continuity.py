"""Motion continuity under replacement (issue 18 items 1, 2, 5), measured on the simulation's clock.

    .venv/bin/python bench/motion_continuity.py [--moves 200] [--changes 200] [--seed 0]

1. Replacements of running moves: a random move (goals near the shoulder and elbow limits half the time) is
   replaced while it runs, at a random moment, by another move, a pose move, a jog (with heartbeats) or home.
2. Speed changes during repeats: random 4-waypoint programs with the shoulder and elbow near their limits,
   repeated while the speed is changed (PATCH /api/jobs/current's station call) to a random 10..100 % at
   random moments.
3. The deadman: a hold-to-run jog at 25 / 50 / 100 % of the top jog speed, released after 1 s of heartbeats.

Figures, from the servo references and the measured joints at every control tick (SimWorkcell's joint
recording, armlab/motion/measure.py): peak acceleration of the command (second difference over 20 ms) and of
the measured joints (velocity difference over 20 ms) against the limit, the largest command step (change of
one tick's motion from the tick before; a planned-from-rest takeover shows up here), refusals, failed jobs,
and the jog's time and distance from the last heartbeat to rest against v*hold + v^2/2a. The command is the servos'
position reference: the integral of their velocity reference plus a blend that ends each trajectory on its last
sample (armlab/devices/sim/servo_reference.py). The measured joints follow it to ~0.01 %: the ideal servos feed the
commanded acceleration forward through the model's inverse dynamics (before, they overshot every change of it: a lone
trapezoid 1.14x, a jog ~1.4x, these replacements 1.49-1.73x) and follow the trajectory at every physics step with
references consistent with MuJoCo's integrator (updated only every 4 ms control tick and sampled at the step's start,
the servos corrected offsets that moved with every change of the commanded acceleration: 1.02-1.03x; a position
reference on the samples' straight lines: up to 1.0022x; open fingers resting on their stops: up to 1.0008x; a jog
handed over at a move's last sample, less than the lead ahead: 1.32x; a joint left creeping at a*h/2 after a braking
end: 1.0108x; a move sent after the last one ended but before the servos let go of it, taken as moving: the joint
driven back at 0.12 rad/s, a 0.5 mrad command step). What is left, the servos' tracking of a profile whose acceleration changes at once (a few 1e-4 of it),
is the planning margin's: plans take 0.99x of each joint's limit (armlab/motion/planning_limits.py); the figures here
are against the hardware limit. The station is synchronous: physics advances only in waits and in this script's steps, so wall-clock load does not
enter (part 2's moments come from a polling thread, so its runs vary).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402


def _pose(rng, model, near_limits: bool) -> np.ndarray:
    """A random joint vector; with near_limits the shoulder and elbow within 0.15 rad of a limit or near zero."""
    lower, upper = np.asarray(model.lower_rad), np.asarray(model.upper_rad)
    q = rng.uniform(lower * 0.6, upper * 0.6)
    if near_limits:
        for joint in (1, 2):
            q[joint] = rng.choice([lower[joint] + rng.uniform(0.01, 0.15), upper[joint] - rng.uniform(0.01, 0.15), rng.uniform(-0.5, 0.5)])
    return q


def _safe_pose(station, rng, near_limits: bool) -> np.ndarray:
    """A random pose that passes the station's check (limits, board, box, the arm against itself)."""
    while True:
        q = _pose(rng, station.model, near_limits)
        try:
            return station.check_pose(q)
        except ValueError:
            continue


def _settle(station, cell) -> None:
    if station.state.value != "idle":
        station.estop()
        station.reset()
    station.wait_motion(30.0)
    cell.step(0.05)


def replacements(station, cell, rng, count: int) -> dict:
    """Part 1: `count` running moves replaced at random moments."""
    from armlab.errors import ArmMoving
    from armlab.motion.measure import motion_figures

    accel = np.asarray(station.model.accel_limit_rad_s2, float)
    kinds = {"move": 0, "pose": 0, "jog": 0, "home": 0}
    refused_unsafe = refused_moving = 0
    worst_command = worst_measured = worst_step = 0.0
    worst_kind = None
    done = 0
    while done < count:
        _settle(station, cell)
        try:
            station.move_joints(_safe_pose(station, rng, near_limits=rng.random() < 0.5), wait=True)
        except ValueError:
            continue
        _settle(station, cell)
        try:
            station.move_joints(_safe_pose(station, rng, near_limits=rng.random() < 0.5))
        except ValueError:
            continue
        cell.step(float(rng.uniform(0.05, 1.0)))
        cell.start_joint_recording()
        cell.step(0.05)
        kind = str(rng.choice(list(kinds)))
        try:
            if kind == "move":
                station.move_joints(_safe_pose(station, rng, near_limits=rng.random() < 0.5))
            elif kind == "pose":
                station.move_to([rng.uniform(-0.3, 0.3), rng.uniform(0.1, 0.35), rng.uniform(0.03, 0.25)])
            elif kind == "jog":
                top = min(station.motion_config.jog_max_speed_rad_s, float(np.min(station.model.velocity_limit_rad_s)))
                station.jog(rng.uniform(-top, top, size=station.model.dof), source="bench")
                for _ in range(int(rng.integers(0, 8))):
                    cell.step(0.05)
                    station.heartbeat(source="bench")
            else:
                station.home()
        except ArmMoving:
            refused_moving += 1
        except ValueError:  # the target itself is unsafe or unreachable: refused, the move in progress goes on
            refused_unsafe += 1
        station.wait_motion(30.0)
        figures = motion_figures(cell.stop_joint_recording())
        command, measured = figures.ratio(accel)
        if command > worst_command:
            worst_kind = kind
        worst_command, worst_measured = max(worst_command, command), max(worst_measured, measured)
        worst_step = max(worst_step, float(figures.step_rad.max()))
        kinds[kind] += 1
        done += 1
    return {"replacements": done, "kinds": kinds, "refused_unsafe_target": refused_unsafe, "refused_while_moving": refused_moving,
            "peak_command_accel_x_limit": worst_command, "peak_measured_accel_x_limit": worst_measured,
            "largest_command_step_rad": worst_step, "worst_command_case": worst_kind}


def speed_changes(station, cell, rng, count: int) -> dict:
    """Part 2: speed changes during repeats of near-limit programs until `count` changes were sent."""
    from armlab import skills
    from armlab.motion.measure import motion_figures
    from armlab.store import Waypoint

    accel = np.asarray(station.model.accel_limit_rad_s2, float)
    sent = refused_at_request = jobs = failed = 0
    failures: list[str] = []
    worst_command = worst_measured = worst_step = 0.0
    deferred = 0
    while sent < count:
        _settle(station, cell)
        waypoints = [Waypoint(tuple(_safe_pose(station, rng, near_limits=True)), "release") for _ in range(4)]
        program = station.store.save_program(f"near the limits {jobs}", waypoints)
        try:
            job = skills.repeat(station, program.id, cycles=2, speed_percent=float(rng.integers(10, 101)))
        except ValueError:  # a path between the waypoints fails the check: refused up front, try another
            continue
        jobs += 1
        seq = station.events.last_seq
        cell.start_joint_recording()
        while not job.done:
            at = cell.sim_time_s + rng.uniform(0.05, 1.0)
            while cell.sim_time_s < at and not job.done:
                time.sleep(0.0005)
            if job.done:
                break
            try:
                station.set_job_speed(float(rng.integers(10, 101)))
            except ValueError:
                refused_at_request += 1
            except Exception:  # noqa: BLE001 - the job ended meanwhile (CommandRefused)
                break
            sent += 1
        job.wait(600)
        if job.state != "succeeded":
            failed += 1
            failures.append(job.message)
        deferred += sum(1 for event in station.events.since(seq) if "applies from the next stop" in str(event.get("message")))
        figures = motion_figures(cell.stop_joint_recording())
        command, measured = figures.ratio(accel)
        worst_command, worst_measured = max(worst_command, command), max(worst_measured, measured)
        worst_step = max(worst_step, float(figures.step_rad.max()))
    return {"speed_changes": sent, "jobs": jobs, "failed_jobs": failed, "failures": failures[:5],
            "refused_at_request": refused_at_request, "deferred_to_next_stop": deferred,
            "peak_command_accel_x_limit": worst_command, "peak_measured_accel_x_limit": worst_measured,
            "largest_command_step_rad": worst_step}


def deadman(station, cell) -> list[dict]:
    """Part 3: released jogs at 25 / 50 / 100 % of the top jog speed."""
    config = station.motion_config
    accel = float(station.model.accel_limit_rad_s2[0])
    top = min(config.jog_max_speed_rad_s, float(station.model.velocity_limit_rad_s[0]))
    rows = []
    for percent in (25, 50, 100):
        _settle(station, cell)
        station.move_joints([-1.5, 0.0, 0.0, 0.0, 0.0], wait=True)
        _settle(station, cell)
        speed = top * percent / 100.0
        station.jog([top, 0, 0, 0, 0], source="bench", speed_percent=percent)
        for _ in range(20):
            cell.step(0.05)
            station.heartbeat(source="bench")
        released_s, q_released = cell.sim_time_s, float(station.arm.reference_rad[0])
        measured_released = float(station.joints_rad()[0])
        cell.start_joint_recording()
        cell.step(1.5)
        trace = cell.stop_joint_recording()
        reference, times = trace["reference_rad"][:, 0], trace["time_s"]
        velocity = np.diff(reference) / np.diff(times)
        stopped = int(np.flatnonzero(np.abs(velocity) < 1e-6)[0])
        braking = int(np.flatnonzero(velocity < speed * (1 - 1e-3))[0])
        rows.append({
            "speed_percent": percent, "speed_rad_s": speed,
            "braking_starts_s": float(times[braking] - released_s), "stopped_after_s": float(times[stopped] - released_s),
            "command_distance_rad": float(reference[stopped] - q_released),
            "measured_distance_rad": float(np.max(trace["position_rad"][:, 0]) - measured_released),
            "bound_rad": speed * config.jog_hold_s + speed**2 / (2 * accel),
        })
    return rows


def main(argv: list[str] | None = None) -> int:
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.kinematics import load_arm
    from armlab.station.config import StationConfig
    from armlab.station.core import Station
    from armlab.store import Store

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=200, help="replacements of running moves")
    parser.add_argument("--changes", type=int, default=200, help="speed changes during repeats")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    config = StationConfig()
    model = load_arm(config.arm)
    rng = np.random.default_rng(args.seed)
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="armlab-bench-") as tmp, SimWorkcell(SimWorkcellConfig(realtime=False, seed=args.seed)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=model, config=config, store=Store(Path(tmp) / "bench.sqlite3"),
                          sim=cell, backend="sim", synchronous=True)
        station.start()
        try:
            sim0 = cell.sim_time_s
            moves = replacements(station, cell, rng, args.moves)
            print("1. replacements of running moves:", moves, flush=True)
            changes = speed_changes(station, cell, rng, args.changes)
            print("2. speed changes during repeats near the limits:", changes, flush=True)
            mc = station.motion_config
            print(f"3. released hold-to-run jog (jog_hold_s {mc.jog_hold_s:.2f} s, top {mc.jog_max_speed_rad_s:.2f} rad/s):")
            for row in deadman(station, cell):
                print("   {speed_percent:3d} % ({speed_rad_s:.2f} rad/s): brakes after {braking_starts_s:.3f} s, at rest after "
                      "{stopped_after_s:.3f} s, travels {command_distance_rad:.3f} rad commanded / {measured_distance_rad:.3f} rad "
                      "measured; bound v*hold + v^2/2a = {bound_rad:.3f} rad".format(**row))
            print(f"simulated {cell.sim_time_s - sim0:.1f} s in {time.monotonic() - started:.1f} s wall")
        finally:
            station.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
