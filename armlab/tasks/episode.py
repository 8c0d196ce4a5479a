"""One headless run of an autonomous job in the simulation's fast mode, scored by the judge.

Deterministic per (event, level, seed): the scene comes from the seed, the simulation steps only
while the job waits on the devices, and frames are rendered only when the job looks.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from armlab import skills
from armlab.recording import Recording
from armlab.recording.library import new_id
from armlab.scene import generate_scene
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.station.jobs import jsonable
from armlab.store import Store
from armlab.tasks.judge import EVENT_LIMITS_S, judge
from armlab.tasks.registry import checked_request, start_auto
from armlab.tasks.scorers import score_job
from armlab.workcell import load_workcell_arm

ARM_CALIBRATION_TIMEOUT_S = 600.0  # wall seconds for the arm's calibration (20 poses, ~24 s simulated)
CALIBRATION_TIMEOUT_S = 60.0
JOB_TIMEOUT_S = 1800.0  # wall time; a job that runs longer is cancelled and scored as it stands


def episode_scene(event: str, level: int | None, seed: int, workcell=None):
    """The starting scene of a headless run on `workcell` (None = the default): the event's generator;
    stack_here (no levels, no generator of its own) stacks pick_sort L2's six blocks."""
    if event == "stack_here":
        return generate_scene("pick_sort", level=2, seed=int(seed), workcell=workcell)
    return generate_scene(event, level=level, seed=int(seed), workcell=workcell)


def score_run(event: str, level: int | None, truth: dict, sim_time_s: float, gripper_path_m, workcell=None):
    """The judge's score for the competition events (DESIGN §7), armlab.tasks.scorers' for the others
    (on `workcell`: its places, block tags and sizes; None = the default)."""
    if event in EVENT_LIMITS_S:
        feeder = truth.get("feeder")
        available = None if not feeder else sum(o["size"] == "large" for o in truth["objects"]) + int(feeder.get("remaining", 0))
        return judge(event, level, truth, sim_time_s=sim_time_s, gripper_path_m=gripper_path_m,
                     workcell=None if workcell is None else getattr(workcell, "name", workcell),
                     **({"blocks_available": available} if event == "to_the_sky" and available else {}))
    return score_job(event, truth, sim_time_s=sim_time_s, workcell=workcell)


def run_episode(event: str, level: int | None, seed: int, *, keep_truth: bool = False, workcell: str | None = None,
                realism: str | None = None, arm_calibration: bool = True, record_dir: str | Path | None = None,
                pick_check: bool | None = None) -> dict:
    """Run job `event` at `level` on the scene of `seed` on `workcell` (config/workcells/<name>.yaml: its
    arm, gripper, board and scene; None = the default, the RX200); return the judged result as a
    JSON-ready dict: {event, level, seed, workcell, realism (the one that ran), points, max_points, sim_time_s, wall_time_s, breakdown,
    failures, full, within_limit} (+ truth with gripper_path_m when keep_truth). realism: real or ideal
    simulation (None: config/sim.yaml's). arm_calibration: on the real arm (a drawn rig), calibrate it from the
    camera after the camera and before the job's clock starts, as a team does before its run (False: skip).
    record_dir: record the run (calibrations and job) to <event>-L<level>-seed<seed>-<id>.mcap there (its path in the
    result's "recording"); the simulation runs in fast mode, so the recording samples it in wall time. pick_check: the
    closed loop before each pick's last descent (armlab.skills.pick_check) on or off; None: StationConfig's."""
    from armlab.devices.sim import (  # MuJoCo only when simulating (tests/test_layering.py)
        SimWorkcell,
        SimWorkcellConfig,
    )

    checked_request(event, level, None)
    wall_start = time.monotonic()
    config = StationConfig(**({} if workcell is None else {"workcell": workcell}),
                           **({} if pick_check is None else {"pick_check": pick_check}))
    with tempfile.TemporaryDirectory(prefix="armlab-eval-") as tmp, SimWorkcell(
        SimWorkcellConfig(realtime=False, seed=int(seed), workcell=config.workcell, realism=realism),
        scene=episode_scene(event, level, seed, config.workcell),
    ) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(config.workcell), config=config,
                          store=Store(Path(tmp) / "eval.sqlite3"), sim=cell, backend="sim", synchronous=True)
        station.start()
        recording = _start_recording(station, record_dir, event, level, seed)
        try:
            calibration = skills.calibrate(station)
            calibration.wait(CALIBRATION_TIMEOUT_S)
            if calibration.state != "succeeded":
                raise RuntimeError(f"calibration failed: {calibration.message}")
            if arm_calibration and cell.rig is not None:
                arm = skills.calibrate_arm(station)
                arm.wait(ARM_CALIBRATION_TIMEOUT_S)
                if arm.state != "succeeded":
                    raise RuntimeError(f"arm calibration failed: {arm.message}")
            sim_start = cell.sim_time_s
            recorder = getattr(cell, "start_path_recording", None)
            if recorder is not None:
                recorder()
            job = start_auto(station, event, level)
            if not job.wait(JOB_TIMEOUT_S):
                job.cancel()
                job.wait(60)
            sim_time_s = cell.sim_time_s - sim_start
            truth = cell.truth()
            path = cell.gripper_path() if hasattr(cell, "gripper_path") else None
        finally:
            if recording is not None:
                recording.stop("the run ended")
            station.close()
    gripper_path_m = None if path is None else [list(map(float, row[1:4])) for row in path]
    score = score_run(event, level, truth, sim_time_s, _after_first_motion(path), config.workcell)
    task = job.to_dict().get("extra", {}).get("task") or {}
    failures = list(task.get("failures", []))
    if job.state != "succeeded":
        failures.append(f"job {job.state}: {job.message}")
    result = {
        "event": event, "level": level, "seed": int(seed), "workcell": config.workcell, "realism": cell.realism,
        **{k: v for k, v in score.to_dict().items() if k != "breakdown"},
        "sim_time_s": round(sim_time_s, 3), "wall_time_s": round(time.monotonic() - wall_start, 3),
        "breakdown": score.to_dict()["breakdown"], "failures": failures,
        "pick_check": _pick_check_figures(job.result) if config.pick_check else None,
    }
    if recording is not None:
        result["recording"] = str(recording.path)
    if keep_truth:
        result["truth"] = {**jsonable(truth), "gripper_path_m": gripper_path_m}
    return result


def _pick_check_figures(result) -> dict:
    """The job result's pick_check summary without its per-pick records (armlab.skills.pick_check.pick_summary), and
    each pick's first look (mm) and how many were refused."""
    summary = (result or {}).get("pick_check") if isinstance(result, dict) else None
    if not summary:
        return {}
    first = [r["looks_mm"][0] for r in summary.get("records", []) if r.get("looks_mm")]
    return {**{k: v for k, v in summary.items() if k != "records"}, "first_looks_mm": first,
            "refused": sum(bool(r.get("refused")) for r in summary.get("records", []))}


def _start_recording(station: Station, record_dir, event: str, level: int | None, seed: int) -> Recording | None:
    if record_dir is None:
        return None
    folder = Path(record_dir)
    folder.mkdir(parents=True, exist_ok=True)
    name = f"{event}-L{level}-seed{int(seed)}-{new_id()}" if level is not None else f"{event}-seed{int(seed)}-{new_id()}"
    recording = Recording(station, folder / f"{name}.mcap", station.config.recording, label=f"eval {name}", source="eval")
    recording.start()
    return recording


def _after_first_motion(path):
    """The gripper path from the end of the job's first motion (the first time the point stops moving
    after it started), as (N, 3); None when not recorded."""
    if path is None or len(path) == 0:
        return None
    import numpy as np

    points = np.asarray(path, float)[:, 1:4]
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    moving = np.flatnonzero(steps > 1e-4)
    if moving.size == 0:
        return points
    first_start = moving[0]
    still_after = np.flatnonzero(steps[first_start:] <= 1e-4)
    return points[first_start + (still_after[0] if still_after.size else 0):]
