"""The launch-independent cell partitioner (hfcdem.mesh.partition)."""

import itertools

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.mesh.partition import band_partition


def _path(n: int, shuffle: np.ndarray) -> dolfinx.cpp.graph.AdjacencyList_int64:
    """A path through the nodes ``shuffle[0], shuffle[1], ...`` (labels shuffled)."""
    nbrs: list[list[int]] = [[] for _ in range(n)]
    for a, b in itertools.pairwise(shuffle):
        nbrs[a].append(int(b))
        nbrs[b].append(int(a))
    data = np.array([j for row in nbrs for j in row], dtype=np.int64)
    offsets = np.cumsum([0] + [len(row) for row in nbrs]).astype(np.int32)
    return dolfinx.graph.adjacencylist(data, offsets)


def test_a_path_is_cut_into_equal_connected_runs_with_its_ghosts():
    n, nparts = 12, 3
    order = np.random.default_rng(1).permutation(n)
    graph = _path(n, order)
    dest = band_partition(MPI.COMM_SELF, nparts, graph, True)
    owner = np.array([dest.links(i)[0] for i in range(n)])
    # along the path the owners are three runs of four: 0000 1111 2222 (or reversed)
    along = owner[order]
    assert sorted(np.bincount(along)) == [4, 4, 4]
    assert np.count_nonzero(np.diff(along)) == nparts - 1
    # a cell is ghosted exactly on the other owners of its neighbours
    for i in range(n):
        expected = {owner[j] for j in graph.links(i)} - {owner[i]}
        assert set(dest.links(i)[1:]) == expected
    plain = band_partition(MPI.COMM_SELF, nparts, graph, False)
    assert [list(plain.links(i)) for i in range(n)] == [[o] for o in owner]
    # the same answer every time
    again = band_partition(MPI.COMM_SELF, nparts, graph, True)
    assert np.array_equal(again.array, dest.array)


@pytest.mark.mpi
def test_meshes_are_balanced_and_ghosted():
    from borehole import borehole_plate

    imap = borehole_plate().mesh.topology.index_map(2)
    sizes = MPI.COMM_WORLD.allgather(imap.size_local)
    assert max(sizes) - min(sizes) <= 1
    assert MPI.COMM_WORLD.allreduce(imap.num_ghosts, op=MPI.MIN) > 0
