"""The record an evaluation writes with its results, so a figure can be traced to what produced it: the git
commit of the code (and whether the work tree had uncommitted changes), a SHA-256 of the config files (every
file under the config folder, and the workcell's file when it lies elsewhere), the seeds, the realism the runs
reported, the job and level, the Python and MuJoCo versions, and when it started."""

from __future__ import annotations

import hashlib
import platform
import subprocess
from collections.abc import Sequence
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path

from armlab.config import config_dir, resolve_config_path
from armlab.errors import ConfigError
from armlab.workcell import DEFAULT_WORKCELL

RECORD_FORMAT = 1  # bump when a field changes meaning
REPO_ROOT = Path(__file__).resolve().parents[2]
CONFIG_SUFFIXES = (".yaml", ".yml", ".json")
GIT_TIMEOUT_S = 10.0


def git_state(root: Path = REPO_ROOT) -> dict:
    """{"commit": HEAD's hash, "dirty": tracked files changed since it} of the repository at root; both None
    when root is not a git work tree or git is missing (an installed copy)."""
    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=GIT_TIMEOUT_S)
        except (OSError, subprocess.TimeoutExpired):
            return None
        return done.stdout if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    if commit is None:
        return {"commit": None, "dirty": None}
    status = git("status", "--porcelain", "--untracked-files=no")
    return {"commit": commit.strip(), "dirty": None if status is None else bool(status.strip())}


def files_sha256(paths: Sequence[Path], root: Path) -> str:
    """SHA-256 over the files' paths relative to root (or absolute, outside it) and their bytes, in path order."""
    digest = hashlib.sha256()
    for path in sorted(set(paths)):
        try:
            name = path.relative_to(root).as_posix()
        except ValueError:
            name = path.as_posix()
        digest.update(name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def workcell_path(workcell: str | None) -> Path | None:
    """The workcell's file (None: the default workcell's name is resolved by the caller; unknown: None)."""
    try:
        return resolve_config_path(workcell, "workcells").resolve()
    except ConfigError:
        return None


def config_state(workcell: str | None, folder: Path | None = None) -> dict:
    """The config folder, how many files it holds, their SHA-256 (any change to any of them changes it) and the
    workcell file's own SHA-256."""
    folder = (folder or config_dir()).resolve()
    files = [path for path in folder.rglob("*") if path.is_file() and path.suffix in CONFIG_SUFFIXES]
    cell = workcell_path(workcell or DEFAULT_WORKCELL)
    if cell is not None and not cell.is_relative_to(folder):
        files.append(cell)
    return {"config_dir": str(folder), "config_files": len(files), "config_sha256": files_sha256(files, folder),
            "workcell": workcell or DEFAULT_WORKCELL, "workcell_file": None if cell is None else str(cell),
            "workcell_sha256": None if cell is None else hashlib.sha256(cell.read_bytes()).hexdigest()}


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def run_record(event: str, level: int | None, seeds: Sequence[int], *, workcell: str | None = None,
               realism_requested: str | None = None, runs: Sequence[dict] = (), arm_calibration: bool = True,
               started_utc: str | None = None, **extra) -> dict:
    """The record of an evaluation of (event, level) over `seeds`. realism: what the runs reported (one value,
    a sorted list when they differ, None when none reported one: every run crashed); realism_requested: the
    --realism given (None: config/sim.yaml's or $ARMLAB_REALISM). `extra` is added as given (e.g. until_ci)."""
    reported = sorted({run["realism"] for run in runs if run.get("realism")})
    return {
        "format": RECORD_FORMAT,
        "event": event, "level": level,
        "seeds": sorted(int(seed) for seed in seeds),
        "realism": reported[0] if len(reported) == 1 else (reported or None),
        "realism_requested": realism_requested,
        "arm_calibration": arm_calibration,
        "git": git_state(),
        **config_state(workcell),
        "python": platform.python_version(), "mujoco": _version("mujoco"), "numpy": _version("numpy"),
        "started_utc": started_utc or now_utc(),
        **extra,
    }


def seed_text(seeds: list[int]) -> str:
    """Seeds as ranges: [0, 1, 2, 5] -> "0-2,5"."""
    parts, start = [], 0
    for i in range(1, len(seeds) + 1):
        if i == len(seeds) or seeds[i] != seeds[i - 1] + 1:
            first, last = seeds[start], seeds[i - 1]
            parts.append(str(first) if first == last else f"{first}-{last}")
            start = i
    return ",".join(parts)


def now_utc() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
