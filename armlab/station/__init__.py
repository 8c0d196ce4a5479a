"""The control station: state machine, jobs, telemetry (see core.Station and DESIGN §6)."""

from armlab.station.config import StationConfig, load_station_config
from armlab.station.core import NotCalibrated, Station
from armlab.station.jobs import Job, JobCancelled, JobContext
from armlab.station.states import COMMANDS, TRANSITIONS, State, allowed_commands, next_state

__all__ = [
    "COMMANDS",
    "TRANSITIONS",
    "Job",
    "JobCancelled",
    "JobContext",
    "NotCalibrated",
    "State",
    "Station",
    "StationConfig",
    "allowed_commands",
    "load_station_config",
    "next_state",
]
