"""What a run leaves in memory once it has returned, case after case in one process.

Runs a scene (No. 2 to its first crack by default) several times in one process
and prints, per rank, the resident memory and the heap in use (glibc's
``mallinfo2``) before, after ``run_scene`` returned and after
``release_memory``, with the PETSc objects created and not destroyed so far
(PETSc's log; rank 0's count).  Nothing of a run should stay in use: the heap in
use after a case should be that of the one before.

    make run CMD="mpirun -n 2 python3 benchmarks/memory_between_runs.py --cases 3"
"""

from __future__ import annotations

import argparse
import re
import shutil
import tempfile
import time
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.scene import load_scene
from hfcdem.workflows.memory import heap_in_use_mb, release_memory
from hfcdem.workflows.run import run_scene


def _gb() -> tuple[float, float]:
    """Resident memory and heap in use (small blocks and mmapped ones), GB."""
    rss = next(float(line.split()[1]) for line in Path("/proc/self/status").read_text().splitlines()
               if line.startswith("VmRSS:")) / 2**20  # fmt: skip
    return rss, (heap_in_use_mb() or 0.0) / 2**10


def _undestroyed(comm: MPI.Comm, scratch: Path) -> str:
    """PETSc objects created and not destroyed (rank 0's log), e.g. 'Matrix 7, Vector 3'."""
    path = scratch / "log.txt"
    viewer = PETSc.Viewer().createASCII(str(path), comm=comm)
    PETSc.Log.view(viewer)
    viewer.destroy()  # the log's own viewer is the one left: not counted
    text = path.read_text() if comm.rank == 0 else ""
    rows = re.findall(r"^\s*([A-Za-z][\w ]*?)\s+(\d+)\s+(\d+)\s*$", text, re.M)
    left = [(n, int(c) - int(d) - (n == "Viewer")) for n, c, d in rows]
    return ", ".join(f"{n} {k}" for n, k in left if k > 0) or "none"


def _say(comm: MPI.Comm, what: str, extra: str = "") -> None:
    rss, used = _gb()
    lines = comm.gather(f"rank {comm.rank}: {rss:6.2f} GB resident, {used:6.2f} GB in use", 0)
    if comm.rank == 0:
        print(f"{what}{extra}\n  " + "\n  ".join(lines), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scene", nargs="?", default="meshes/scenes/perforation_no2.toml")
    parser.add_argument("--resolution", default="coarse")
    parser.add_argument("--cases", type=int, default=3)
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    PETSc.Log.begin()
    scratch = Path(comm.bcast(tempfile.mkdtemp(prefix="hfcdem_mem_") if comm.rank == 0 else None))
    _say(comm, "before")
    for case in range(args.cases):
        until = {"injection.until": "first crack"}
        scene = load_scene(args.scene, args.resolution, overrides=until)
        t0 = time.perf_counter()
        run_scene(scene, scratch / f"case{case}", comm, force=True)
        _say(comm, f"case {case}: returned after {time.perf_counter() - t0:.0f} s")
        release_memory()
        left = _undestroyed(comm, scratch)
        _say(comm, f"case {case}: after release_memory", f"; PETSc objects left: {left}")
    comm.barrier()
    if comm.rank == 0:
        shutil.rmtree(scratch)


if __name__ == "__main__":
    main()
