"""Shared test set-up: MPI-aware markers, a shared temporary directory, teardown."""

from __future__ import annotations

import gc
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
