"""The cell partitioner: PT-SCOTCH on one thread, so a launch partitions as the last did.

PT-SCOTCH as Debian builds it (SCOTCH 7) partitions with several threads, and
the same mesh came out differently from one ``mpirun`` to the next (2 ranks,
the borehole plate: 522/522, 521/523 or 523/521 cells).  A parallel run's
round-off, and with it every near-tie of a break or a contact switch, then
changed between identical launches (a 2-rank viscous borehole run broke down
in one launch and stopped at dt_min in another).  SCOTCH reads
``SCOTCH_PTHREAD_NUMBER`` when it partitions; on one thread the partition is
the same at every launch (515/529 there).  A value the user set is kept.
"""

from __future__ import annotations

import os
from collections.abc import Callable

import dolfinx

#: SCOTCH's threads while partitioning (unless the environment says otherwise)
SCOTCH_THREADS = "1"


def create_partitioner(ghost_mode: dolfinx.mesh.GhostMode) -> Callable:
    """Return the default cell partitioner with SCOTCH pinned to one thread."""
    os.environ.setdefault("SCOTCH_PTHREAD_NUMBER", SCOTCH_THREADS)
    return dolfinx.mesh.create_cell_partitioner(ghost_mode)


__all__ = ["SCOTCH_THREADS", "create_partitioner"]
