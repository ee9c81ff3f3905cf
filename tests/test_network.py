"""The fracture network: stars, junctions, components (serial and parallel alike)."""

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.flow.network import CAVITY, build_network


def _line_network(comm):
    # three 2D facets meeting at vertex 1 (a junction), one also touching vertex 0 (cavity)
    keys = np.array([[0, 1], [1, 2], [1, 3], [5, 6]])
    coords = np.array(
        [
            [[0, 0, 0], [1, 0, 0]],
            [[1, 0, 0], [2, 0, 0]],
            [[1, 0, 0], [1, 1, 0]],
            [[5, 5, 0], [6, 5, 0]],
        ],
        dtype=float,
    )
    area = np.ones(4)
    mine = slice(None) if comm.rank == 0 else slice(0, 0)
    return build_network(comm, keys[mine], area[mine], coords[mine], np.array([0]))


def test_junction_and_cavity_connections():
    net, _ = _line_network(MPI.COMM_WORLD)
    assert net.size == 4
    # junction at vertex 1 connects all three pairs; facet [0, 1] also joins the cavity
    assert int(np.sum(net.pair_b == CAVITY)) == 1
    assert int(np.sum(net.pair_b != CAVITY)) == 3
    comp = net.components()
    assert list(comp[:3]) == [0, 0, 0]
    assert comp[3] != 0


def test_star_delta_transmissibility():
    net, _ = _line_network(MPI.COMM_WORLD)
    k = np.array([1.0, 1.0, 1.0, 1.0])
    trans = net.transmissibility(k, lambda a: a)  # conductivity = aperture
    inner = net.pair_b != CAVITY
    # equal members at distance 0.5 from the junction: t = 2 each, T = t t / (3 t) = 2/3
    np.testing.assert_allclose(trans[inner], 2.0 / 3.0)
    # the cavity connection takes the member's own t (cross 1 / distance 0.5)
    assert trans[~inner][0] == pytest.approx(2.0)
