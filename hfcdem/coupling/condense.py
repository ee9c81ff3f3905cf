"""The solid condensed onto the pressure groups, and the cavity it encloses.

Between interface events the solid is linear, so with its stiffness factorised
once ``u = u_base + sum_g p_g u_g``, where ``u_g`` answers a unit pressure on the
open facets of group ``g`` (and on the cavity walls and wet wall joints for the
cavity group 0).  The void volume of every network facet and of the cavity are
the work-conjugates of those loads, so they are linear in the group pressures
with a symmetric compliance: :class:`~hfcdem.flow.balance.VoidVolumes`.
"""

from __future__ import annotations

import collections
import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.flow.balance import VoidVolumes
from hfcdem.flow.network import gather_rows
from hfcdem.solid.cdem import SOLVE_BATCH, CDEMSolid
from hfcdem.solid.forms import OPEN_FACETS, SPRING, Loads


@dataclass(frozen=True, eq=False)
class NetworkView:
    """Where the network's facets are among this rank's interfaces."""

    facets: np.ndarray  # local interface index of every broken facet (owned and ghost)
    positions: np.ndarray  # their index in the network
    owned: np.ndarray  # which of them this rank owns
    size: int  # facets in the network

    def gather(self, values: np.ndarray, comm: MPI.Comm) -> np.ndarray:
        """Network array of per-facet ``values`` of the owned facets (collective)."""
        out = np.zeros((self.size, *values.shape[1:]))
        out[self.positions[self.owned]] = values
        return comm.allreduce(out, op=MPI.SUM)


@dataclass(frozen=True, eq=False)
class CondensedSolid:
    """The solid for the current interface states, as a function of the group pressures."""

    base: dolfinx.fem.Function  # the in-situ state with no fluid pressure
    columns: list[dolfinx.fem.Function]  # the response to unit pressure in each group
    volumes: VoidVolumes

    def displacement(self, u: dolfinx.fem.Function, p: np.ndarray) -> None:
        """Set ``u`` to the displacement at group pressures ``p``."""
        u.x.array[:] = self.base.x.array
        for g, col in enumerate(self.columns):
            u.x.array[:] += p[g] * col.x.array


class KeptCondensations:
    """The last few condensations, by everything they were made from (collective keys).

    A condensation depends on the interface states, the network and its pressure
    groups, not on the pressures, so a state met again costs no solve.  That is
    common: a contact round that undoes the one before (broken facets that open
    under the fluid pressure and close again as their blocks press them shut)
    comes back to the states of a moment ago, and so does the next step's first
    round while nothing broke.
    """

    def __init__(self, comm: MPI.Comm, size: int = 4) -> None:
        self.comm = comm
        self.size = size
        self._kept: collections.OrderedDict[bytes, Any] = collections.OrderedDict()
        self.reused = 0

    def key(self, local: Sequence[np.ndarray], shared: Sequence[object]) -> bytes:
        """Digest of per-rank ``local`` arrays and ``shared`` values, the same on every rank."""
        digest = hashlib.sha256()
        for a in local:
            digest.update(np.ascontiguousarray(a).tobytes())
        combined = hashlib.sha256(b"".join(self.comm.allgather(digest.digest())))
        for v in shared:
            combined.update(
                np.ascontiguousarray(v).tobytes() if isinstance(v, np.ndarray) else repr(v).encode()
            )
        return combined.digest()

    def get(self, key: bytes) -> Any:
        """Return the condensation kept under ``key``, or None."""
        found = self._kept.get(key)
        if found is not None:
            self._kept.move_to_end(key)
            self.reused += 1
        return found

    def put(self, key: bytes, value: Any) -> None:
        """Keep ``value`` under ``key``, dropping the least recently used past ``size``."""
        self._kept[key] = value
        self._kept.move_to_end(key)
        while len(self._kept) > self.size:
            self._kept.popitem(last=False)


# ------------------------------------------------------------------- cavity


def local_vertex_ids(mesh: dolfinx.mesh.Mesh, facets: np.ndarray) -> np.ndarray:
    """Global input ids of the vertices of local ``facets``."""
    tdim = mesh.topology.dim
    if len(facets) == 0:  # entities_to_geometry divides by the count
        return np.zeros((0, tdim), dtype=np.int64)
    nodes = dolfinx.mesh.entities_to_geometry(mesh, tdim - 1, facets.astype(np.int32), False)
    return np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[nodes]


def cavity_vertices(
    solid: CDEMSolid, cavity: Sequence[str], injection_point: Sequence[float] | None
) -> np.ndarray:
    """Global ids of the vertices on the cavity walls (or nearest the injection point)."""
    comm, tm = solid.comm, solid.tmesh
    ids = [local_vertex_ids(solid.mesh, tm.facets(name)).reshape(-1) for name in cavity]
    local = np.unique(np.concatenate(ids)) if ids else np.zeros(0, dtype=np.int64)
    if injection_point is not None:
        x = solid.mesh.geometry.x
        pt = np.zeros(3)
        ip = np.asarray(injection_point, dtype=float)
        pt[: len(ip)] = ip
        d = np.linalg.norm(x - pt, axis=1)
        i = int(np.argmin(d)) if len(d) else -1
        best = (
            (float(d[i]), int(solid.mesh.geometry.input_global_indices[i]))
            if i >= 0
            else (math.inf, -1)
        )
        best = min(comm.allgather(best))
        local = np.append(local, best[1])
    return np.unique(gather_rows(comm, local.astype(np.int64)))


def mean_point(mesh: dolfinx.mesh.Mesh, vertex_ids: np.ndarray) -> np.ndarray:
    """Mean coordinates of the vertices ``vertex_ids`` (collective)."""
    geo, comm = mesh.geometry, mesh.comm
    mask = np.isin(np.asarray(geo.input_global_indices), vertex_ids)
    total = comm.allreduce(geo.x[mask].sum(axis=0), op=MPI.SUM)
    count = comm.allreduce(int(mask.sum()), op=MPI.SUM)
    return total / max(count, 1)


def mesh_cavity_volume(solid: CDEMSolid, cavity: Sequence[str]) -> float:
    """Volume enclosed by the walls: -(1/d) int x.n ds (n out of the rock)."""
    if not cavity:
        return 0.0
    mesh = solid.mesh
    x, n = ufl.SpatialCoordinate(mesh), ufl.FacetNormal(mesh)
    form = sum(-ufl.dot(x, n) / solid.gdim * solid.tmesh.ds(name) for name in cavity)
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form))
    return float(solid.comm.allreduce(local, op=MPI.SUM))


def touching_joints(solid: CDEMSolid, vertex_ids: np.ndarray) -> np.ndarray:
    """Interfaces (not cracks) sharing an edge (2D: a vertex) with ``vertex_ids``."""
    touching = np.isin(solid.vertex_ids, vertex_ids).sum(axis=1)
    return (touching >= solid.gdim - 1) & ~solid.is_crack


def wall_joint_term(
    solid: CDEMSolid, wet: np.ndarray, v: ufl.Argument, dS: ufl.Measure | None = None
) -> ufl.Form | None:
    """Return the unit pressure in the ``wet`` intact joints, -int n+.[v] dS, or None.

    ``dS`` must be the interface measure of the form the term joins (one
    subdomain_data per measure and form).
    """
    if not solid.comm.allreduce(bool(wet.any()), op=MPI.LOR):
        return None
    jw = solid.facet_function(wet.astype(float))
    nrm = ufl.FacetNormal(solid.mesh)
    if dS is None:
        dS = ufl.Measure("dS", domain=solid.mesh, subdomain_data=solid.interface_tags())
    return -jw("+") * ufl.dot(nrm("+"), ufl.jump(v)) * dS(SPRING, metadata={"quadrature_degree": 1})


def cavity_load_form(
    solid: CDEMSolid, cavity: Sequence[str], wet_joints: np.ndarray
) -> dolfinx.fem.Form | None:
    """Return the unit-pressure load on the cavity, -int n.v ds (also dV = c.u).

    It includes the faces of the ``wet_joints`` (intact wall joints holding fluid).
    """
    if not cavity:
        return None
    v, n = ufl.TestFunction(solid.V), ufl.FacetNormal(solid.mesh)
    L = sum(-ufl.dot(n, v) * solid.tmesh.ds(name) for name in cavity)
    joints = wall_joint_term(solid, wet_joints, v)
    return dolfinx.fem.form(L if joints is None else L + joints)


# ------------------------------------------------------------- condensation


def condense(
    solid: CDEMSolid,
    cavity: Sequence[str],
    wet_joints: np.ndarray,
    group: np.ndarray,
    is_open: np.ndarray,
    size: int,
) -> tuple[dolfinx.fem.Function, list[dolfinx.fem.Function]]:
    """Factorise the solid once; return its base state and one response per group.

    ``group`` and ``is_open`` are per local interface (-2: not in the network);
    the column of group ``g`` answers unit pressure on its open facets, plus the
    walls and ``wet_joints`` for the cavity group 0.
    """
    a_form, ksp = solid.factorize()
    base = dolfinx.fem.Function(solid.V)
    zero = solid.load_form(Loads(cavity=dict.fromkeys(cavity, 0.0)))
    # (right-hand side, solution) pairs not solved yet: MUMPS reads its factor once per batch
    pending = [(solid.assemble_load(a_form, zero), base)]
    v, nrm = ufl.TestFunction(solid.V), ufl.FacetNormal(solid.mesh)
    # per-facet values through a CR function (exact at the single quadrature point)
    cr = solid.facet_function(np.zeros(solid.num_facets))
    dS = ufl.Measure("dS", domain=solid.mesh, subdomain_data=solid.interface_tags())
    L = (
        -cr("+")
        * ufl.dot(nrm("+"), ufl.jump(v))
        * dS(OPEN_FACETS, metadata={"quadrature_degree": 1})
    )
    c_cav = dolfinx.fem.Constant(solid.mesh, dolfinx.default_scalar_type(0.0))
    if cavity:
        L += sum(-c_cav * ufl.dot(nrm, v) * solid.tmesh.ds(name) for name in cavity)
        joints = wall_joint_term(solid, wet_joints, v, dS)
        if joints is not None:
            L += c_cav * joints
    L_form = dolfinx.fem.form(L)
    cr_dofs = solid.facet_dofs()
    columns = [dolfinx.fem.Function(solid.V) for _ in range(size)]

    def solve_pending() -> None:
        solid.solve_assembled(ksp, [b for b, _ in pending], [x for _, x in pending])
        pending.clear()

    for g, column in enumerate(columns):
        cr.x.array[:] = 0.0
        cr.x.array[cr_dofs] = ((group == g) & is_open).astype(float)
        cr.x.scatter_forward()
        c_cav.value = 1.0 if g == 0 else 0.0
        pending.append((solid.assemble_load(a_form, L_form), column))
        if len(pending) == SOLVE_BATCH:
            solve_pending()
    if pending:
        solve_pending()
    solid.solves += 1
    return base, columns


def network_openings(solid: CDEMSolid, view: NetworkView, u: dolfinx.fem.Function) -> np.ndarray:
    """Mean normal opening of every network facet (midpoint jump), gathered."""
    sel = view.facets[view.owned]
    if len(sel):
        mid = solid.midpoints[sel]
        jump = u.eval(mid, solid.cells[sel, 0]) - u.eval(mid, solid.cells[sel, 1])
        w = -np.einsum("fi,fi->f", np.asarray(jump).reshape(-1, solid.gdim), solid.normals[sel])
    else:
        w = np.zeros(0)
    return view.gather(w, solid.comm)


def closure_offsets(
    solid: CDEMSolid, view: NetworkView
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offset, closure stress and contact compliance of each network facet.

    The offset is the intact pre-compression offset of a broken facet; the
    closure stress the in-situ normal stress, compression positive; the contact
    compliance ``1/kn`` of a broken facet (0 for a pre-existing crack): the
    overlap its springs would take per pascal of contact pressure, by which an
    open face under fluid pressure p counts its void (``w - offset + p/kn``),
    so void and contact switch on one quantity (:meth:`CDEMSolid.update_contact`).
    """
    sel = view.facets[view.owned]
    n = solid.normals[sel]
    t0n = np.einsum("fi,ij,fj->f", n, solid.sigma0, n)
    broken = ~solid.is_crack[sel]
    off = np.where((t0n < 0.0) & broken, -t0n / solid.kn[sel], 0.0)
    compliance = np.where(broken, 1.0 / solid.kn[sel], 0.0)
    out = view.gather(np.column_stack([off, -t0n, compliance]).reshape(-1, 3), solid.comm)
    return out[:, 0], out[:, 1], out[:, 2]


def group_volumes(
    solid: CDEMSolid,
    view: NetworkView,
    base: dolfinx.fem.Function,
    columns: list[dolfinx.fem.Function],
    offsets: np.ndarray,
    open_area: tuple[np.ndarray, np.ndarray, float],
    cavity_form: dolfinx.fem.Form | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Void volumes of the network facets and the cavity, linear in the group pressures.

    ``open_area``: (open flags, areas, residual aperture) of the network facets;
    the cavity's change is measured by ``cavity_form`` (None: a rigid cavity).
    Returns v0, h, hc and the wall motion c.u of the base state.
    """
    is_open, area, residual = open_area
    # void volume: the mechanical opening (minus the intact pre-compression offset
    # of broken facets, as in CDEMSolid.snapshot) plus the residual aperture
    w0 = network_openings(solid, view, base) - offsets
    v0 = np.where(is_open, area * w0, 0.0) + area * residual
    h = np.zeros((view.size, len(columns)))
    hc = np.zeros(len(columns))
    wall = 0.0  # c.u of the base state: the cavity's change from the undeformed mesh
    cvec = dolfinx.fem.petsc.assemble_vector(cavity_form) if cavity_form is not None else None
    if cvec is not None:
        cvec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        wall = cvec.dot(base.x.petsc_vec)
    for g, col in enumerate(columns):
        h[:, g] = np.where(is_open, area * network_openings(solid, view, col), 0.0)
        if cvec is not None:
            hc[g] = cvec.dot(col.x.petsc_vec)
    if cvec is not None:
        cvec.destroy()
    return v0, h, hc, wall


__all__ = [
    "CondensedSolid",
    "KeptCondensations",
    "NetworkView",
    "cavity_load_form",
    "cavity_vertices",
    "closure_offsets",
    "condense",
    "group_volumes",
    "local_vertex_ids",
    "mean_point",
    "mesh_cavity_volume",
    "network_openings",
    "touching_joints",
    "wall_joint_term",
]
