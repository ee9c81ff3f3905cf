"""Values of a function at fixed points as a gather and a small product.

A pumped run reads the displacement jump at the same points of every interface
(the midpoints and the strength points) after every solve.  ``Function.eval``
pulls each point back into its cell at every call; on an affine simplex mesh the
reference coordinates and the basis values there do not change, so
:class:`PointValues` computes them once, and a call is a gather of the cells'
degrees of freedom and one product (No. 2's default mesh: 34,545 facets).
"""

from __future__ import annotations

import dolfinx
import numpy as np


class PointValues:
    """Values at ``points`` (``P x 3``), each point in the local cell ``cells[p]``.

    Exact for any point of the cell (and its affine continuation beyond): the
    basis functions of the function's element, tabulated at the point's reference
    coordinates.  Needs an affine simplex mesh (a degree 1 coordinate element)
    and an element without dof transformations (discontinuous Lagrange); see
    :meth:`applies`.
    """

    def __init__(self, V: dolfinx.fem.FunctionSpace, points: np.ndarray, cells: np.ndarray) -> None:
        if not self.applies(V):
            raise ValueError("PointValues needs an affine simplex mesh and a Lagrange-type element")
        mesh = V.mesh
        gdim, tdim = mesh.geometry.dim, mesh.topology.dim
        cells = np.asarray(cells, dtype=np.int32)
        nodes = mesh.geometry.x[mesh.geometry.dofmap[cells]][:, :, :gdim]  # (P, tdim + 1, gdim)
        # x = x0 + sum_i X_i (x_i - x0): the rows of J are the edges from the first node
        J = nodes[:, 1:, :] - nodes[:, :1, :]
        offset = np.asarray(points)[:, :gdim] - nodes[:, 0, :]
        X = np.linalg.solve(np.transpose(J, (0, 2, 1)), offset[..., None])[..., 0]
        self.basis = np.asarray(V.element.basix_element.tabulate(0, X.reshape(-1, tdim)))[
            0, :, :, 0
        ]
        self.dofs = V.dofmap.list[cells]  # (P, dofs per cell), blocks
        self.bs = V.dofmap.bs

    @staticmethod
    def applies(V: dolfinx.fem.FunctionSpace) -> bool:
        """Return whether ``V``'s mesh and element allow precomputed point values."""
        mesh = V.mesh
        simplex = mesh.topology.cell_type in (
            dolfinx.mesh.CellType.triangle,
            dolfinx.mesh.CellType.tetrahedron,
        )
        return (
            simplex
            and mesh.geometry.cmap.degree == 1
            and mesh.topology.dim == mesh.geometry.dim
            and not V.element.needs_dof_transformations
            and V.element.num_sub_elements in (0, V.dofmap.bs)  # a blocked scalar element
        )

    def __call__(self, u: dolfinx.fem.Function) -> np.ndarray:
        """Return ``u`` at the points (``P x bs``; its ghosts must be up to date)."""
        values = u.x.array.reshape(-1, self.bs)[self.dofs]  # (P, dofs per cell, bs)
        return np.einsum("pi,pic->pc", self.basis, values)


__all__ = ["PointValues"]
