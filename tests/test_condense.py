"""The solid condensed onto pressure groups equals a direct solve, with a symmetric compliance."""

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import break_crack, tiny_solid

from hfcdem.coupling.condense import (
    cavity_vertices,
    mean_point,
    mesh_cavity_volume,
    network_openings,
    touching_joints,
)
from hfcdem.coupling.groups import condense_network, local_network, network_volumes
from hfcdem.solid.forms import Loads


def _condensed():
    solid = tiny_solid()
    break_crack(solid)
    walls = cavity_vertices(solid, ("left",), None)
    network = local_network(solid, walls)
    group = np.array([1, 2])  # each crack facet its own group; 0 the wall 'left'
    none = np.zeros(solid.num_facets, dtype=bool)
    base, columns = condense_network(solid, ("left",), network, group, none)
    return solid, network, group, base, columns


def test_the_wall_is_the_left_side_and_encloses_no_volume():
    solid = tiny_solid()
    walls = cavity_vertices(solid, ("left",), None)
    assert len(walls) == 3  # 2 cells high: 3 vertices on x = 0
    assert mean_point(solid.mesh, walls) == pytest.approx([0.0, 0.5, 0.0])
    # -(1/2) int x.n ds over x = 0 vanishes: the wall passes through the origin
    assert mesh_cavity_volume(solid, ("left",)) == pytest.approx(0.0, abs=1e-14)
    joints = touching_joints(solid, walls)
    count = solid.comm.allreduce(int(np.sum(joints & solid.owned)), op=MPI.SUM)
    assert count > 0 and np.all(np.isclose(solid.vertex_coords[joints][:, :, 0].min(axis=1), 0.0))


def test_superposed_columns_equal_a_direct_solve():
    solid, network, group, base, columns = _condensed()
    assert network.net.size == 2 and len(columns) == 3
    p = np.array([3e6, 2e6, 5e6])
    u = dolfinx.fem.Function(solid.V)
    u.x.array[:] = base.x.array + sum(pi * c.x.array for pi, c in zip(p, columns, strict=True))
    crack = np.zeros(solid.num_facets)
    crack[network.view.facets] = p[group[network.view.positions]]
    solid.solve(Loads(cavity={"left": p[0]}, crack_pressure=crack))
    scale = np.max(np.abs(solid.u.x.array))
    assert scale > 0.0
    np.testing.assert_allclose(u.x.array, solid.u.x.array, atol=1e-9 * scale)


@pytest.mark.parametrize("batch", [1, 2, 3])
def test_columns_do_not_depend_on_how_the_solves_are_batched(monkeypatch, batch):
    """Base and 3 columns: 4 right-hand sides, solved in batches of 1, 2 or 3 (the rest last)."""
    *_, base, columns = _condensed()
    import hfcdem.coupling.condense as condense_module

    monkeypatch.setattr(condense_module, "SOLVE_BATCH", batch)
    *_, base_b, columns_b = _condensed()
    assert len(columns_b) == 3
    for a, b in zip([base, *columns], [base_b, *columns_b], strict=True):
        assert np.abs(b.x.array).max() > 0.0
        np.testing.assert_allclose(
            b.x.array, a.x.array, rtol=0, atol=1e-12 * np.abs(a.x.array).max()
        )


def test_void_volumes_are_linear_with_a_symmetric_compliance():
    solid, network, _, base, columns = _condensed()
    _, h, hc, _, closure = network_volumes(solid, network, (base, columns), 0.0, None)
    assert hc.tolist() == [0.0, 0.0, 0.0]  # no cavity form: the wall is not measured
    # Betti: facet 0's volume change under unit pressure in facet 1's group (2)
    # equals facet 1's under unit pressure in facet 0's group (1)
    assert h[0, 2] == pytest.approx(h[1, 1], rel=1e-8)
    assert h[0, 1] > 0.0 and h[1, 2] > 0.0  # pressure opens the facet it acts in
    # v0 + h p changes by the area times the opening of the superposed displacement
    p = np.array([1e6, 4e6, 2e6])
    u = dolfinx.fem.Function(solid.V)
    u.x.array[:] = base.x.array + sum(pi * c.x.array for pi, c in zip(p, columns, strict=True))
    opened = network_openings(solid, network.view, u) - network_openings(solid, network.view, base)
    np.testing.assert_allclose(h @ p, network.net.area * opened, rtol=1e-8)
    # the in-situ SH = 1 MPa along x closes the crack on x = 1 (compression positive)
    np.testing.assert_allclose(closure, [1e6, 1e6], rtol=1e-9)


def test_open_broken_facets_count_the_overlap_of_their_own_pressure():
    """With their groups, open broken facets add area / kn per pascal of their own group."""
    solid, network, group, base, columns = _condensed()
    _, h0, _, _, _ = network_volumes(solid, network, (base, columns), 0.0, None)
    _, h, _, _, _ = network_volumes(solid, network, (base, columns), 0.0, None, group)
    view = network.view
    kn = view.gather(solid.kn[view.facets[view.owned]], solid.comm)  # the whole network
    extra = np.zeros_like(h)
    extra[[0, 1], group] = network.net.area / kn
    # h - h0 cancels 6 digits of h (area / kn is 1/alpha of the rock's compliance)
    np.testing.assert_allclose(h - h0, extra, rtol=1e-6, atol=1e-30)
    assert h[0, 2] == pytest.approx(h[1, 1], rel=1e-8)  # still symmetric (Betti)
