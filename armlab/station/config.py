"""The station's configuration (config/station.yaml), validated by pydantic."""

from __future__ import annotations

from pathlib import Path

from pydantic import Field, field_validator

from armlab.config import StrictModel, config_dir, load_config


class SimStartConfig(StrictModel):
    """How `armlab serve` starts the simulation: its seed and an optional starting scene."""

    seed: int = 0
    event: str | None = None
    level: int = Field(1, ge=1, le=3)
    scene_seed: int = 0
    camera_fps: float = Field(30.0, gt=0.0, le=120.0)


class StationConfig(StrictModel):
    arm: str = "rx200"
    telemetry_rate_hz: float = Field(30.0, ge=20.0, le=200.0)
    perception_rate_hz: float = Field(5.0, gt=0.0, le=60.0)
    jpeg_quality: int = Field(80, ge=10, le=100)
    database_path: str = "var/armlab.sqlite3"
    restore_calibration: bool = False
    click_snap_radius_m: float = Field(0.03, gt=0.0, le=0.2)
    max_moving_time_s: float = Field(30.0, gt=0.0)
    default_block_height_m: float = Field(0.038, gt=0.0, le=0.2)
    gripper_settle_timeout_s: float = Field(2.5, gt=0.0, le=10.0)
    database_backups: int = Field(3, ge=0, le=50)
    allowed_hosts: tuple[str, ...] = ()
    camera_timeout_s: float = Field(2.0, gt=0.0, le=30.0)
    device_check_rate_hz: float = Field(10.0, ge=1.0, le=100.0)
    moving_speed_rad_s: float = Field(0.05, gt=0.0, le=1.0)
    close_timeout_s: float = Field(2.0, gt=0.0, le=30.0)
    sim: SimStartConfig = SimStartConfig()

    @field_validator("allowed_hosts")
    @classmethod
    def _host_names(cls, names: tuple[str, ...]) -> tuple[str, ...]:
        """Bare host names or IP addresses: no scheme, path or port (the Host check compares names)."""
        for name in names:
            if not name.strip() or any(char in name for char in "/ \t@") or name.count(":") == 1:
                raise ValueError(f"allowed_hosts: {name!r} is not a bare host name (no scheme, port or path)")
        return tuple(name.strip() for name in names)

    def database_file(self) -> Path:
        """database_path; a relative path is relative to the repository root."""
        path = Path(self.database_path)
        return path if path.is_absolute() else config_dir().parent / path


def load_station_config(path: str | Path | None = None) -> StationConfig:
    """config/station.yaml (or `path`); ConfigError naming the file and field when invalid."""
    return load_config(path or config_dir() / "station.yaml", StationConfig)
