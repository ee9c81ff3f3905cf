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


def _reference_network(keys, coords, cavity):
    """The star loop the vectorised build replaced, facet by facet (serial)."""
    nv = keys.shape[1]
    skeys = np.sort(keys, axis=1)
    x = np.take_along_axis(coords, np.argsort(keys, axis=1)[:, :, None], axis=1)
    order = np.lexsort(skeys.T[::-1])
    skeys, x = skeys[order], x[order]
    cav = set(int(v) for v in cavity)
    centroid = x.mean(axis=1)
    stars, point, cross, on_wall, e_fac, e_star, e_geom = {}, [], [], [], [], [], []
    for f in range(len(skeys)):
        for loc in [(0,), (1,)] if nv == 2 else [(0, 1), (1, 2), (0, 2)]:
            key = tuple(int(skeys[f, i]) for i in loc)
            s = stars.get(key)
            if s is None:
                s = stars[key] = len(point)
                pts = x[f, list(loc)]
                point.append(pts.mean(axis=0))
                cross.append(1.0 if nv == 2 else float(np.linalg.norm(pts[1] - pts[0])))
                on_wall.append(all(k in cav for k in key))
            e_fac.append(f)
            e_star.append(s)
            e_geom.append(cross[s] / max(float(np.linalg.norm(centroid[f] - point[s])), 1e-300))
    members = [[] for _ in point]
    for e, s in enumerate(e_star):
        members[s].append(e)
    pairs = []
    for s, mem in enumerate(members):
        if on_wall[s]:
            pairs += [(e, CAVITY, s) for e in mem]
        else:
            pairs += [(a, b, s) for i, a in enumerate(mem) for b in mem[i + 1 :]]
    return skeys, np.array(e_fac), np.array(e_star), np.array(e_geom), np.array(pairs)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_vectorised_build_equals_the_star_loop_on_any_number_of_ranks(dim):
    """Every facet of a small mesh as a joint: stars, pairs and geometry as the loop made them."""
    import dolfinx

    n = 4
    if dim == 2:
        mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, n, n)
    else:
        mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, n, n, n)
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, 0)
    keys = mesh.topology.connectivity(tdim - 1, 0).array.reshape(-1, dim)
    x = mesh.geometry.x  # vertices and geometry nodes coincide for P1 meshes
    coords = x[keys]
    cavity = np.flatnonzero(np.isclose(x[:, 0], 0.0))
    comm = MPI.COMM_WORLD
    mine = np.arange(len(keys)) % comm.size == comm.rank
    net, positions = build_network(comm, keys[mine], np.ones(mine.sum()), coords[mine], cavity)
    ref_keys, e_fac, e_star, e_geom, pairs = _reference_network(keys, coords, cavity)
    np.testing.assert_array_equal(net.keys, ref_keys)
    np.testing.assert_array_equal(net.entry_facet, e_fac)
    np.testing.assert_array_equal(net.entry_star, e_star)
    np.testing.assert_allclose(net.entry_geometry, e_geom, rtol=1e-14)
    np.testing.assert_array_equal(np.column_stack([net.pair_a, net.pair_b, net.pair_star]), pairs)
    assert net.num_stars == e_star.max() + 1
    assert int(np.sum(net.pair_b == CAVITY)) > 0  # the wall x = 0 is met
    # a facet's position found by its key, in any vertex order; an unknown key is -1
    np.testing.assert_array_equal(net.positions(keys[mine][:, ::-1]), positions)
    assert net.positions(np.full((1, dim), 10**6))[0] == -1


def test_positions_by_key_with_ids_too_large_for_one_integer():
    """Keys whose mixed-radix code would overflow int64 are found by the row-wise search."""
    big = 2**40
    keys = np.array([[0, 1, 2], [1, 2, 3], [2, 3, 4]]) + big
    coords = np.random.default_rng(0).random((3, 3, 3))
    net, _ = build_network(MPI.COMM_SELF, keys, np.ones(3), coords, np.array([big]))
    np.testing.assert_array_equal(net.positions(keys[[2, 0]][:, ::-1]), [2, 0])
    assert net.positions(np.array([[big, big + 1, big + 5]]))[0] == -1
