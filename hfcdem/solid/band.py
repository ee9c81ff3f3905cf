"""The band of free interfaces of the reduced solid, and the traction that screens the rest.

In the reduced mode (:mod:`hfcdem.solid.reduction`) only the interfaces of a
*band* carry their own springs; the others are glued (the displacement is
continuous across them) and so carry no spring traction.  Their traction is
recovered from the stress of the two cells beside them, ``(sigma0 + C:eps(u)) n``
averaged over both cells, and a glued interface whose recovered traction reaches
``threshold`` of its strength joins the band before it may break: a facet is never
missed, it is freed first and then checked on its own springs.

The band starts with the pre-existing cracks, only grows (no chatter between
solves), and every facet freed brings ``rings`` vertex rings of its neighbours,
so a crack tip always sits inside free springs.  Flags agree between owners and
ghosts: the rings are grown on vertex flags reduced over the ranks.
"""

from __future__ import annotations

import dolfinx
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.materials import ElasticMaterial
from hfcdem.solid.elastic import stress
from hfcdem.solid.facets import InterfaceFacets

SOLID_MODES = ("full", "reduced")


class InterfaceBand:
    """Which interfaces are free (own springs) in the reduced mode; it only grows.

    ``all_free``: every interface free (the full-DG mode).
    ``version`` counts the changes, so a solver knows when to rebuild its clusters.
    """

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        facets: InterfaceFacets,
        threshold: float,
        rings: int,
        all_free: bool = False,
    ) -> None:
        if not 0.0 < threshold <= 1.0:
            raise ValueError(f"band threshold must be a fraction in (0, 1], got {threshold!r}")
        if int(rings) != rings or rings < 0:
            raise ValueError(f"band rings must be a whole number >= 0, got {rings!r}")
        self.threshold = float(threshold)
        self.rings = int(rings)
        self.comm: MPI.Comm = mesh.comm
        tdim = mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, 0)
        f2v = mesh.topology.connectivity(tdim - 1, 0)
        self._facet_vertices = f2v.array.reshape(-1, tdim)[facets.facets]
        self._vertex_map = mesh.topology.index_map(0)
        self._facet_map = mesh.topology.index_map(tdim - 1)
        self._facets = facets.facets
        self._owned = facets.owned
        self.free = np.ones_like(facets.is_crack) if all_free else facets.is_crack.copy()
        self.version = 0

    def count(self) -> int:
        """Global number of free interfaces."""
        return int(self.comm.allreduce(int(np.count_nonzero(self.free & self._owned)), MPI.SUM))

    def include(self, flags: np.ndarray, rings: int | None = None) -> int:
        """Free the interfaces ``flags`` marks on their owners, with ``rings`` rings around.

        Collective.  Returns the global number of interfaces newly freed.
        """
        flags = self._from_owners(np.asarray(flags, dtype=bool) & self._owned)
        for _ in range(self.rings if rings is None else rings):
            marked = np.zeros(self._vertex_map.size_local + self._vertex_map.num_ghosts)
            marked[self._facet_vertices[flags].reshape(-1)] = 1.0
            marked = self._reduce_vertices(marked)
            flags |= marked[self._facet_vertices].max(axis=1, initial=0.0) > 0.0
        new = flags & ~self.free
        added = int(self.comm.allreduce(int(np.count_nonzero(new & self._owned)), MPI.SUM))
        if added:
            self.free |= new
            self.version += 1
        return added

    def _from_owners(self, flags: np.ndarray) -> np.ndarray:
        """Owners' flags copied to the ghosts of their facets."""
        vec = dolfinx.la.vector(self._facet_map, 1)
        vec.array[:] = 0.0
        vec.array[self._facets] = flags
        vec.scatter_reverse(dolfinx.la.InsertMode.add)
        vec.scatter_forward()
        out: np.ndarray = vec.array[self._facets] > 0.0
        return out

    def _reduce_vertices(self, marked: np.ndarray) -> np.ndarray:
        """Largest flag of each vertex over the ranks that hold it."""
        vec = dolfinx.la.vector(self._vertex_map, 1)
        vec.array[:] = marked
        petsc = vec.petsc_vec
        petsc.ghostUpdate(addv=PETSc.InsertMode.MAX_VALUES, mode=PETSc.ScatterMode.REVERSE)
        petsc.ghostUpdate(addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        out = vec.array.copy()
        petsc.destroy()
        return out


class StressRecovery:
    """Cell stresses ``C:eps(u)`` of a DG1 displacement, and the tractions they give on facets."""

    def __init__(self, u: dolfinx.fem.Function, material: ElasticMaterial) -> None:
        mesh = u.function_space.mesh
        gdim = mesh.geometry.dim
        T = dolfinx.fem.functionspace(mesh, ("DG", 0, (gdim, gdim)))
        self._sigma = dolfinx.fem.Function(T)
        self._expr = dolfinx.fem.Expression(stress(u, material), T.element.interpolation_points())
        self._dofs = T.dofmap.list[:, 0]
        self._gdim = gdim

    def tractions(
        self, facets: InterfaceFacets, sigma0: np.ndarray, select: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Return the normal (tension positive) and tangential traction on ``select``.

        ``sigma0``: the in-situ stress to add (already scaled).  Zero on other facets.
        """
        self._sigma.interpolate(self._expr)
        self._sigma.x.scatter_forward()
        g = self._gdim
        cell_stress = self._sigma.x.array.reshape(-1, g, g)
        tn, shear = np.zeros(facets.num_facets), np.zeros((facets.num_facets, g))
        if not np.any(select):
            return tn, shear
        cells = facets.cells[select]
        s = 0.5 * (cell_stress[self._dofs[cells[:, 0]]] + cell_stress[self._dofs[cells[:, 1]]])
        n = facets.normals[select]
        t = np.einsum("fij,fj->fi", s + sigma0, n)
        tn[select] = np.einsum("fi,fi->f", t, n)
        shear[select] = t - tn[select][:, None] * n
        return tn, shear


__all__ = ["SOLID_MODES", "InterfaceBand", "StressRecovery"]
