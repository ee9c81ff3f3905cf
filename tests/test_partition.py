"""The cell partitioner (hfcdem.mesh.partition): the same partition at every launch.

Two separate ``mpirun -n 2`` launches mesh seed 001's borehole plate and must
give each rank the same cells (before SCOTCH was pinned to one thread they
gave 522/522, 521/523 or 523/521 at random).  Run from the serial pass only.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from mpi4py import MPI

SCRIPT = """
import sys
sys.path.insert(0, {tests!r})
import numpy as np
from mpi4py import MPI
from borehole import borehole_plate
mesh = borehole_plate().mesh
imap = mesh.topology.index_map(2)
cells = mesh.geometry.dofmap[: imap.size_local]
centre = np.round(mesh.geometry.x[cells].mean(axis=1), 9)
rows = sorted(map(tuple, centre.tolist()))
print(MPI.COMM_WORLD.rank, imap.size_local, imap.num_ghosts, hash(tuple(rows)), flush=True)
"""


def _launch() -> list[str]:
    # a clean launch: what a singleton MPI start put in this environment is dropped,
    # the image's run-as-root and oversubscription settings are kept
    keep = ("OMPI_ALLOW_RUN_AS_ROOT", "OMPI_MCA_rmaps")
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith(("OMPI_", "PMIX_")) or k.startswith(keep)
    }
    env.pop("SCOTCH_PTHREAD_NUMBER", None)  # the package must set it
    env["PYTHONHASHSEED"] = "0"
    script = SCRIPT.format(tests=str(Path(__file__).parent))
    out = subprocess.run(
        ["mpirun", "-n", "2", sys.executable, "-c", script],
        capture_output=True,
        text=True,
        check=True,
        env=env,
        timeout=300,
    )
    return sorted(line for line in out.stdout.splitlines() if line[:2] in ("0 ", "1 "))


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="launches mpirun itself: serial pass only")
@pytest.mark.skipif(shutil.which("mpirun") is None, reason="needs mpirun")
def test_two_launches_partition_alike():
    first, second = _launch(), _launch()
    assert len(first) == 2
    assert first == second
    sizes = [int(line.split()[1]) for line in first]
    assert max(sizes) <= 1.05 * min(sizes)
