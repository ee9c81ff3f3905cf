"""A cell partitioner that gives the same partition at every launch.

DOLFINx's default (PT-SCOTCH, as Debian builds it) partitions the same mesh
differently from one ``mpirun`` to the next (2 ranks, the borehole plate:
522/522, 521/523, 523/521 cells), so a parallel run's round-off, and with it
every near-tie of a break or a contact switch, changed between identical
launches.  Gmsh meshes on rank 0, so the whole dual graph arrives there: it
is ordered by Gibbs-Poole-Stockmeyer (a banded, deterministic ordering) and
cut into ``nparts`` equal runs of that order, each a connected slab.  When the
cells are spread over several ranks (another mesh source) the default
partitioner runs instead.
"""

from __future__ import annotations

from collections.abc import Callable

import dolfinx
import dolfinx.cpp.graph
import numpy as np
from mpi4py import MPI


def band_partition(
    comm: MPI.Comm, nparts: int, graph: dolfinx.cpp.graph.AdjacencyList_int64, ghosting: bool
) -> dolfinx.cpp.graph.AdjacencyList_int32:
    """Destinations of the local cells: owner first, then the ranks that ghost them."""
    counts = comm.allgather(int(graph.num_nodes))
    if sum(1 for c in counts if c > 0) > 1:
        return dolfinx.graph.partitioner_scotch()(comm, nparts, graph, ghosting)
    n = int(graph.num_nodes)
    if n == 0:
        empty = np.zeros(0, dtype=np.int32)
        return dolfinx.graph.adjacencylist(empty, np.zeros(1, dtype=np.int32))
    # all cells are here, numbered 0..n-1 (the ranks before hold none)
    offsets = np.asarray(graph.offsets, dtype=np.int64)
    links = np.asarray(graph.array, dtype=np.int64)
    local = dolfinx.graph.adjacencylist(links.astype(np.int32), offsets.astype(np.int32))
    rank_of = np.asarray(dolfinx.cpp.graph.reorder_gps(local), dtype=np.int64) * nparts // n
    rank_of = rank_of.astype(np.int32)
    if not ghosting:
        return dolfinx.graph.adjacencylist(rank_of, np.arange(n + 1, dtype=np.int32))
    # a cell is ghosted on every other rank owning one of its facet neighbours
    cell = np.repeat(np.arange(n), np.diff(offsets))
    other = rank_of[links]
    pairs = np.unique(np.column_stack([cell, other])[other != rank_of[cell]], axis=0)
    extra = np.bincount(pairs[:, 0], minlength=n) if len(pairs) else np.zeros(n, dtype=np.int64)
    out_offsets = np.concatenate([[0], np.cumsum(1 + extra)]).astype(np.int32)
    data = np.empty(out_offsets[-1], dtype=np.int32)
    data[out_offsets[:-1]] = rank_of
    if len(pairs):  # pairs are sorted by cell: each cell's ghosts follow its owner
        starts = out_offsets[pairs[:, 0]] + 1
        rank_in_cell = np.arange(len(pairs)) - np.searchsorted(pairs[:, 0], pairs[:, 0])
        data[starts + rank_in_cell] = pairs[:, 1]
    return dolfinx.graph.adjacencylist(data, out_offsets)


def create_partitioner(ghost_mode: dolfinx.mesh.GhostMode) -> Callable:
    """Return a cell partitioner for ``gmshio.model_to_mesh``, the same at every launch."""
    return dolfinx.mesh.create_cell_partitioner(band_partition, ghost_mode)


__all__ = ["band_partition", "create_partitioner"]
