"""Shared test set-up: MPI-aware markers, a shared temporary directory, teardown."""

from __future__ import annotations

import gc
import os
import sys
from pathlib import Path

import pytest
from mpi4py import MPI


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    size = MPI.COMM_WORLD.size
    skip_serial = pytest.mark.skip(reason="serial-only test: run without mpirun")
    skip_mpi = pytest.mark.skip(reason="needs two or more MPI ranks")
    for item in items:
        if "serial" in item.keywords and size > 1:
            item.add_marker(skip_serial)
        if "mpi" in item.keywords and size < 2:
            item.add_marker(skip_mpi)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo) -> object:
    """Under mpirun, a failure on one rank ends the whole run at once.

    The other ranks may be waiting in a collective that the failed rank will never
    reach (or they reach the next test's collectives out of step): without this,
    the run hangs instead of failing.  The failure is printed first, since the
    abort ends pytest before its summary.  ``HFCDEM_NO_ABORT=1`` turns it off.
    """
    outcome = yield
    report = outcome.get_result()  # type: ignore[attr-defined]
    comm = MPI.COMM_WORLD
    if report.failed and comm.size > 1 and os.environ.get("HFCDEM_NO_ABORT") != "1":
        sys.stdout.flush()
        sys.stderr.write(
            f"\n==== rank {comm.rank}: {item.nodeid} FAILED ({report.when}); "
            f"aborting all {comm.size} ranks ====\n{report.longreprtext}\n"
            f"==== rank {comm.rank}: MPI_Abort after {item.nodeid} ====\n"
        )
        sys.stderr.flush()
        comm.Abort(1)


@pytest.fixture(autouse=True)
def _collective_teardown():
    # DOLFINx/PETSc objects are freed collectively: collect on every rank together.
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()


@pytest.fixture
def comm() -> MPI.Comm:
    return MPI.COMM_WORLD


@pytest.fixture
def shared_tmp_path(tmp_path: Path) -> Path:
    """A temporary directory that is the same on every rank (rank 0's)."""
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))
