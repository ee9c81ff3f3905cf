"""Memory between the runs of one process, and each run's own peak.

A study or a reproduction runs its cases one after another in one process.
After a run has returned, Python holds none of its objects, yet the process
keeps its pages: glibc's malloc keeps freed memory in its heaps (No. 2 to its
first crack at the default mesh, one rank: 4.2 GB resident after the run,
0.23 GB after :func:`release_memory`).  And petsc4py keeps a parallel
object that Python has let go as garbage of its communicator until
:func:`free_petsc_garbage` is called there (``run_scene`` does, on its
mesh's communicator).  That call also frees what a destroyed object's Python
context held (the low-rank solver's Python PC holds the MUMPS factor's KSP),
which PETSc's own cleanup loses: until it did, about the factor's size stayed
in use a rank after every run on two ranks (benchmarks/README.md, 2026-12-07).

``getrusage``'s peak is the process's since it started;
:func:`reset_peak_memory` restarts Linux's high-water mark so that
:func:`peak_memory_mb` gives the run's own peak.  Elsewhere the peak stays the
process's (``summary.json`` says which: ``peak_memory_scope``).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import resource
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

_STATUS = Path("/proc/self/status")
_CLEAR_REFS = Path("/proc/self/clear_refs")


def _libc() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name) if name else None
    except OSError:
        return None
    return libc if libc is not None and hasattr(libc, "malloc_trim") else None


def free_petsc_garbage(comm: MPI.Comm) -> None:
    """Destroy the PETSc objects on ``comm`` that Python has let go (collective).

    petsc4py does not destroy a parallel object when Python frees it (that
    would be a collective call at a rank's own moment): it keeps it as garbage
    of its communicator until this is called on every rank of it.  A run's
    solver lives on its mesh's communicator (a duplicate of the run's), so
    nothing else frees it.

    Destroying a garbage object can release Python objects holding others (a
    Python PC's context: the low-rank solver's holds the MUMPS factor's KSP and
    its matrix).  Released during ``PETSc.garbage_cleanup`` they would be lost:
    PETSc (3.22) files them in a fresh garbage table of the communicator, which
    the cleanup replaces by its own when it ends, so nothing destroys them.  The
    live wrappers are therefore held through each cleanup and released after it,
    and the cleanup repeats while that freed any (the ranks agree on it).
    """
    gc.collect()
    if comm.size == 1:  # petsc4py destroys an object of one process at once: no garbage
        PETSc.garbage_cleanup(comm)
        return
    held = _petsc_wrappers()  # (a scan of every object: 0.1-0.6 s, so only in parallel)
    while True:
        PETSc.garbage_cleanup(comm)
        count = len(held)
        held = []  # what only a destroyed object held goes to the garbage now
        gc.collect()
        held = _petsc_wrappers()
        if not comm.allreduce(len(held) < count, op=MPI.LOR):
            break


def _petsc_wrappers() -> list[PETSc.Object]:
    """Return the petsc4py objects Python holds (tracked by its collector)."""
    # type(), not isinstance(): a dead weak proxy among the objects would raise
    return [o for o in gc.get_objects() if issubclass(type(o), PETSc.Object)]


class _MallInfo2(ctypes.Structure):
    _fields_ = [
        (name, ctypes.c_size_t)
        for name in ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks",
                     "uordblks", "fordblks", "keepcost")
    ]  # fmt: skip


def heap_in_use_mb() -> float | None:
    """Heap in use by this process (MB): malloc's small blocks and mmapped ones (glibc).

    None where malloc has no ``mallinfo2``.
    """
    libc = _libc()
    if libc is None or not hasattr(libc, "mallinfo2"):
        return None
    libc.mallinfo2.restype = _MallInfo2
    info = libc.mallinfo2()
    return float(info.uordblks + info.hblkhd) / 2**20


def release_memory() -> bool:
    """Collect garbage and return the heap's free pages to the system (glibc).

    Returns whether the pages could be returned (False where malloc has no
    ``malloc_trim``).
    """
    gc.collect()
    libc = _libc()
    if libc is None:
        return False
    libc.malloc_trim(0)
    return True


def reset_peak_memory() -> bool:
    """Restart the process's resident-memory high-water mark at its present size.

    Linux only (``/proc/self/clear_refs``); returns whether it was restarted.
    """
    try:
        _CLEAR_REFS.write_text("5")
    except OSError:
        return False
    return True


def _own_peak_kb() -> float:
    try:
        for line in _STATUS.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1])
    except OSError:
        pass
    return float(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)  # kB on Linux


def peak_memory_mb(comm: MPI.Comm, op: MPI.Op = MPI.SUM) -> float:
    """Peak resident memory of the ranks (MB): their sum, or ``op`` over them (collective).

    Since the last :func:`reset_peak_memory` where it worked, else since the
    process started.
    """
    return float(comm.allreduce(_own_peak_kb(), op=op)) / 1024.0


__all__ = ["free_petsc_garbage", "peak_memory_mb", "release_memory", "reset_peak_memory"]
