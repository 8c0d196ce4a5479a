"""The layering and the lint, as checks of the suite: import-linter's contracts ([tool.importlinter] in
pyproject.toml: the layers, no backend below the station's factory, no cycle inside a package), ruff
([tool.ruff]), every armlab module placed in a layer, no function-level armlab/server import outside
the allowlist below, and the server importable without MuJoCo."""

from __future__ import annotations

import ast
import os
import pkgutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import armlab

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent  # the tools come with the test extras, next to the interpreter

# Function-level imports of armlab/server modules that stay: file (or folder/) -> (module prefixes, why).
# Anything else belongs at the module's top; an import cycle is broken by moving the shared piece down.
LAZY_IMPORTS = {
    "armlab/cli/": (("armlab", "server"), "the CLI registers every subcommand at start; a command's imports wait "
                    "for the command, so `armlab fk` never imports MuJoCo or FastAPI"),
    "armlab/station/factory.py": (("armlab.devices.sim",), "MuJoCo only when a simulated station is built"),
    "armlab/tasks/episode.py": (("armlab.devices.sim",), "MuJoCo only when an episode runs"),
    "server/routes/sim.py": (("armlab.devices.sim",), "MuJoCo only on the simulation's own route"),
}


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": str(ROOT)}


def _run(args: list[str]) -> subprocess.CompletedProcess:
    tool = BIN / args[0]
    if not tool.exists():
        pytest.fail(f"{tool} is missing: install the test extras (pip install -e '.[test]')")
    return subprocess.run([str(tool), *args[1:]], cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=300)


def test_import_contracts_hold():
    result = _run(["lint-imports", "--no-cache"])
    assert result.returncode == 0, f"lint-imports failed:\n{result.stdout}\n{result.stderr}"


def test_ruff_is_clean():
    result = _run(["ruff", "check", "--no-cache", "armlab", "server", "tests", "bench"])
    assert result.returncode == 0, f"ruff check failed:\n{result.stdout}\n{result.stderr}"


def _contracts() -> list[dict]:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]


def test_every_armlab_module_has_a_layer():
    (layers,) = [c["layers"] for c in _contracts() if c["type"] == "layers"]
    placed = {name.strip() for layer in layers for name in layer.replace(":", "|").split("|")}
    modules = {f"armlab.{m.name}" for m in pkgutil.iter_modules(armlab.__path__)}
    assert modules - placed == set(), "armlab modules missing from the layers contract in pyproject.toml"
    assert placed - modules - {"server"} == set(), "the layers contract names modules that do not exist"


def function_level_imports(root: Path) -> list[tuple[str, int, str]]:
    """(file, line, module) of every armlab/server import inside a function under root's armlab/ and server/."""
    found = []
    for path in sorted([*root.glob("armlab/**/*.py"), *root.glob("server/**/*.py")]):
        rel = path.relative_to(root).as_posix()

        def visit(node: ast.AST, in_function: bool) -> None:
            for child in ast.iter_child_nodes(node):
                if in_function and isinstance(child, ast.Import):
                    found.extend((rel, child.lineno, a.name) for a in child.names if a.name.split(".")[0] in ("armlab", "server"))
                elif in_function and isinstance(child, ast.ImportFrom):
                    module = "." * child.level + (child.module or "")
                    if child.level or module.split(".")[0] in ("armlab", "server"):
                        found.append((rel, child.lineno, module))
                visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

        visit(ast.parse(path.read_text(), rel), False)
    return found


def _allowed(rel: str, module: str) -> bool:
    for where, (prefixes, _why) in LAZY_IMPORTS.items():
        if rel == where or (where.endswith("/") and rel.startswith(where)):
            return any(module == p or module.startswith(p + ".") for p in prefixes)
    return False


def test_no_function_level_imports_outside_the_allowlist():
    stray = [f"{rel}:{line} imports {module}" for rel, line, module in function_level_imports(ROOT) if not _allowed(rel, module)]
    assert stray == [], "function-level imports (move them to the module's top, or to LAZY_IMPORTS with a reason):\n" + "\n".join(stray)


def test_function_level_import_finder_finds_one(tmp_path):
    """The finder above sees an import in a method, and not one at module level or under TYPE_CHECKING."""
    (tmp_path / "armlab").mkdir()
    (tmp_path / "armlab" / "m.py").write_text(
        "from typing import TYPE_CHECKING\nimport armlab.errors\nif TYPE_CHECKING:\n    from armlab.store import Store\n"
        "class C:\n    def f(self):\n        from armlab.workcell import Workcell\n        return Workcell\n")
    assert function_level_imports(tmp_path) == [("armlab/m.py", 7, "armlab.workcell")]


def test_the_server_imports_without_mujoco():
    """A station on the real arm never loads the simulator: the lazy imports above keep MuJoCo out of the server."""
    code = ("import sys, server.app, armlab.station.factory, armlab.tasks.evaluate, armlab.skills.side_grasp\n"
            "print(sorted(m for m in sys.modules if m == 'mujoco' or m.startswith('armlab.devices.sim')))")
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"
