"""Interface facets: which interior facets carry springs or cracks, and their geometry."""

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.facets import FacetFunctions, InterfaceFacets

N = 4  # unit square, N x N squares cut into two triangles each


def square(comm):
    """Unit square with the interior facets on y = 0.5 tagged ``crack`` and a ``left`` half."""
    mesh = dolfinx.mesh.create_unit_square(
        comm, N, N, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    mesh.topology.create_entities(1)
    on_line = dolfinx.mesh.locate_entities(mesh, 1, lambda x: np.isclose(x[1], 0.5))
    left = dolfinx.mesh.locate_entities(mesh, 2, lambda x: x[0] <= 0.5 + 1e-12)
    ftags = dolfinx.mesh.meshtags(mesh, 1, on_line, np.full(len(on_line), 7, dtype=np.int32))
    ctags = dolfinx.mesh.meshtags(mesh, 2, left, np.full(len(left), 3, dtype=np.int32))
    return TaggedMesh(mesh, ctags, ftags, {"left": 3}, {"crack": 7})


def total(comm, facets, values):
    return comm.allreduce(float(np.sum(values[facets.owned])), op=MPI.SUM)


@pytest.mark.parametrize("comm", [MPI.COMM_SELF, MPI.COMM_WORLD], ids=["self", "world"])
def test_every_interior_facet_is_an_interface_without_a_zone(comm):
    f = InterfaceFacets.build(square(comm), None, ("crack",))
    # interior edges: 2 N (N - 1) axis-parallel of length 1/N and N^2 diagonals
    count = total(comm, f, np.ones(f.num_facets))
    assert count == 2 * N * (N - 1) + N * N
    length = total(comm, f, f.areas)
    assert length == pytest.approx(2 * (N - 1) + N * np.sqrt(2.0), rel=1e-14)
    assert len(f.glue_facets) == 0
    # the crack: N facets on y = 0.5, of total length 1
    assert total(comm, f, f.is_crack.astype(float)) == N
    assert total(comm, f, np.where(f.is_crack, f.areas, 0.0)) == pytest.approx(1.0)
    assert np.allclose(f.midpoints[f.is_crack, 1], 0.5)


def test_normals_are_unit_perpendicular_and_point_out_of_the_first_cell():
    tmesh = square(MPI.COMM_WORLD)
    f = InterfaceFacets.build(tmesh, None, ())
    assert np.allclose(np.linalg.norm(f.normals, axis=1), 1.0)
    tangent = f.vertex_coords[:, 1, :2] - f.vertex_coords[:, 0, :2]
    assert np.allclose(np.einsum("ij,ij->i", f.normals, tangent), 0.0)
    # the first cell's centroid lies behind the facet
    mesh = tmesh.mesh
    first = dolfinx.mesh.compute_midpoints(mesh, 2, f.cells[:, 0])[:, :2]
    assert np.all(np.einsum("ij,ij->i", f.normals, f.midpoints[:, :2] - first) > 0.0)
    # h: two right triangles of legs 1/N, circumdiameter = hypotenuse
    assert np.allclose(f.h, np.sqrt(2.0) / N)


@pytest.mark.parametrize("comm", [MPI.COMM_SELF, MPI.COMM_WORLD], ids=["self", "world"])
def test_a_cell_zone_keeps_facets_between_its_cells_and_glues_the_rest(comm):
    tmesh = square(comm)
    by_group = InterfaceFacets.build(tmesh, "left", ("crack",))
    by_marker = InterfaceFacets.build(tmesh, lambda x: x[0] < 0.5, ("crack",))
    # left half: N (N/2 - 1) vertical + (N - 1) N/2 horizontal + N^2/2 diagonals,
    # plus the N/2 crack facets of the right half (cracks are always interfaces)
    inside = N * (N // 2 - 1) + (N - 1) * N // 2 + N * N // 2
    for f in (by_group, by_marker):
        assert total(comm, f, np.ones(f.num_facets)) == inside + N // 2
    assert np.array_equal(np.sort(by_group.facets), np.sort(by_marker.facets))
    fmap = tmesh.mesh.topology.index_map(1)
    owned_glue = np.sum(by_group.glue_facets < fmap.size_local)
    glue = comm.allreduce(int(owned_glue), op=MPI.SUM)
    assert glue == 2 * N * (N - 1) + N * N - inside - N // 2


def test_a_facet_group_zone_is_exactly_that_path():
    tmesh = square(MPI.COMM_WORLD)
    f = InterfaceFacets.build(tmesh, "crack", ())
    assert total(MPI.COMM_WORLD, f, np.ones(f.num_facets)) == N
    assert not f.is_crack.any()  # a path of intact springs, not a pre-existing crack
    with pytest.raises(KeyError, match="not a cell or facet group"):
        InterfaceFacets.build(tmesh, "nowhere", ())


def test_vertex_ids_are_the_same_on_any_rank_count():
    def ids(comm):
        f = InterfaceFacets.build(square(comm), None, ())
        mine = [tuple(sorted(v)) for v in f.vertex_ids[f.owned]]
        return sorted(v for part in comm.allgather(mine) for v in part)

    assert ids(MPI.COMM_WORLD) == ids(MPI.COMM_SELF)


def test_facet_functions_are_exact_at_facet_midpoints():
    tmesh = square(MPI.COMM_WORLD)
    f = InterfaceFacets.build(tmesh, None, ())
    functions = FacetFunctions(tmesh.mesh, f)
    values = 3.0 * f.midpoints[:, 0] - f.midpoints[:, 1]
    fn = functions.function(values)
    assert np.allclose(fn.x.array[functions.dofs()], values)
    # vectors too, on the facets this rank assembles (a ghost takes its owner's
    # value, which the owner oriented by its own first cell)
    vec = functions.function(f.normals, (2,))
    assert np.allclose(vec.x.array.reshape(-1, 2)[functions.dofs()][f.owned], f.normals[f.owned])
