"""Job history: each job's row from its start to its outcome, and the jobs a killed station left running."""

from __future__ import annotations

import json

from armlab.store.database import ROW_ERRORS, Database


class JobTables(Database):
    """The job_results table of the station's database."""

    def record_job(self, job: dict) -> None:
        """Insert or update a job's outcome (the dict of Job.to_dict())."""
        self._run(
            "INSERT INTO job_results (id, name, state, message, started_s, finished_s, result_json) VALUES (?, ?, ?, ?, ?, ?, ?) "
            "ON CONFLICT(id) DO UPDATE SET name = excluded.name, state = excluded.state, message = excluded.message, "
            "started_s = excluded.started_s, finished_s = excluded.finished_s, result_json = excluded.result_json",  # keeps a score
            (
                job["id"],
                job["name"],
                job["state"],
                job.get("message") or "",
                job["started_s"],
                job.get("finished_s"),
                json.dumps(job.get("result"), default=str),
            ),
        )

    def record_job_start(self, job: dict) -> None:
        """A job's row as it starts (state running), unless its outcome is already in: a station killed
        mid-job leaves this row, which mark_interrupted_jobs turns into 'interrupted' at the next start."""
        self._run(
            "INSERT OR IGNORE INTO job_results (id, name, state, message, started_s, finished_s, result_json) "
            "VALUES (?, ?, ?, ?, ?, NULL, 'null')",
            (job["id"], job["name"], job["state"], job.get("message") or "", job["started_s"]),
        )

    def mark_interrupted_jobs(self) -> int:
        """At start-up: jobs still 'running' were cut off by a kill, crash or power loss; they become
        'interrupted'. Returns how many."""
        rows = self._run(
            "UPDATE job_results SET state = 'interrupted', message = ? WHERE state = 'running' RETURNING id",
            ("the station stopped while this job ran (killed, crashed or lost power)",),
        )
        return len(rows)

    def job_results(self, limit: int = 50) -> list[dict]:
        """The newest job outcomes; damaged rows are logged and skipped."""
        rows = self._run(
            "SELECT id, name, state, message, started_s, finished_s, result_json FROM job_results "
            "ORDER BY started_s DESC LIMIT ?",
            (int(limit),),
            raw_text=True,
        )
        results = []
        for row in rows:
            try:
                text = [value.decode("utf-8") if isinstance(value, bytes) else value for value in row]
                results.append(
                    {
                        "id": text[0],
                        "name": text[1],
                        "state": text[2],
                        "message": text[3],
                        "started_s": float(text[4]),
                        "finished_s": None if text[5] is None else float(text[5]),
                        "result": json.loads(text[6]) if text[6] else None,
                    }
                )
            except ROW_ERRORS as error:
                self._skip(f"job result {row[0]!r}", error)
        return results
