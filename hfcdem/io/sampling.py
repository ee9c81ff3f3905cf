"""Evaluate fields at points, identically on any number of ranks."""

from __future__ import annotations

import dolfinx
import numpy as np
import numpy.typing as npt
import ufl
from mpi4py import MPI


def interpolate_expression(
    expr: ufl.core.expr.Expr, mesh: dolfinx.mesh.Mesh, element: tuple, name: str = ""
) -> dolfinx.fem.Function:
    """Interpolate a UFL expression into a new function on ``element``."""
    V = dolfinx.fem.functionspace(mesh, element)
    f = dolfinx.fem.Function(V, name=name)
    f.interpolate(dolfinx.fem.Expression(expr, V.element.interpolation_points()))
    f.x.scatter_forward()
    return f


def evaluate_at_points(f: dolfinx.fem.Function, points: npt.ArrayLike) -> np.ndarray:
    """Values of ``f`` at ``points`` (N x gdim or N x 3), the same array on every rank.

    A point on a boundary between cells is evaluated in the cell with the lowest
    *original* (input) index, so discontinuous fields give the same answer for
    any partition.  Raises ValueError for a point outside the mesh.
    """
    mesh = f.function_space.mesh
    comm = mesh.comm
    pts = np.zeros((np.atleast_2d(points).shape[0], 3))
    p_in = np.atleast_2d(np.asarray(points, dtype=float))
    pts[:, : p_in.shape[1]] = p_in

    tdim = mesh.topology.dim
    num_owned = mesh.topology.index_map(tdim).size_local
    tree = dolfinx.geometry.bb_tree(mesh, tdim, np.arange(num_owned, dtype=np.int32))
    candidates = dolfinx.geometry.compute_collisions_points(tree, pts)
    colliding = dolfinx.geometry.compute_colliding_cells(mesh, candidates, pts)
    original = mesh.topology.original_cell_index

    big = np.iinfo(np.int64).max
    best = np.full(len(pts), big, dtype=np.int64)
    best_local = np.full(len(pts), -1, dtype=np.int32)
    for i in range(len(pts)):
        cells = colliding.links(i)
        cells = cells[cells < num_owned]
        if len(cells):
            k = int(np.argmin(original[cells]))
            best[i] = original[cells[k]]
            best_local[i] = cells[k]
    winner = np.empty_like(best)
    comm.Allreduce(best, winner, op=MPI.MIN)
    missing = np.flatnonzero(winner == big)
    if len(missing):
        raise ValueError(f"point {pts[missing[0]].tolist()} lies outside the mesh")

    size = int(np.prod(f.ufl_shape)) if f.ufl_shape else 1
    values = np.zeros((len(pts), size))
    mine = np.flatnonzero((best == winner) & (best_local >= 0))
    if len(mine):
        values[mine] = f.eval(pts[mine], best_local[mine]).reshape(len(mine), size)
    total = np.empty_like(values)
    comm.Allreduce(values, total, op=MPI.SUM)
    return total


__all__ = [
    "evaluate_at_points",
    "interpolate_expression",
]
