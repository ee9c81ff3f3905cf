"""Memory between runs of one process: freed heap handed back, each run's own peak."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.workflows.memory import peak_memory_mb, release_memory, reset_peak_memory

linux = pytest.mark.skipif(
    not sys.platform.startswith("linux") or not Path("/proc/self/clear_refs").exists(),
    reason="the high-water mark is restarted through /proc/self/clear_refs (Linux)",
)


def _resident_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return float(line.split()[1]) / 1024.0
    raise AssertionError("no VmRSS")


@linux
def test_peak_is_the_runs_own_after_a_reset() -> None:
    comm = MPI.COMM_SELF
    big = np.ones(200 * 2**20 // 8)  # 200 MB, every page touched
    before = peak_memory_mb(comm)
    del big
    release_memory()
    assert reset_peak_memory()
    after = peak_memory_mb(comm)
    assert after < before - 150.0  # the 200 MB are no longer in the mark
    assert after < _resident_mb() + 50.0  # it restarted at the present size


@linux
def test_peaks_of_the_ranks_are_summed_and_maxed() -> None:
    comm = MPI.COMM_WORLD
    reset_peak_memory()
    # read one after another: the mark may grow by a few pages between the reads
    total, largest = peak_memory_mb(comm), peak_memory_mb(comm, MPI.MAX)
    mine = peak_memory_mb(MPI.COMM_SELF)
    assert largest >= mine - 1.0 > 0.0
    assert total == pytest.approx(comm.allreduce(mine), rel=0.05)
    assert total >= largest - 1.0
    if comm.size == 1:
        assert total == pytest.approx(largest, abs=1.0)


@linux
def test_release_hands_back_a_fragmented_heap() -> None:
    # 64 kB blocks sit in malloc's heap (below its mmap threshold); freeing all but
    # the last leaves the heap's top in use, so only a trim returns the pages
    blocks = [np.ones(8192) for _ in range(4000)]  # 256 MB
    keep = blocks[-1]
    del blocks
    held = _resident_mb()
    assert release_memory()
    assert _resident_mb() < held - 150.0
    assert keep.sum() == 8192.0
