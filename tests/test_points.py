"""Precomputed point values against ``Function.eval``, on one rank and two."""

import dolfinx
import numpy as np
import pytest
import tiny_solid
from mpi4py import MPI

from hfcdem.solid.cdem import Loads
from hfcdem.solid.points import PointValues

comm = MPI.COMM_WORLD


def mesh_of(gdim: int) -> dolfinx.mesh.Mesh:
    if gdim == 2:
        return dolfinx.mesh.create_rectangle(comm, [[0.0, 0.0], [2.0, 1.0]], [5, 4])
    return dolfinx.mesh.create_box(comm, [[0.0, 0.0, 0.0], [2.0, 1.0, 1.5]], [3, 2, 3])


def random_points(mesh: dolfinx.mesh.Mesh, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """One point per local cell (ghosts too), anywhere in it, padded to three coordinates."""
    rng = np.random.default_rng(seed + comm.rank)
    tdim = mesh.topology.dim
    imap = mesh.topology.index_map(tdim)
    cells = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
    nodes = mesh.geometry.x[mesh.geometry.dofmap[cells]]
    weights = rng.dirichlet(np.ones(tdim + 1), size=len(cells))
    return np.einsum("pn,pnx->px", weights, nodes), cells


@pytest.mark.parametrize("gdim", [2, 3])
@pytest.mark.parametrize("degree", [1, 2])
def test_point_values_are_function_eval(gdim, degree):
    mesh = mesh_of(gdim)
    V = dolfinx.fem.functionspace(mesh, ("DG", degree, (gdim,)))
    u = dolfinx.fem.Function(V)
    u.interpolate(
        lambda x: np.array([np.sin(3 * x[0]) * x[1] + k * x[gdim - 1] ** 2 for k in range(gdim)])
    )
    u.x.array[:] += np.random.default_rng(comm.rank).uniform(-1, 1, u.x.array.size) * 1e-3
    u.x.scatter_forward()
    points, cells = random_points(mesh, 7)
    assert PointValues.applies(V)
    got = PointValues(V, points, cells)(u)
    want = np.asarray(u.eval(points, cells)).reshape(-1, gdim)
    assert got.shape == want.shape
    scale = comm.allreduce(float(np.abs(want).max()), op=MPI.MAX)
    gap = comm.allreduce(float(np.abs(got - want).max()), op=MPI.MAX)
    assert gap < 1e-14 * scale


def test_a_quadrilateral_mesh_is_refused_by_name():
    mesh = dolfinx.mesh.create_unit_square(comm, 2, 2, dolfinx.mesh.CellType.quadrilateral)
    V = dolfinx.fem.functionspace(mesh, ("DG", 1, (2,)))
    assert not PointValues.applies(V)
    with pytest.raises(ValueError, match="affine simplex"):
        PointValues(V, np.zeros((1, 3)), np.zeros(1, dtype=np.int32))


def test_the_solids_jumps_at_its_fixed_points_are_those_of_function_eval():
    solid = tiny_solid.tiny_solid()
    tiny_solid.break_crack(solid)
    solid.solve(Loads())  # the in-situ stress: every spring carries a jump
    for x in (solid.midpoints, *solid.strength_points):
        cells = solid.cells
        want = np.asarray(solid.u.eval(x, cells[:, 0]) - solid.u.eval(x, cells[:, 1]))
        got = solid.jumps(solid.u, x)
        scale = comm.allreduce(float(np.abs(want).max(initial=0.0)), op=MPI.MAX)
        assert scale > 0.0
        gap = comm.allreduce(
            float(np.abs(got - want.reshape(got.shape)).max(initial=0.0)), op=MPI.MAX
        )
        assert gap < 1e-13 * scale
    # a point set made on the fly goes through Function.eval: the same values
    x = solid.midpoints.copy()
    assert np.array_equal(
        solid.jumps(solid.u, x),
        np.asarray(solid.u.eval(x, solid.cells[:, 0]) - solid.u.eval(x, solid.cells[:, 1])).reshape(
            -1, solid.gdim
        ),
    )
