"""Strength over a material length: the interfaces read a filtered stress.

A strength criterion at a point has no length scale: where the stress
concentrates over a length the mesh resolves (a 1 mm tunnel, a sharp
junction), the finer the mesh the higher the stress its facets see and the
more of them break.  Real rock resists over a length of its own (a fracture
process zone; the critical distance of Taylor's theory, ``L = (K_IC / T0)^2 /
pi``).  Here the stress the failure check reads is filtered over a length
``l`` by the implicit-gradient (Helmholtz) equation of Peerlings et al.
(1996),

    s - l^2 lap(s) = sigma(u)   in the rock,   grad(s) . n = 0 on its boundary,

solved for each of the six stress components on continuous P1 (one
factorisation, reused).  In 1D its kernel is ``exp(-|x| / l) / (2 l)``; as
``l -> 0`` ``s`` is the L2 projection of the stress, as the mesh refines at a
fixed ``l`` it converges to the filtered field, and the check converges with
it.  The in-situ stress is uniform and passes the filter unchanged, so only
the perturbation ``C : eps(u)`` is filtered.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from hfcdem.solid.elastic import stress
from hfcdem.solvers import create_ksp

if TYPE_CHECKING:
    from hfcdem.config.materials import ElasticMaterial

#: the filter's solver: a direct LU of the small P1 system, factorised once
FILTER_OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


class StressFilter:
    """The stress of ``u`` filtered over ``length``, at the midpoints of ``facets``.

    ``facets``: local facet indices; ``cells``: a local cell beside each.  Options
    under the PETSc prefix ``prefix`` override :data:`FILTER_OPTIONS`.
    """

    def __init__(
        self,
        u: dolfinx.fem.Function,
        material: ElasticMaterial,
        facets: np.ndarray,
        cells: np.ndarray,
        length: float,
        prefix: str = "hfcdem_filter_",
    ) -> None:
        if not length > 0.0:
            raise ValueError(f"length must be positive (m), got {length!r}")
        mesh = u.function_space.mesh
        tdim, gdim = mesh.topology.dim, mesh.geometry.dim
        self.length = length
        self.gdim = gdim
        self.space = V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
        s, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        l2 = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(length**2))
        a = dolfinx.fem.form((s * v + l2 * ufl.inner(ufl.grad(s), ufl.grad(v))) * ufl.dx)
        self._A = dolfinx.fem.petsc.assemble_matrix(a)
        self._A.assemble()
        self._ksp = create_ksp(self._A, prefix, FILTER_OPTIONS, mesh.comm)
        sigma = stress(u, material)
        self._parts = [(i, j) for i in range(gdim) for j in range(i, gdim)]
        self._rhs = [dolfinx.fem.form(sigma[i, j] * v * ufl.dx) for i, j in self._parts]
        self._b = dolfinx.fem.petsc.create_vector(self._rhs[0])
        self._out = dolfinx.fem.Function(V)
        # the P1 dofs at each interface facet's vertices (local, ghosts included):
        # a P1 field's value at the midpoint is their mean
        closure = V.element.basix_element.entity_closure_dofs[tdim - 1]
        mesh.topology.create_connectivity(tdim, tdim - 1)
        c2f = mesh.topology.connectivity(tdim, tdim - 1)
        dofs = np.zeros((len(facets), len(closure[0])), dtype=np.int32)
        for k, (f, c) in enumerate(zip(facets, cells, strict=True)):
            local = int(np.flatnonzero(c2f.links(c) == f)[0])
            dofs[k] = V.dofmap.cell_dofs(int(c))[closure[local]]
        self._dofs = dofs

    def midpoint_stress(self) -> np.ndarray:
        """Return the filtered perturbation stress at each facet's midpoint, (F, gdim, gdim).

        Collective (one back-substitution per component).
        """
        out = np.zeros((self._dofs.shape[0], self.gdim, self.gdim))
        x = self._out.x
        for (i, j), form in zip(self._parts, self._rhs, strict=True):
            with self._b.localForm() as local:
                local.set(0.0)
            dolfinx.fem.petsc.assemble_vector(self._b, form)
            self._b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            self._ksp.solve(self._b, x.petsc_vec)
            x.scatter_forward()
            value = x.array[self._dofs].mean(axis=1)
            out[:, i, j] = value
            out[:, j, i] = value
        return out

    def destroy(self) -> None:
        """Free the PETSc objects."""
        self._ksp.destroy()
        self._A.destroy()
        self._b.destroy()


__all__ = ["FILTER_OPTIONS", "StressFilter"]
