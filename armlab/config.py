"""Loading validated configuration from config/ (YAML or JSON) into pydantic models.

Every config model should derive from `StrictModel`: unknown fields and NaN/inf are errors, and
`load_config` turns pydantic's errors into one ConfigError naming the file and the field.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from armlab.errors import ConfigError

ModelT = TypeVar("ModelT", bound=BaseModel)


class StrictModel(BaseModel):
    """Base for config models: no unknown fields, no NaN or infinity, frozen after validation."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


def config_dir() -> Path:
    """The config/ folder: $ARMLAB_CONFIG_DIR if set, else the repository's config/."""
    override = os.environ.get("ARMLAB_CONFIG_DIR")
    return Path(override) if override else Path(__file__).resolve().parents[1] / "config"


def resolve_config_path(name_or_path: str | Path, subdir: str) -> Path:
    """A path as given if it exists, else config/<subdir>/<name>.yaml (e.g. ("rx200", "arms"))."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml", ".json") and path.exists():
        return path
    candidate = config_dir() / subdir / f"{name_or_path}.yaml"
    if candidate.exists():
        return candidate
    available = sorted(p.stem for p in (config_dir() / subdir).glob("*.yaml"))
    raise ConfigError(f"no config '{name_or_path}' in {config_dir() / subdir} (available: {', '.join(available)})")


def read_config_file(path: str | Path) -> dict:
    """Parse a YAML or JSON file into a dict; ConfigError if unreadable or not a mapping."""
    path = Path(path)
    try:
        text = path.read_text()
        data = json.loads(text) if path.suffix == ".json" else yaml.safe_load(text)
    except (OSError, yaml.YAMLError, json.JSONDecodeError) as error:
        raise ConfigError(f"{path}: cannot read config: {error}") from error
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level, got {type(data).__name__}")
    return data


def validate_config(data: dict, model: type[ModelT], source: str) -> ModelT:
    """Validate a dict against `model`; ConfigError naming `source` and each bad field."""
    try:
        return model.model_validate(data)
    except ValidationError as error:
        problems = "; ".join(
            f"{'.'.join(str(part) for part in item['loc']) or '<root>'}: {item['msg']}" for item in error.errors()
        )
        raise ConfigError(f"{source}: invalid config: {problems}") from error


def load_config(path: str | Path, model: type[ModelT]) -> ModelT:
    """Read and validate one config file."""
    return validate_config(read_config_file(path), model, str(path))
