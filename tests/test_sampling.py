"""Point evaluation that gives the same answer on any number of ranks."""

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.io.sampling import evaluate_at_points


def _mesh(comm):
    return dolfinx.mesh.create_unit_square(
        comm, 8, 8, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )


def test_linear_field_is_exact_everywhere():
    mesh = _mesh(MPI.COMM_WORLD)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (2,)))
    f = dolfinx.fem.Function(V)
    f.interpolate(lambda x: np.vstack([1 + 2 * x[0] - x[1], 3 * x[1]]))
    pts = np.array([[0.0, 0.0], [0.5, 0.5], [0.123, 0.987], [1.0, 1.0]])
    vals = evaluate_at_points(f, pts)
    assert np.allclose(vals[:, 0], 1 + 2 * pts[:, 0] - pts[:, 1])
    assert np.allclose(vals[:, 1], 3 * pts[:, 1])


def test_discontinuous_field_on_cell_boundary_is_rank_independent():
    def sample(comm):
        mesh = _mesh(comm)
        V = dolfinx.fem.functionspace(mesh, ("DG", 0))
        f = dolfinx.fem.Function(V)
        f.x.array[:] = mesh.topology.original_cell_index[: len(f.x.array)]
        # vertices and edge midpoints of the 8x8 grid lie on several cells
        pts = np.array([[0.5, 0.5], [0.25, 0.0625], [0.125, 0.125], [1.0, 0.0]])
        return evaluate_at_points(f, pts)

    assert np.array_equal(sample(MPI.COMM_WORLD), sample(MPI.COMM_SELF))


def test_point_outside_is_an_error():
    mesh = _mesh(MPI.COMM_WORLD)
    f = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 1)))
    with pytest.raises(ValueError, match="outside the mesh"):
        evaluate_at_points(f, [[2.0, 0.5]])
