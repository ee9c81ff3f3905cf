"""The CDEM solid in the subspace continuous across glued facets.

The DG1 displacement has one dof block per cell *corner* (cell, vertex).  Around a
vertex, the corners of cells joined through *glued* facets form a *vertex
cluster*; each cluster carries one reduced dof block (gdim components) and every
corner in it takes that value.  The prolongation ``P`` (one 1 per row) maps the
reduced dofs to the DG dofs, and the reduced problem is

    K_red = P^T K P,   f_red = P^T f,   u = P u_red.

Glued facets carry no jump in this subspace, so their springs and Nitsche terms
vanish: with every facet glued the reduced problem is continuous P1 elasticity;
with none glued ``P`` is a permutation and the reduced problem is the DG one.
Between, the glued springs act as infinitely stiff, which differs from the DG
answer at spring factor alpha by O(1/alpha) (their compliance).

Which facets are glued is the caller's input (:func:`glued_facet_set`); the solid
chooses them as the complement of its band of free interfaces
(:mod:`hfcdem.solid.band`).  Clusters are connected components of a
graph on the DG dof blocks; they are found rank by rank and merged over the ghost
layer, so the reduced system is the same on any number of ranks.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import dolfinx
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from hfcdem.solid.facets import InterfaceFacets
from hfcdem.solvers import (
    DIRECT_CHOLESKY,
    check_ksp,
    create_ksp,
    setup_factorisation,
    solve_together,
)


def glued_facet_set(
    facets: InterfaceFacets, glued: np.ndarray | None = None, outside: bool = True
) -> np.ndarray:
    """Local indices of the glued facets of a solid's ``facets``.

    ``glued`` flags each interface facet (None: every interface that is not a
    pre-existing crack); ``outside`` adds the facets the solid glues by Nitsche's
    method (outside the fracturable zone).  Flags must agree between the owner
    and the ghosts of a facet.
    """
    if glued is None:
        glued = ~facets.is_crack
    glued = np.asarray(glued, dtype=bool)
    if glued.shape != (facets.num_facets,):
        raise ValueError(
            f"glued must flag each of the {facets.num_facets} interface facets, "
            f"got shape {glued.shape}"
        )
    parts = [facets.facets[glued]] + ([facets.glue_facets] if outside else [])
    return np.unique(np.concatenate(parts)).astype(np.int32)


def _corner_vertices(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """(cells, nv) vertex of each DG1 dof block of each local cell (checked by position)."""
    mesh = V.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim, 0)
    mesh.topology.create_connectivity(0, tdim)
    c2v = mesh.topology.connectivity(tdim, 0)
    dofs = V.dofmap.list
    corners = c2v.array.reshape(len(dofs), -1)
    nverts = mesh.topology.index_map(0).size_local + mesh.topology.index_map(0).num_ghosts
    vx = mesh.geometry.x[
        dolfinx.mesh.entities_to_geometry(mesh, 0, np.arange(nverts, dtype=np.int32), False)[:, 0]
    ]
    dof_x = V.tabulate_dof_coordinates()
    if not np.allclose(dof_x[dofs], vx[corners], rtol=0.0, atol=1e-12 * (1 + np.abs(vx).max())):
        raise RuntimeError("DG1 dofs are not ordered like the cell vertices")
    return corners


def _glue_edges(V: dolfinx.fem.FunctionSpace, glued: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of local DG dof blocks joined by the glued facets seen with both cells here."""
    mesh = V.mesh
    tdim = mesh.topology.dim
    for dim in (0, tdim):
        mesh.topology.create_connectivity(tdim - 1, dim)
    corners = _corner_vertices(V)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    f2v = mesh.topology.connectivity(tdim - 1, 0)
    glued = np.asarray(glued, dtype=np.int32)
    # facets on the edge of the ghost layer have one local cell: their owners join them
    glued = glued[np.diff(f2c.offsets)[glued] == 2]
    first = f2c.offsets[glued]
    c0, c1 = f2c.array[first], f2c.array[first + 1]
    fv = f2v.array.reshape(-1, tdim)[glued]  # (nf, tdim): simplex facets
    dofs = V.dofmap.list

    def at(cells: np.ndarray) -> np.ndarray:
        pos = np.argmax(corners[cells][:, :, None] == fv[:, None, :], axis=1)
        return dofs[cells[:, None], pos].reshape(-1)

    return at(c0), at(c1)


def _component_min(
    values: np.ndarray, graph: tuple[int, np.ndarray], imap: dolfinx.common.IndexMap
) -> np.ndarray:
    """Minimum of ``values`` over each connected component of the distributed graph."""
    count, labels = graph
    comm = imap.comm
    vec = dolfinx.la.vector(imap, 1)
    petsc = vec.petsc_vec
    values = values.copy()
    while True:
        low = np.full(count, np.inf)
        np.minimum.at(low, labels, values)
        merged = low[labels]
        # owners take the smallest value of their ghosts, then ghosts copy the owner
        vec.array[:] = -merged
        petsc.ghostUpdate(addv=PETSc.InsertMode.MAX_VALUES, mode=PETSc.ScatterMode.REVERSE)
        petsc.ghostUpdate(addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        merged = -vec.array
        changed = bool(np.any(merged != values))
        values = merged
        if not comm.allreduce(changed, op=MPI.LOR):
            petsc.destroy()
            return values


@dataclass(frozen=True, eq=False)
class VertexClusters:
    """Vertex clusters of a DG1 vector space and the prolongation onto them."""

    prolongation: PETSc.Mat  # (DG dofs) x (reduced dofs), one 1 per row
    cluster: np.ndarray  # (owned + ghost DG dof blocks,) global cluster index
    num_owned: int  # clusters owned by this rank
    num_global: int  # clusters on all ranks
    bs: int  # components per dof block

    @classmethod
    def build(cls, V: dolfinx.fem.FunctionSpace, glued: np.ndarray) -> VertexClusters:
        """Cluster the corners of ``V`` (DG1, vector) joined by the local ``glued`` facets."""
        element = V.ufl_element()
        if element.embedded_superdegree != 1 or not element.discontinuous:
            raise ValueError("vertex clusters need a DG1 space (degree 1, discontinuous)")
        imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
        comm = imap.comm
        n = imap.size_local + imap.num_ghosts
        gidx = imap.local_to_global(np.arange(n, dtype=np.int32)).astype(np.int64)
        a, b = _glue_edges(V, glued)
        adjacency = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
        graph = connected_components(adjacency, directed=False)
        # the smallest global dof of a cluster names it; its owner owns the cluster
        root = _component_min(gidx.astype(np.float64), graph, imap).astype(np.int64)
        owned = np.arange(n) < imap.size_local
        is_root = owned & (root == gidx)
        num_owned = int(np.count_nonzero(is_root))
        offset = comm.exscan(num_owned) or 0
        number = np.full(n, np.inf)
        number[is_root] = offset + np.arange(num_owned)
        cluster = _component_min(number, graph, imap).astype(np.int64)
        num_global = comm.allreduce(num_owned, op=MPI.SUM)
        rows = imap.size_local * bs
        cols = (cluster[: imap.size_local, None] * bs + np.arange(bs)).reshape(-1)
        P = PETSc.Mat().createAIJ(
            ((rows, imap.size_global * bs), (num_owned * bs, num_global * bs)),
            csr=(
                np.arange(rows + 1, dtype=PETSc.IntType),
                cols.astype(PETSc.IntType),
                np.ones(rows, dtype=PETSc.ScalarType),
            ),
            comm=comm,
        )
        P.assemble()
        return cls(P, cluster, num_owned, num_global, bs)

    def reduce_matrix(self, A: PETSc.Mat) -> PETSc.Mat:
        """Return ``P^T A P`` (a new matrix)."""
        return A.PtAP(self.prolongation)

    def reduce_vector(self, b: PETSc.Vec) -> PETSc.Vec:
        """Return ``P^T b`` (a new vector)."""
        out = self.prolongation.createVecRight()
        self.prolongation.multTranspose(b, out)
        return out

    def prolong(self, u_red: PETSc.Vec, target: dolfinx.fem.Function) -> None:
        """Set ``target = P u_red`` (ghosts updated)."""
        self.prolongation.mult(u_red, target.x.petsc_vec)
        target.x.scatter_forward()

    def constrained(
        self, bcs: list[dolfinx.fem.DirichletBC], V: dolfinx.fem.FunctionSpace
    ) -> np.ndarray:
        """Local rows of the reduced dofs holding a Dirichlet dof (homogeneous conditions).

        A cluster with one held corner is held as a whole: its corners share one value.
        """
        flags = dolfinx.fem.Function(V)
        flags.x.array[:] = 1.0
        for bc in bcs:
            bc.set(flags.x.array)  # held dofs take their value, 0
        flags.x.scatter_forward()
        held = self.prolongation.createVecRight()
        free = flags.x.petsc_vec.copy()
        free.scale(-1.0)
        free.shift(1.0)  # 1 at held dofs
        self.prolongation.multTranspose(free, held)
        lo = held.getOwnershipRange()[0]
        rows = np.flatnonzero(held.array > 0.5).astype(PETSc.IntType) + lo
        held.destroy()
        free.destroy()
        return rows


class ReducedSystem:
    """Factorise and solve ``K`` of a DG1 space in the subspace glued on ``glued`` facets.

    ``bcs``: the (homogeneous) Dirichlet conditions of ``K``; a cluster with a held
    corner is held as a whole.  The reduced system is always factorised (MUMPS
    LDL^T): it is a continuous-P1-like system away from the band.
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        bcs: list[dolfinx.fem.DirichletBC],
        glued: np.ndarray,
        petsc_options: Mapping[str, object] | None = None,
        prefix: str = "hfcdem_reduced_",
    ) -> None:
        t0 = time.perf_counter()
        self.comm: MPI.Comm = V.mesh.comm
        self.prefix = prefix
        self.petsc_options = dict(petsc_options or {})
        self.clusters = VertexClusters.build(V, glued)
        self.held = self.clusters.constrained(bcs, V)
        self.seconds: dict[str, float] = {"cluster": time.perf_counter() - t0}

    @property
    def num_dofs(self) -> int:
        """Global number of reduced unknowns."""
        return self.clusters.num_global * self.clusters.bs

    def destroy(self) -> None:
        """Free the prolongation (collective)."""
        self.clusters.prolongation.destroy()

    def reduce(self, A: PETSc.Mat, diagonal: float = 1.0) -> PETSc.Mat:
        """Return ``P^T A P`` with the held rows and columns set to ``diagonal`` I.

        ``diagonal = 0`` reduces a change of ``A`` that is added to a reduced matrix.
        """
        t0 = time.perf_counter()
        A_red = self.clusters.reduce_matrix(A)
        A_red.zeroRowsColumns(self.held, diag=diagonal)
        A_red.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        self.seconds["reduce"] = time.perf_counter() - t0
        return A_red

    def create_solver(self, A_red: PETSc.Mat) -> PETSc.KSP:
        """Factorise a reduced matrix (MUMPS LDL^T); the caller destroys the KSP."""
        t0 = time.perf_counter()
        options = {**DIRECT_CHOLESKY, **self.petsc_options}
        ksp = setup_factorisation(
            lambda: create_ksp(A_red, self.prefix, options, self.comm), self.comm
        )
        self.seconds["factorise"] = time.perf_counter() - t0
        return ksp

    def factorize(self, A: PETSc.Mat) -> PETSc.KSP:
        """Reduce and factorise the assembled ``A`` (left to the caller); return the KSP."""
        A_red = self.reduce(A)
        ksp = self.create_solver(A_red)
        A_red.destroy()  # the KSP keeps its own reference
        return ksp

    def solve(self, ksp: PETSc.KSP, b: PETSc.Vec, target: dolfinx.fem.Function) -> None:
        """Solve the reduced system for the DG right-hand side ``b``; prolong into ``target``."""
        self.solve_many(ksp, [b], [target])

    def solve_many(
        self,
        ksp: PETSc.KSP,
        rhs: Sequence[PETSc.Vec],
        targets: Sequence[dolfinx.fem.Function],
    ) -> None:
        """Solve for every DG right-hand side of ``rhs`` into ``targets``, together if direct."""
        reduced = []
        for b in rhs:
            b_red = self.clusters.reduce_vector(b)
            b_red.setValues(self.held, np.zeros(len(self.held)))
            b_red.assemble()
            reduced.append(b_red)
        u_red = reduced[0].duplicate()
        if len(reduced) > 1 and ksp.getType() == PETSc.KSP.Type.PREONLY:
            solved = solve_together(ksp, reduced)
            check_ksp(ksp, "reduced CDEM solve", "a block may be held by no boundary condition")
            for i, target in enumerate(targets):
                u_red.setArray(solved[:, i])
                self.clusters.prolong(u_red, target)
        else:
            for b_red, target in zip(reduced, targets, strict=True):
                ksp.solve(b_red, u_red)
                check_ksp(ksp, "reduced CDEM solve", "a block may be held by no boundary condition")
                self.clusters.prolong(u_red, target)
        for vec in (*reduced, u_red):
            vec.destroy()


__all__ = ["ReducedSystem", "VertexClusters", "glued_facet_set"]
