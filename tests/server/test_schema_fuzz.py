"""The schema fuzz (tests/server/schema_fuzz_cases.py: schemathesis over the whole OpenAPI schema against a real
uvicorn server on the simulated station, issue 10 and issue 18 "must show") in a pytest process of its own.

Its cases come from a fixed seed, yet in the whole suite's process schemathesis's generator gave up on the programs'
recursive step tree ("InvalidSchema: Cannot generate an array with 1 demanded elements", PATCH /api/programs/{id},
in two fresh-clone runs out of two, every retry in the same process too), while the same module alone passed every
time (7 runs): what the suite's other tests leave in the process changes the generation. A process of its own gives
the same cases on every run. Its output (every failing case, the summary line) is shown when it fails. The
operations are split in SHARDS processes, each at least a third of the 1,000 calls."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

CASES = Path(__file__).with_name("schema_fuzz_cases.py")
SHARDS = 3  # each operation in one of them; side by side on a parallel suite's workers (tests/conftest.py: one unit each)
REPO = Path(__file__).resolve().parents[2]


@pytest.mark.long_first
@pytest.mark.timeout(1800)  # a shard ~40 s quiet; over 1,000 calls in all, each waiting for the station at rest
@pytest.mark.parametrize("shard", range(SHARDS))
def test_the_whole_schema_fuzz_passes_in_a_process_of_its_own(shard):
    env = dict(os.environ, ARMLAB_FUZZ_SHARD=f"{shard}/{SHARDS}")
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rA", "-p", "no:cacheprovider", "-s", str(CASES)],
        cwd=REPO, capture_output=True, text=True, timeout=1750, env=env,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, f"the schema fuzz's shard {shard} failed (exit {result.returncode}):\n{output[-12000:]}"
    summary = [line[line.index("schema fuzz:"):] for line in output.splitlines() if "schema fuzz:" in line]  # after -q's dots
    assert summary, f"the fuzz's summary test did not run:\n{output[-4000:]}"
    print(summary[0])


def test_the_shards_split_the_operations_between_them():
    """Every operation in exactly one shard: shards that each ran the whole schema tripled the fuzz's time."""
    import schema_fuzz_cases as cases

    everything = {result.ok().label for result in cases._load_schema().get_all_operations()}
    shards = [{result.ok().label for result in cases._shard(cases._load_schema(), f"{index}/{SHARDS}")[0].get_all_operations()}
              for index in range(SHARDS)]
    assert len(everything) > 50
    assert set().union(*shards) == everything
    assert sum(len(shard) for shard in shards) == len(everything), [len(shard) for shard in shards]
