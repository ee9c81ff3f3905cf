"""The parallel suite fails, never hangs, when a test fails on one rank only."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).parent


@pytest.mark.serial
@pytest.mark.skipif(shutil.which("mpirun") is None, reason="needs mpirun")
def test_a_failure_on_one_rank_ends_the_parallel_run():
    # a clean environment: this process may itself be an MPI singleton
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_COMM", "PMIX_"))}
    env.pop("HFCDEM_NO_ABORT", None)
    cmd = ["mpirun", "-n", "2", sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"]
    cmd += [str(HERE / "mpi_cases" / "case_one_rank_fails.py")]
    try:
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.fail("the two-rank run hung after a failure on rank 1")
    out = done.stdout + done.stderr
    assert done.returncode != 0
    assert "rank 1: " in out and "aborting all 2 ranks" in out, out[-3000:]
    assert "passed" not in out  # the run ended at the failure, not at the end
