"""Scores an autonomous job run from the API in the simulation: simulated time from the job's start to
its end, the gripper path, and the judge's points for the final ground truth (the competition events
of DESIGN §7; the other jobs by their own scorers, armlab.tasks.scorers).

Server side only: the task and perception never see ground truth or the judge. A watcher thread
samples the true gripper point while the job runs (pick_stack's box rule needs the path) and scores
the run once, the moment the job ends.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Any

from armlab.station.jobs import Job, jsonable
from armlab.tasks.episode import _after_first_motion, score_run
from armlab.tasks.judge import EVENT_LIMITS_S
from armlab.tasks.scorers import SCORED_JOBS, score_job

log = logging.getLogger(__name__)

PATH_SAMPLE_PERIOD_S = 0.05  # 20 Hz of wall time; the served simulation runs in real time (§7 asks >= 10 Hz)
SCORE_WAIT_S = 5.0  # how long a reader waits for the score of a job that has just ended


@dataclass
class AutoRun:
    """One autonomous job on the simulation, watched until it ends and then judged."""

    job: Job
    name: str
    level: int | None
    params: dict
    cell: Any  # the SimWorkcell: sim_time_s, gripper_point_m(), truth()
    sim_start_s: float
    path: list[list[float]] = field(default_factory=list)  # rows [sim time s, x, y, z] of the gripper point
    workcell: str | None = None  # the station's workcell (its places, block tags and sizes); None = the default
    sim_end_s: float | None = None
    score: dict | None = None
    note: str = ""
    scored: threading.Event = field(default_factory=threading.Event)
    store: Any = None  # the station's Store: the score is kept with the job's row (History)

    def start(self) -> AutoRun:
        threading.Thread(target=self._watch, name=f"auto-score-{self.job.id}", daemon=True).start()
        return self

    def _sample(self) -> None:
        point = self.cell.gripper_point_m()
        self.path.append([float(self.cell.sim_time_s), *map(float, point)])

    def _watch(self) -> None:
        try:
            self._sample()
            while not self.job.wait(PATH_SAMPLE_PERIOD_S):
                self._sample()
            self.sim_end_s = float(self.cell.sim_time_s)
            self._sample()
            self.score, self.note = self._judge()
            if self.store is not None and self.score is not None:
                self.job.wait(SCORE_WAIT_S)
                self.store.record_job_score(self.job.id, self.score)
        except Exception as error:  # noqa: BLE001 - reported to whoever asks for the score
            log.exception("scoring the %s run failed", self.name)
            self.note = f"could not score the run: {type(error).__name__}: {error}"
        finally:
            self.scored.set()

    def _judge(self) -> tuple[dict | None, str]:
        if not is_scored(self.name):
            return None, f"'{self.name}' has no judge or scorer"

        truth = self.cell.truth()
        sim_time_s = self.sim_end_s - self.sim_start_s
        if self.name in EVENT_LIMITS_S:
            path = _after_first_motion(self.path)
            score = score_run(self.name, self.level, truth, sim_time_s, None if path is None else path.tolist(), self.workcell)
            return jsonable(score.to_dict()), ""
        score = score_job(self.name, truth, sim_time_s=sim_time_s, params=self.params, workcell=self.workcell)
        return jsonable(score.to_dict()), "not a competition event: scored by the job's own scorer, not the §7 judge"

    def to_dict(self, wait_s: float = 0.0) -> dict:
        """The AutoScoreResponse wire dict; waits up to wait_s for the score of a job that has ended."""
        if self.job.done and wait_s > 0:
            self.scored.wait(wait_s)
        final = self.scored.is_set()
        end_s = self.sim_end_s if final and self.sim_end_s is not None else float(self.cell.sim_time_s)
        note = self.note if final else "running: scored when the job ends"
        return {
            "job_id": self.job.id, "job": self.name, "level": self.level, "state": self.job.state, "final": final,
            "sim_time_s": round(end_s - self.sim_start_s, 3), "score": self.score if final else None, "note": note,
        }


def is_judged(name: str) -> bool:
    """A competition event of DESIGN §7: the judge scores it."""
    return name in EVENT_LIMITS_S


def is_scored(name: str) -> bool:
    """The simulation can score it: the judge, or the job's own scorer."""
    return is_judged(name) or name in SCORED_JOBS


def watch_run(job: Job, name: str, level: int | None, params: dict | None, cell: Any, sim_start_s: float,
              workcell: str | None = None, store: Any = None) -> AutoRun:
    """Start watching `job` (begun at simulated time sim_start_s on `cell`, the station's `workcell`) to score
    it when it ends."""
    return AutoRun(job, name, level, dict(params or {}), cell, sim_start_s, workcell=workcell, store=store).start()
