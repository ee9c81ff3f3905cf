"""Blocks cut loose by broken faces: found on any rank count, released as debris, held."""

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import break_crack, crack_facets, tiny_solid

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.coupling.events import LOOSE_JUMP
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads
from hfcdem.solid.fragments import Fragments
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import OPEN


def _centroids(solid: CDEMSolid, global_cells: np.ndarray) -> np.ndarray:
    """Centroids of the given global cells, the same rows on every rank (sorted)."""
    tdim = solid.mesh.topology.dim
    imap = solid.mesh.topology.index_map(tdim)
    owned = np.arange(imap.size_local, dtype=np.int32)
    mine = owned[np.isin(imap.local_to_global(owned), global_cells)]
    x = dolfinx.mesh.compute_midpoints(solid.mesh, tdim, mine)
    rows = np.concatenate(solid.comm.allgather(x), axis=0)
    return rows[np.lexsort(rows.T[::-1])]


def _largest_jump_over_size(solid: CDEMSolid) -> float:
    broken = np.flatnonzero((solid.state != FacetState.INTACT) & solid.owned)
    ratio = 0.0
    if broken.size:
        x, cells = solid.midpoints[broken], solid.cells[broken]
        jump = np.asarray(solid.u.eval(x, cells[:, 0]) - solid.u.eval(x, cells[:, 1]))
        ratio = float(
            np.max(np.linalg.norm(jump.reshape(len(broken), -1), axis=1) / solid.h[broken])
        )
    return solid.comm.allreduce(ratio, op=MPI.MAX)


def test_a_crack_across_the_plate_cuts_the_free_half_loose():
    """x = 1 broken top to bottom: the 8 triangles at x < 1 are loose; half of it: none."""
    half = tiny_solid()
    lower = crack_facets(half)
    lower = lower[half.owned[lower] & (half.midpoints[lower, 1] < 0.5)]
    half.break_facets(lower, np.ones(len(lower), dtype=np.int8), 0.0)
    assert Fragments(half, ("left",)).loose_cells().size == 0

    solid = tiny_solid()
    break_crack(solid)
    loose = Fragments(solid, ()).loose_cells()
    assert loose.size == 8
    # 'right' is fixed: the rock is the half that holds it
    assert np.all(_centroids(solid, loose)[:, 0] < 1.0)
    # no wall named: loose but not debris
    facets, cells = Fragments(solid, ()).debris()
    assert cells == 0 and facets.size == 0


def test_debris_faces_are_released_and_hold_the_block_in_place():
    """The loose half on the cavity wall: its crack takes the cavity pressure and stays open."""
    p = 3e6  # below the in-situ 5 MPa: the half is squeezed less than before
    solid = tiny_solid(stress=5e6)
    break_crack(solid)
    facets, cells = Fragments(solid, ("left",)).debris()
    assert cells == 8
    crack = crack_facets(solid)
    assert np.array_equal(np.sort(facets), np.sort(crack))  # owned and ghost alike
    total = solid.comm.allreduce(int(np.count_nonzero(solid.owned[facets])), op=MPI.SUM)
    assert total == 2

    # not released: the in-situ stress presses the open crack shut
    loads = Loads(cavity={"left": p}, crack_pressure=0.0)
    solid.solve(loads)
    assert solid.update_contact(loads) == 2

    solid.release_facets(facets)
    assert np.all(solid.contact[facets] == OPEN) and np.all(solid.released[facets])
    assert solid.update_contact(loads) == 0  # released faces stay open
    again, _ = Fragments(solid, ("left",)).debris()
    assert again.size == 0  # nothing left to release

    # the cavity's pressure on the wall and on the crack: the loose half is in equilibrium
    held = Loads(cavity={"left": p}, crack_pressure=np.where(solid.released, p, 0.0))
    solid.solve(held)
    ratio = _largest_jump_over_size(solid)
    assert ratio < 1e-6 * LOOSE_JUMP  # measured 2.1e-7: the half's elastic strain
    # the pressure only on the wall: the half flies on its residual springs
    solid.solve(Loads(cavity={"left": p}, crack_pressure=0.0))
    assert _largest_jump_over_size(solid) > 1e4 * LOOSE_JUMP  # measured 3.0e4


def test_a_loose_block_next_to_debris_is_debris_too():
    """Cuts at x = 0.5 and x = 1: the strip at the wall is debris, the strip behind it too.

    The fluid fills the gap between them, so the second strip, whose face
    toward the first takes the cavity pressure, has lost its support there.
    """
    solid = tiny_solid()
    cuts = np.flatnonzero(
        np.isclose(solid.midpoints[:, 0], 0.5) | np.isclose(solid.midpoints[:, 0], 1.0)
    )
    mine = cuts[solid.owned[cuts]]
    solid.break_facets(mine, np.ones(len(mine), dtype=np.int8), 0.0)
    fragments = Fragments(solid, ("left",))
    assert fragments.loose_cells().size == 8
    facets, cells = fragments.debris()
    assert cells == 8  # both strips, not only the one on the wall (4 cells)
    assert np.array_equal(np.sort(facets), np.sort(cuts))
    assert fragments.loose_cells_on(("left",)).size == 2  # the strip's triangles with a face on it
    # the loose cells found once give the same debris and the same cells on the wall
    loose = fragments.loose_cells()
    again, count = fragments.debris(loose)
    assert count == cells and np.array_equal(again, facets)
    assert np.array_equal(
        fragments.loose_cells_on(("left",), loose), fragments.loose_cells_on(("left",))
    )
    # none loose (an empty set passed in): no debris, none on the wall
    assert fragments.debris(loose[:0])[1] == 0
    assert fragments.loose_cells_on(("left",), loose[:0]).size == 0


def _cube_with_one_cell_cut_out(comm: MPI.Comm) -> tuple[CDEMSolid, np.ndarray]:
    """Unit cube, fixed at x = 0, every interior facet an interface; one cell's 4 faces broken."""
    mesh = dolfinx.mesh.create_unit_cube(
        comm, 3, 3, 3, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    mesh.topology.create_connectivity(2, 3)
    left = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], 0.0))
    ftags = dolfinx.mesh.meshtags(
        mesh, 2, np.sort(left).astype(np.int32), np.ones(len(left), np.int32)
    )
    cmap = mesh.topology.index_map(3)
    cells = np.arange(cmap.size_local + cmap.num_ghosts, dtype=np.int32)
    ctags = dolfinx.mesh.meshtags(mesh, 3, cells, np.ones_like(cells))
    tmesh = TaggedMesh(mesh, ctags, ftags, {"rock": 1}, {"left": 1})
    solid = CDEMSolid(
        tmesh,
        ElasticMaterial(10e9, 0.25),
        InSituStress(1e6, 1e6),
        InterfaceModel(alpha=100, tensile_strength=1e6),
        fixed=("left",),
    )
    # the interior cell nearest the cube's centre, found the same way on every rank
    mid = dolfinx.mesh.compute_midpoints(mesh, 3, cells)
    d = np.linalg.norm(mid - 0.5, axis=1) + 1e-9 * mid @ np.array([1.0, 10.0, 100.0])
    best = comm.allreduce((float(d.min()), tuple(mid[np.argmin(d)])), op=MPI.MIN)
    target = np.asarray(best[1])
    around = np.flatnonzero(
        np.any(np.isclose(np.linalg.norm(mid[solid.cells] - target, axis=2), 0.0), axis=1)
    )
    mine = around[solid.owned[around]]
    solid.break_facets(mine, np.full(len(mine), 2, dtype=np.int8), 0.0)
    return solid, target


@pytest.mark.parametrize("which", ["world", "self"])
def test_one_tetrahedron_cut_out_is_found_on_any_rank_count(which):
    comm = MPI.COMM_WORLD if which == "world" else MPI.COMM_SELF
    solid, target = _cube_with_one_cell_cut_out(comm)
    assert solid.comm.allreduce(int(np.count_nonzero(solid.state[solid.owned])), MPI.SUM) == 4
    loose = Fragments(solid, ("left",)).loose_cells()
    assert loose.size == 1
    assert np.allclose(_centroids(solid, loose), target)
    # inside the rock, not on the wall: not debris
    facets, cells = Fragments(solid, ("left",)).debris()
    assert cells == 0 and facets.size == 0
