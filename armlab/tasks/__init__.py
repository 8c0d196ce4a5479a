"""Autonomous jobs (the station's auto_sort state) and the competition judge.

`JOBS` names every job with its levels; `start_auto(station, job, level, params)` starts one as a
job on the gate. Imports go one way: armlab.tasks → armlab.skills → armlab.station.
"""

from armlab.tasks.registry import JOBS, JobSpec, start_auto

__all__ = ["JOBS", "JobSpec", "start_auto"]
