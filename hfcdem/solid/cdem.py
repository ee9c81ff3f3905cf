"""The CDEM solid: elastic blocks joined by breakable interface springs.

Discretisation (docs/design.md option (a), measured against the alternatives in the
closing notes): the displacement is discontinuous Lagrange (DG1 or DG2) on every
cell, so every facet is a potential interface.

- Facets of the *fracturable zone* carry springs ``kn [u_n] + ks [u_t]`` with
  ``kn = alpha E / h``; they break by the rules of :mod:`hfcdem.solid.interfaces`.
- Pre-existing cracks (facet group ``"crack"`` and any others named) start
  broken and open.
- All other interior facets are glued by a symmetric interior penalty (Nitsche)
  term, which is consistent: away from the zone the blocks behave as a
  continuous body with no spring compliance.

The unknown is the perturbation of the in-situ state (see :mod:`hfcdem.solid.elastic`).
Interface traction on the ``+`` side: ``t = sigma0 n+ - K (u+ - u-)`` while
intact or closed; ``-p n+`` while open with fluid pressure ``p``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.elastic import ElasticMaterial, InSituStress, strain, stress
from hfcdem.solid.interfaces import (
    FacetState,
    InterfaceModel,
    check_failure,
    select_breaking,
    stable_facet_hash,
    weibull_scatter,
)
from hfcdem.solvers import DIRECT_CHOLESKY, check_ksp, create_ksp, setup_factorisation

# interior-facet integral ids
SPRING = 1  # intact, or broken and closed in stick: kn and ks
OPEN_FACETS = 2  # broken/pre-existing and open: fluid pressure, no springs
SLIP_FACETS = 3  # broken, closed, sliding: kn and a friction traction
GLUE = 4  # outside the zone: Nitsche continuity

# contact sub-states of broken facets
OPEN, STICK, SLIP = 0, 1, 2

ZoneMarker = Callable[[np.ndarray], np.ndarray]

# solver="auto": direct (MUMPS) up to this many unknowns, CG + GAMG beyond
AUTO_DIRECT_MAX_DOFS = 300_000


@dataclass(frozen=True)
class Loads:
    """Loads of one solve: in-situ stress plus fluid pressures (Pa).

    ``cavity`` maps exterior facet-group names to pressure; ``crack_pressure``
    acts on every open broken or pre-existing interface (a number, or one value
    per local facet of :attr:`CDEMSolid.facets`).  ``joint_pressure`` (one value
    per local facet) acts inside intact interfaces holding fluid.
    """

    cavity: Mapping[str, float] = field(default_factory=dict)
    crack_pressure: float | np.ndarray = 0.0
    joint_pressure: np.ndarray | None = None
    in_situ_factor: float = 1.0


@dataclass(frozen=True)
class InterfaceSnapshot:
    """Per-facet values of the interfaces owned by this rank."""

    opening: np.ndarray  # normal opening w (m), physical aperture for open facets
    slip: np.ndarray  # tangential jump magnitude (m)
    normal_traction: np.ndarray  # tension positive (Pa)
    shear_traction: np.ndarray  # magnitude (Pa)
    shear_vector: np.ndarray  # on the + face


@dataclass
class BreakEvent:
    """Interfaces broken at one load level."""

    load_factor: float
    facets: np.ndarray  # local facet indices
    modes: np.ndarray
    midpoints: np.ndarray


class CDEMSolid:
    """Blocks and springs on a :class:`TaggedMesh`, with a quasi-static solver."""

    def __init__(
        self,
        tmesh: TaggedMesh,
        material: ElasticMaterial,
        in_situ: InSituStress,
        interfaces: InterfaceModel,
        zone: ZoneMarker | str | None = None,
        *,
        degree: int = 1,
        cracks: Sequence[str] = ("crack",),
        rollers: Mapping[str, int] | None = None,
        fixed: Sequence[str] = (),
        nitsche_penalty: float | None = None,
        solver: str = "auto",
        strength_points: str = "vertices",
        petsc_options: Mapping[str, object] | None = None,
        prefix: str = "hfcdem_cdem_",
    ) -> None:
        if degree not in (1, 2):
            raise ValueError(f"degree must be 1 or 2 (DG blocks), got {degree!r}")
        if solver not in ("direct", "iterative", "auto"):
            raise ValueError(f"solver must be 'direct', 'iterative' or 'auto', got {solver!r}")
        self.tmesh = tmesh
        self.mesh = mesh = tmesh.mesh
        self.comm: MPI.Comm = mesh.comm
        self.material = material
        self.in_situ = in_situ
        self.model = interfaces
        self.degree = degree
        self.prefix = prefix
        self.solver_kind = solver
        self.petsc_options = dict(petsc_options or {})
        tdim = mesh.topology.dim
        self.gdim = gdim = mesh.geometry.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        mesh.topology.create_connectivity(tdim, tdim - 1)
        mesh.topology.create_connectivity(tdim - 1, 0)

        self.V = dolfinx.fem.functionspace(mesh, ("DG", degree, (gdim,)))
        if solver == "auto":
            # MUMPS is robust for any alpha; past this size CG + GAMG wins on 2 cores
            dofs = self.V.dofmap.index_map.size_global * gdim
            self.solver_kind = "direct" if dofs <= AUTO_DIRECT_MAX_DOFS else "iterative"
        self.u = dolfinx.fem.Function(self.V, name="displacement")
        self._u_unit = dolfinx.fem.Function(self.V)
        self.sigma0 = in_situ.tensor(gdim)

        if strength_points not in ("vertices", "midpoint"):
            raise ValueError(
                f"strength_points must be 'vertices' or 'midpoint', got {strength_points!r}"
            )
        self._classify_facets(zone, cracks)
        self._facet_geometry()
        if strength_points == "midpoint":
            self.strength_points = [self.midpoints]
        else:
            self.strength_points = [
                self.vertex_coords[:, k] for k in range(self.vertex_coords.shape[1])
            ]
        self._strengths()
        self._bcs = self._boundary_conditions(rollers or {}, fixed)
        self._nitsche = nitsche_penalty if nitsche_penalty is not None else 10.0 * (degree + 1) ** 2
        # facets that ever broke, and their contact sub-state
        self.contact = np.full(self.num_facets, OPEN, dtype=np.int8)
        self.contact[~self.is_crack] = STICK
        self.friction_traction = np.zeros((self.num_facets, gdim))
        self.solves = 0
        self.solve_seconds = 0.0
        self.events: list[BreakEvent] = []
        self.progress: Callable[[str], None] | None = None
        self._cr_cache: dict[tuple[int, ...], tuple[dolfinx.fem.FunctionSpace, np.ndarray]] = {}
        scalar = dolfinx.default_scalar_type
        self._c_kn = dolfinx.fem.Constant(mesh, scalar(self.model.alpha * material.youngs_modulus))
        self._c_ratio = dolfinx.fem.Constant(
            mesh, scalar(self.model.shear_stiffness_ratio(material.poisson_ratio))
        )
        self._c_residual = dolfinx.fem.Constant(mesh, scalar(self.model.residual_stiffness))
        lam2mu = material.lame_lambda + 2.0 * material.shear_modulus
        self._c_glue = dolfinx.fem.Constant(mesh, scalar(self._nitsche * lam2mu))

    # ------------------------------------------------------------------ setup

    def _classify_facets(self, zone: ZoneMarker | str | None, cracks: Sequence[str]) -> None:
        mesh, tdim = self.mesh, self.mesh.topology.dim
        fmap = mesh.topology.index_map(tdim - 1)
        num_local = fmap.size_local + fmap.num_ghosts
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        counts = np.diff(f2c.offsets)
        interior = np.flatnonzero(counts == 2).astype(np.int32)
        crack_mask = np.zeros(num_local, dtype=bool)
        for name in cracks:
            if name in self.tmesh.facet_names:
                crack_mask[self.tmesh.facets(name)] = True
        # crack facets must be interior: a crack on the boundary is just a loaded face
        crack_mask &= counts == 2

        num_cells = (
            mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
        )
        if zone is None:
            in_zone_cell = np.ones(num_cells, dtype=bool)
        elif isinstance(zone, str) and zone in self.tmesh.facet_names:
            # a facet group: springs on exactly those facets (a prescribed fracture path)
            in_zone_cell = np.zeros(num_cells, dtype=bool)
        elif isinstance(zone, str):
            if zone not in self.tmesh.cell_names:
                known = ", ".join(sorted(self.tmesh.cell_names) + sorted(self.tmesh.facet_names))
                raise KeyError(
                    f"fracturable zone {zone!r} is not a cell or facet group; known: {known}"
                )
            in_zone_cell = np.zeros(num_cells, dtype=bool)
            in_zone_cell[self.tmesh.cell_tags.find(self.tmesh.cell_names[zone])] = True
        else:
            mids = dolfinx.mesh.compute_midpoints(mesh, tdim, np.arange(num_cells, dtype=np.int32))
            in_zone_cell = np.asarray(zone(mids.T), dtype=bool)
        cells = f2c.array.reshape(-1)  # interior facets only are indexed below
        first = f2c.offsets[interior]
        c0, c1 = cells[first], cells[first + 1]
        zone_facet = in_zone_cell[c0] & in_zone_cell[c1]
        if isinstance(zone, str) and zone in self.tmesh.facet_names:
            path_mask = np.zeros(num_local, dtype=bool)
            path_mask[self.tmesh.facets(zone)] = True
            zone_facet = path_mask[interior]

        keep = zone_facet | crack_mask[interior]
        self.facets = interior[keep]  # local facet indices carrying springs or cracks
        self.num_facets = len(self.facets)
        self.cells = np.column_stack([c0[keep], c1[keep]]).astype(np.int32)
        self.is_crack = crack_mask[self.facets]
        self.glue_facets = interior[~keep]
        self.owned = self.facets < fmap.size_local
        self.state = np.where(self.is_crack, FacetState.TENSILE, FacetState.INTACT).astype(np.int8)

    def _facet_geometry(self) -> None:
        mesh, tdim, gdim = self.mesh, self.mesh.topology.dim, self.gdim
        # DOLFINx divides by the entity count: a rank without interfaces must not ask
        nverts = tdim
        if self.num_facets:
            nodes = dolfinx.mesh.entities_to_geometry(mesh, tdim - 1, self.facets, False)
        else:
            nodes = np.zeros((0, nverts), dtype=np.int32)
        x = mesh.geometry.x[nodes][..., :gdim]  # (F, nverts, gdim)
        self.vertex_coords = mesh.geometry.x[nodes]
        self.midpoints = self.vertex_coords.mean(axis=1)
        if gdim == 2:
            t = x[:, 1] - x[:, 0]
            self.areas = np.linalg.norm(t, axis=1)
            normals = np.column_stack([t[:, 1], -t[:, 0]])
        else:
            cr = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
            self.areas = 0.5 * np.linalg.norm(cr, axis=1)
            normals = cr
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        # orient n+ out of the first cell
        cmid = (
            dolfinx.mesh.compute_midpoints(mesh, tdim, self.cells[:, 0])[:, :gdim]
            if self.num_facets
            else np.zeros((0, gdim))
        )
        flip = np.einsum("ij,ij->i", normals, self.midpoints[:, :gdim] - cmid) < 0.0
        normals[flip] *= -1.0
        self.normals = normals
        hc = (
            mesh.h(tdim, self.cells.reshape(-1)).reshape(-1, 2)
            if self.num_facets
            else np.zeros((0, 2))
        )
        self.h = hc.mean(axis=1)
        self.kn = self.model.alpha * self.material.youngs_modulus / self.h
        self.ks = self.kn * self.model.shear_stiffness_ratio(self.material.poisson_ratio)
        inputs = mesh.geometry.input_global_indices
        self.vertex_ids = np.asarray(inputs)[nodes].astype(np.int64)

    def _strengths(self) -> None:
        m = self.model
        if m.weibull_modulus is None:
            self.t0 = np.full(self.num_facets, m.tensile_strength)
            self.c0 = np.full(self.num_facets, m.cohesion)
        else:
            u1 = stable_facet_hash(self.vertex_ids, m.seed)
            u2 = stable_facet_hash(self.vertex_ids, m.seed + 7919)
            self.t0 = weibull_scatter(m.tensile_strength, m.weibull_modulus, u1)
            self.c0 = weibull_scatter(m.cohesion, m.weibull_modulus, u2)

    def _boundary_conditions(
        self, rollers: Mapping[str, int], fixed: Sequence[str]
    ) -> list[dolfinx.fem.DirichletBC]:
        """Dirichlet conditions on DG dofs that lie on the named boundary facets."""
        mesh, tdim = self.mesh, self.mesh.topology.dim
        import basix

        cg = basix.create_element(
            basix.ElementFamily.P, mesh.basix_cell(), self.degree, basix.LagrangeVariant.gll_warped
        )
        closure = cg.entity_closure_dofs[tdim - 1]
        c2f = mesh.topology.connectivity(tdim, tdim - 1)
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        bcs = []
        items = [(name, comp) for name, comp in rollers.items()]
        items += [(name, c) for name in fixed for c in range(self.gdim)]
        for name, comp in items:
            if not 0 <= comp < self.gdim:
                raise ValueError(f"roller component for {name!r} must be in [0, {self.gdim})")
            sub = self.V.sub(comp)
            dofs = []
            for f in self.tmesh.facets(name):
                for c in f2c.links(f):
                    local = int(np.flatnonzero(c2f.links(c) == f)[0])
                    cell_dofs = sub.dofmap.cell_dofs(c)
                    dofs.extend(cell_dofs[closure[local]])
            dofs_arr = np.unique(np.asarray(dofs, dtype=np.int32))
            bcs.append(dolfinx.fem.dirichletbc(dolfinx.default_scalar_type(0.0), dofs_arr, sub))
        return bcs

    # ------------------------------------------------------------------ forms

    def interface_tags(self) -> dolfinx.mesh.MeshTags:
        """Tag interface facets by their integral: SPRING, OPEN_FACETS, SLIP_FACETS or GLUE."""
        broken = self.state != FacetState.INTACT
        values = np.full(self.num_facets, SPRING, dtype=np.int32)
        values[broken & (self.contact == OPEN)] = OPEN_FACETS
        values[broken & (self.contact == SLIP)] = SLIP_FACETS
        idx = np.concatenate([self.facets, self.glue_facets]).astype(np.int32)
        vals = np.concatenate([values, np.full(len(self.glue_facets), GLUE, dtype=np.int32)])
        order = np.argsort(idx)
        return dolfinx.mesh.meshtags(self.mesh, self.mesh.topology.dim - 1, idx[order], vals[order])

    def facet_dofs(self, shape: tuple[int, ...] = ()) -> np.ndarray:
        """Dofs of the Crouzeix-Raviart space of ``shape`` at this rank's interface facets."""
        if shape not in self._cr_cache:
            self.facet_function(np.zeros((self.num_facets, *shape)), shape)
        return self._cr_cache[shape][1]

    def facet_function(
        self, values: np.ndarray, shape: tuple[int, ...] = ()
    ) -> dolfinx.fem.Function:
        """Return per-facet values as a Crouzeix-Raviart function (exact at facet midpoints)."""
        if shape not in self._cr_cache:
            V = dolfinx.fem.functionspace(self.mesh, ("CR", 1, shape) if shape else ("CR", 1))
            self._cr_cache[shape] = (V, self._cr_dofs(V))
        V, dofs = self._cr_cache[shape]
        f = dolfinx.fem.Function(V)
        bs = V.dofmap.index_map_bs
        f.x.array.reshape(-1, bs)[dofs] = np.asarray(values).reshape(len(dofs), bs)
        f.x.scatter_forward()
        return f

    def _cr_dofs(self, V: dolfinx.fem.FunctionSpace) -> np.ndarray:
        tdim = self.mesh.topology.dim
        c2f = self.mesh.topology.connectivity(tdim, tdim - 1)
        c = self.cells[:, 0]
        local = np.array(
            [
                int(np.flatnonzero(c2f.links(ci) == f)[0])
                for ci, f in zip(c, self.facets, strict=True)
            ]
        )
        return np.array(
            [V.dofmap.cell_dofs(int(ci))[li] for ci, li in zip(c, local, strict=True)],
            dtype=np.int32,
        )

    def _forms(self, loads_a: Loads, loads_b: Loads | None) -> tuple:
        mesh, gdim = self.mesh, self.gdim
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        n = ufl.FacetNormal(mesh)
        npl = n("+")
        dS = ufl.Measure("dS", domain=mesh, subdomain_data=self.interface_tags())
        h = ufl.avg(ufl.CellDiameter(mesh))
        # stiffness factors as Constants: changing alpha or the rock never recompiles
        kn = self._c_kn / h
        ks = kn * self._c_ratio
        eye = ufl.Identity(gdim)
        Pn = ufl.outer(npl, npl)
        K = kn * Pn + ks * (eye - Pn)
        ju, jv = ufl.jump(u), ufl.jump(v)

        a = ufl.inner(stress(u, self.material), strain(v)) * ufl.dx
        a += ufl.inner(K * ju, jv) * dS(SPRING)
        a += ufl.inner(kn * Pn * ju, jv) * dS(SLIP_FACETS)
        # a residual spring on open and sliding faces keeps detached blocks attached
        a += self._c_residual * ufl.inner(K * ju, jv) * dS(OPEN_FACETS)
        a += self._c_residual * ks * ufl.inner((eye - Pn) * ju, jv) * dS(SLIP_FACETS)
        # Nitsche glue outside the zone (symmetric interior penalty)
        a += (
            -ufl.inner(ufl.avg(stress(u, self.material)) * npl, jv)
            - ufl.inner(ufl.avg(stress(v, self.material)) * npl, ju)
            + self._c_glue / h * ufl.inner(ju, jv)
        ) * dS(GLUE)

        rhs = [self._rhs(loads, v, n, dS) for loads in ([loads_a] + ([loads_b] if loads_b else []))]
        return a, rhs

    def _rhs(self, loads: Loads, v, n, dS) -> ufl.Form:
        """Load form; every number is a Constant so new load values never recompile."""
        mesh, gdim = self.mesh, self.gdim
        scalar = dolfinx.default_scalar_type

        def const(value: float | np.ndarray) -> dolfinx.fem.Constant:
            return dolfinx.fem.Constant(mesh, np.asarray(value, dtype=scalar))

        sigma0 = const(loads.in_situ_factor * self.sigma0)
        eye = ufl.Identity(gdim)
        L = ufl.inner(const(np.zeros(gdim)), v) * ufl.dx
        for name, p in loads.cavity.items():
            if not math.isfinite(p):
                raise ValueError(f"cavity pressure on {name!r} must be finite, got {p!r}")
            L += -ufl.inner((const(p) * eye + sigma0) * n, v) * self.tmesh.ds(name)
        npl = n("+")
        if np.isscalar(loads.crack_pressure):
            p_crack = const(float(loads.crack_pressure))  # type: ignore[arg-type]
            L += -ufl.inner((p_crack * eye + sigma0) * npl, ufl.jump(v)) * dS(OPEN_FACETS)
        else:
            pf = self.facet_function(np.asarray(loads.crack_pressure))
            L += -ufl.inner((pf("+") * eye + sigma0) * npl, ufl.jump(v)) * dS(
                OPEN_FACETS, metadata={"quadrature_degree": 1}
            )
        has_joints = loads.joint_pressure is not None and bool(np.any(loads.joint_pressure))
        if self.comm.allreduce(has_joints, op=MPI.LOR):  # collective, as below
            jf = self.facet_function(
                np.zeros(len(self.facets))
                if loads.joint_pressure is None
                else np.asarray(loads.joint_pressure)
            )
            L += -ufl.inner(jf("+") * npl, ufl.jump(v)) * dS(
                SPRING, metadata={"quadrature_degree": 1}
            )
        # collective decision: building the facet function is collective
        any_slip = self.comm.allreduce(bool(np.any(self.contact == SLIP)), op=MPI.LOR)
        if any_slip and loads.in_situ_factor != 0.0:
            # friction minus in-situ shear on sliding faces, per facet (+ side); a unit
            # load (no in-situ part) is the linearisation about the current slip set
            tf = self.facet_function(self.friction_traction, (gdim,))
            tau0 = sigma0 * npl - ufl.inner(sigma0 * npl, npl) * npl
            L += ufl.inner(tf("+") - tau0, ufl.jump(v)) * dS(
                SLIP_FACETS, metadata={"quadrature_degree": 1}
            )
        return L

    # ------------------------------------------------------------------ solve

    def _ksp(self, A: PETSc.Mat) -> PETSc.KSP:
        if self.solver_kind == "direct":
            # K is symmetric (SIPG glue, symmetric springs, symmetric Dirichlet rows and
            # columns): MUMPS LDL^T factorises it in about half the time of LU
            defaults: dict[str, object] = dict(DIRECT_CHOLESKY)
            A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        else:
            defaults = {"ksp_type": "cg", "pc_type": "gamg", "ksp_rtol": 1e-10, "ksp_max_it": 2000}
            A.setNearNullSpace(self._rigid_modes())
        return create_ksp(A, self.prefix, {**defaults, **self.petsc_options}, self.comm)

    def _rigid_modes(self) -> PETSc.NullSpace:
        """Rigid-body modes of the DG displacement, for the algebraic multigrid."""
        x = self.V.tabulate_dof_coordinates()
        gdim = self.gdim
        modes = [
            dolfinx.la.vector(self.V.dofmap.index_map, gdim) for _ in range(3 if gdim == 2 else 6)
        ]
        arrays = [m.array.reshape(-1, gdim) for m in modes]
        for k in range(gdim):
            arrays[k][:, k] = 1.0
        if gdim == 2:
            arrays[2][:, 0], arrays[2][:, 1] = -x[:, 1], x[:, 0]
        else:
            arrays[3][:, 0], arrays[3][:, 1] = -x[:, 1], x[:, 0]
            arrays[4][:, 0], arrays[4][:, 2] = x[:, 2], -x[:, 0]
            arrays[5][:, 2], arrays[5][:, 1] = x[:, 1], -x[:, 2]
        dolfinx.la.orthonormalize(modes)
        self._modes = modes  # PETSc keeps references to the vectors only
        return PETSc.NullSpace().create(vectors=[m.petsc_vec for m in modes], comm=self.comm)

    def factorize(self) -> tuple[dolfinx.fem.Form, PETSc.KSP]:
        """Assemble the stiffness of the current interface states; return its form and solver.

        The caller owns the KSP (destroy it when done); :meth:`solve_load` reuses it
        for any number of right-hand sides.
        """
        t0 = time.perf_counter()
        a, _ = self._forms(Loads(), None)
        a_form = dolfinx.fem.form(a)
        A = dolfinx.fem.petsc.assemble_matrix(a_form, bcs=self._bcs)
        A.assemble()
        if self.solver_kind == "direct":
            # factorised here, with more room if MUMPS's dynamic scheduling needs it
            ksp = setup_factorisation(lambda: self._ksp(A), self.comm)
        else:
            ksp = self._ksp(A)
        A.destroy()  # the KSP keeps its own reference
        self.solve_seconds += time.perf_counter() - t0
        return a_form, ksp

    def solve_load(
        self,
        ksp: PETSc.KSP,
        a_form: dolfinx.fem.Form,
        L_form: dolfinx.fem.Form,
        target: dolfinx.fem.Function,
    ) -> None:
        """Solve ``K target = L`` with a factorised ``ksp`` (from :meth:`factorize`)."""
        t0 = time.perf_counter()
        b = dolfinx.fem.petsc.assemble_vector(L_form)
        dolfinx.fem.petsc.apply_lifting(b, [a_form], bcs=[self._bcs])
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, self._bcs)
        ksp.solve(b, target.x.petsc_vec)
        target.x.scatter_forward()
        b.destroy()
        check_ksp(
            ksp,
            "CDEM solve",
            "a failed factorisation means a block may be detached (raise "
            "InterfaceModel.residual_stiffness) or held by no boundary condition; "
            "an iterative solve that does not converge wants the direct solver",
        )
        if not np.all(np.isfinite(target.x.array)):
            raise FloatingPointError(
                "CDEM solve produced non-finite displacements: check that every block is "
                "held (rollers/fixed faces) and that alpha is not extreme"
            )
        self.solve_seconds += time.perf_counter() - t0

    def load_form(self, loads: Loads) -> dolfinx.fem.Form:
        """Compiled right-hand side of ``loads`` for the current interface states."""
        v = ufl.TestFunction(self.V)
        n = ufl.FacetNormal(self.mesh)
        dS = ufl.Measure("dS", domain=self.mesh, subdomain_data=self.interface_tags())
        return dolfinx.fem.form(self._rhs(loads, v, n, dS))

    def solve(self, loads: Loads, unit: Loads | None = None) -> None:
        """Solve for ``loads`` (and, with the same matrix, for ``unit`` into ``u_unit``)."""
        a_form, ksp = self.factorize()
        for item, target in zip((loads, unit), (self.u, self._u_unit), strict=True):
            if item is not None:
                self.solve_load(ksp, a_form, self.load_form(item), target)
        ksp.destroy()
        self.solves += 1

    # ------------------------------------------------------------- interfaces

    def _jumps(self, u: dolfinx.fem.Function, x: np.ndarray | None = None) -> np.ndarray:
        """Displacement jump u+ - u- at one point per facet (default: midpoints)."""
        x = self.midpoints if x is None else x
        up = u.eval(x, self.cells[:, 0]) if len(x) else np.zeros((0, self.gdim))
        um = u.eval(x, self.cells[:, 1]) if len(x) else np.zeros((0, self.gdim))
        return np.asarray(up - um).reshape(-1, self.gdim)

    def snapshot(
        self, loads: Loads, u: dolfinx.fem.Function | None = None, points: np.ndarray | None = None
    ) -> InterfaceSnapshot:
        """Return openings and tractions at one point per facet (default: midpoints)."""
        u = u or self.u
        jump = self._jumps(u, points)
        n = self.normals
        s0 = loads.in_situ_factor * self.sigma0
        t0 = np.einsum("ij,fj->fi", s0, n)
        t0n = np.einsum("fi,fi->f", t0, n)
        jn = np.einsum("fi,fi->f", jump, n)
        jt = jump - jn[:, None] * n
        w = -jn
        intact_like = (self.state == FacetState.INTACT) | (self.contact != OPEN)
        tn = np.where(intact_like, t0n + self.kn * w, -self._crack_pressure(loads))
        tau_vec = np.where(
            ((self.state == FacetState.INTACT) | (self.contact == STICK))[:, None],
            (t0 - t0n[:, None] * n) - self.ks[:, None] * jt,
            np.where((self.contact == SLIP)[:, None], self.friction_traction, 0.0),
        )
        # physical aperture of an open facet: the pre-compression offset removed
        offset = np.where(t0n < 0.0, -t0n / self.kn, 0.0)
        opening = np.where(intact_like, w, np.maximum(w - offset * (~self.is_crack), 0.0))
        return InterfaceSnapshot(
            opening=opening,
            slip=np.linalg.norm(jt, axis=1),
            normal_traction=tn,
            shear_traction=np.linalg.norm(tau_vec, axis=1),
            shear_vector=tau_vec,
        )

    def _crack_pressure(self, loads: Loads) -> np.ndarray:
        return np.broadcast_to(np.asarray(loads.crack_pressure, dtype=float), (self.num_facets,))

    def update_contact(self, loads: Loads) -> int:
        """Open/close/slip switches of broken facets; returns the global count of changes."""
        snap = self.snapshot(loads)
        broken = (self.state != FacetState.INTACT) & ~self.is_crack
        pc = self._crack_pressure(loads)
        old = self.contact.copy()
        mu = self.model.friction
        # closed facets open when their normal traction exceeds the fluid pressure
        closed = broken & (self.contact != OPEN)
        opening = closed & (snap.normal_traction > -pc)
        self.contact[opening] = OPEN
        # open facets close when the faces interpenetrate
        t0n = np.einsum(
            "fi,ij,fj->f", self.normals, loads.in_situ_factor * self.sigma0, self.normals
        )
        w_raw = -np.einsum("fi,fi->f", self._jumps(self.u), self.normals)
        offset = np.where(t0n < 0.0, -t0n / self.kn, 0.0)
        closing = broken & (old == OPEN) & (w_raw < offset)
        self.contact[closing] = STICK
        # stick/slip by Coulomb on closed facets
        closed = broken & (self.contact != OPEN)
        limit = mu * np.maximum(-snap.normal_traction, 0.0)
        trial = snap.shear_vector
        mag = np.linalg.norm(trial, axis=1)
        sliding = closed & (mag > limit * (1.0 + 1e-9))
        self.contact[closed & ~sliding & (old != SLIP)] = STICK
        self.contact[sliding] = SLIP
        with np.errstate(invalid="ignore", divide="ignore"):
            direction = np.where(mag[:, None] > 0.0, trial / mag[:, None], 0.0)
        self.friction_traction = np.where(
            (self.contact == SLIP)[:, None], direction * limit[:, None], 0.0
        )
        changed = int(np.count_nonzero((old != self.contact) & self.owned))
        return int(self.comm.allreduce(changed, op=MPI.SUM))

    def overstress(self, loads: Loads) -> tuple[np.ndarray, np.ndarray]:
        """Failure ratio and mode of the intact owned facets (others get ratio 0).

        The check runs at every strength point of a facet (its vertices, like the
        nodal springs of CDEM, or its midpoint) and keeps the worst.
        """
        ratio: np.ndarray = np.zeros(self.num_facets)
        mode: np.ndarray = np.full(self.num_facets, FacetState.TENSILE, dtype=np.int8)
        for pts in self.strength_points:
            snap = self.snapshot(loads, points=pts)
            check = check_failure(
                snap.normal_traction, snap.shear_traction, self.t0, self.c0, self.model.friction
            )
            worse = check.ratio > ratio
            ratio = np.where(worse, check.ratio, ratio)
            mode = np.where(worse, check.mode, mode)
        ratio = np.where((self.state == FacetState.INTACT) & self.owned, ratio, 0.0)
        return ratio, mode

    def break_facets(self, facets: np.ndarray, modes: np.ndarray, load_factor: float) -> None:
        """Break local ``facets`` in ``modes`` (1 tensile, 2 shear) at ``load_factor``."""
        self.state[facets] = modes
        # tensile breaks start open, shear breaks closed; update_contact corrects both
        self.contact[facets] = np.where(modes == FacetState.TENSILE, OPEN, STICK)
        self.sync_ghost_states()
        mids = self.midpoints[facets]
        self.events.append(BreakEvent(load_factor, facets, modes, mids))

    def sync_ghost_states(self) -> None:
        """Owners decide; ghosts copy (states live on facets shared by two ranks)."""
        tdim = self.mesh.topology.dim
        imap = self.mesh.topology.index_map(tdim - 1)
        vec = dolfinx.la.vector(imap, 2, dtype=np.float64)
        arr = vec.array.reshape(-1, 2)
        arr[:] = -1.0
        arr[self.facets, 0] = self.state
        arr[self.facets, 1] = self.contact
        vec.scatter_forward()
        self.state[:] = arr[self.facets, 0].astype(np.int8)
        self.contact[:] = arr[self.facets, 1].astype(np.int8)

    def equilibrate(self, loads: Loads, max_iterations: int = 200, load_factor: float = 0.0) -> int:
        """Solve, then break overstressed facets and switch contacts until nothing changes.

        Returns the number of facets broken (global). Raises RuntimeError with a
        diagnostic when the active set does not settle in ``max_iterations``.
        """
        broken_total = 0
        t0 = time.perf_counter()
        for iteration in range(max_iterations):
            if self.progress is not None and iteration and iteration % 10 == 0:
                counts = self.broken_counts()
                self.progress(
                    f"  iteration {iteration}: {counts['tensile']} tensile, "
                    f"{counts['shear']} shear, "
                    f"{self.solves} solves, {time.perf_counter() - t0:.1f} s"
                )
            self.solve(loads)
            ratio, mode = self.overstress(loads)
            keys = self.midpoints
            chosen = select_breaking(
                ratio, keys, self.model.break_rule, self.model.max_breaks, self.comm
            )
            n_break = int(self.comm.allreduce(len(chosen), op=MPI.SUM))
            if n_break:
                self.break_facets(chosen, mode[chosen], load_factor)
                broken_total += n_break
                continue
            if self.update_contact(loads) == 0:
                return broken_total
            self.sync_ghost_states()
        raise RuntimeError(
            f"interface states did not settle in {max_iterations} iterations "
            f"({broken_total} facets broke); try break_rule='all' or a smaller load step"
        )

    def ramp(
        self,
        base: Loads,
        unit: Loads,
        max_factor: float,
        stop_after_first: bool = True,
        samples: int = 32,
        max_iterations: int = 200,
    ) -> float | None:
        """Raise ``base + lam * unit`` from 0 to ``max_factor``, breaking interfaces on the way.

        Exploits linearity between events: two solves with one matrix give
        ``u(lam) = u_base + lam u_unit``, and the critical ``lam`` of every intact
        facet is found by sampling and bisection; at each critical level the
        states are equilibrated (:meth:`equilibrate`).  With ``stop_after_first``
        the ramp ends at the first break.  Returns the load factor of the first
        break, or None if nothing breaks up to ``max_factor``.
        """
        lam = 0.0
        first: float | None = None
        while lam < max_factor:
            self.solve(base, unit)
            crit = self._critical_factor(base, unit, lam, max_factor, samples)
            local_min = float(crit.min()) if crit.size else math.inf
            lam_star = self.comm.allreduce(local_min, op=MPI.MIN)
            if not math.isfinite(lam_star):
                break
            first = lam_star if first is None else first
            lam = lam_star * (1.0 + 1e-9)
            loads = combine(base, unit, lam)
            self.u.x.array[:] += lam * self._u_unit.x.array
            self.equilibrate(loads, max_iterations=max_iterations, load_factor=lam)
            if self.progress is not None:
                counts = self.broken_counts()
                self.progress(
                    f"  load factor {lam:.6g}: {counts['tensile']} tensile, {counts['shear']} shear"
                )
            if stop_after_first:
                break
        return first

    def _critical_factor(
        self, base: Loads, unit: Loads, lam0: float, lam1: float, samples: int
    ) -> np.ndarray:
        """Smallest factor in (lam0, lam1] at which each intact owned facet fails.

        Jumps are linear in the factor, so every facet's failure ratio is a cheap
        function of it: sample, then bisect each bracket (all facets at once).
        """
        intact = (self.state == FacetState.INTACT) & self.owned
        jbs = [self._jumps(self.u, pts)[intact] for pts in self.strength_points]
        jus = [self._jumps(self._u_unit, pts)[intact] for pts in self.strength_points]
        n, kn, ks = self.normals[intact], self.kn[intact], self.ks[intact]
        t0s, c0s = self.t0[intact], self.c0[intact]
        fb, fu = base.in_situ_factor, unit.in_situ_factor
        s0n = np.einsum("ij,fj->fi", self.sigma0, n)
        mu = self.model.friction

        def ratio(lam: np.ndarray, sel: np.ndarray) -> np.ndarray:
            """Failure ratio of the facets ``sel``, each at its own factor ``lam``."""
            ns = n[sel]
            t0 = s0n[sel] * (fb + lam * fu)[:, None]
            t0n = np.einsum("fi,fi->f", t0, ns)
            worst = np.zeros(len(lam))
            for jb, ju in zip(jbs, jus, strict=True):
                jump = jb[sel] + lam[:, None] * ju[sel]
                jn = np.einsum("fi,fi->f", jump, ns)
                tn = t0n - kn[sel] * jn
                jt = jump - jn[:, None] * ns
                tau = np.linalg.norm((t0 - t0n[:, None] * ns) - ks[sel][:, None] * jt, axis=1)
                worst = np.maximum(worst, check_failure(tn, tau, t0s[sel], c0s[sel], mu).ratio)
            return worst

        count = len(n)
        lo = np.full(count, lam0)
        hi = np.full(count, np.inf)
        # sample: bracket each facet's first failure, looking only at unbracketed ones
        for lam in np.linspace(lam0, lam1, samples + 1)[1:]:
            sel = np.flatnonzero(~np.isfinite(hi))
            if len(sel) == 0:
                break
            failed = ratio(np.full(len(sel), lam), sel) >= 1.0
            hi[sel[failed]] = lam
            lo[sel[~failed]] = lam
        # bisect every bracket at once
        todo = np.flatnonzero(np.isfinite(hi))
        a, b = lo[todo], hi[todo]
        if len(todo):
            for _ in range(60):
                mid = 0.5 * (a + b)
                over = ratio(mid, todo) >= 1.0
                b = np.where(over, mid, b)
                a = np.where(over, a, mid)
        crit = np.full(count, np.inf)
        crit[todo] = b
        return crit

    # ---------------------------------------------------------------- results

    def fracture_degree(self) -> float:
        """Broken interface area / breakable interface area (pre-existing cracks excluded)."""
        breakable = self.owned & ~self.is_crack
        broken = breakable & (self.state != FacetState.INTACT)
        num = self.comm.allreduce(float(self.areas[broken].sum()), op=MPI.SUM)
        den = self.comm.allreduce(float(self.areas[breakable].sum()), op=MPI.SUM)
        return num / den if den > 0 else 0.0

    def broken_counts(self) -> dict[str, int]:
        """Global numbers of tensile and shear failures (pre-existing cracks excluded)."""
        mask = self.owned & ~self.is_crack
        tensile = int(np.count_nonzero(mask & (self.state == FacetState.TENSILE)))
        shear = int(np.count_nonzero(mask & (self.state == FacetState.SHEAR)))
        return {
            "tensile": self.comm.allreduce(tensile, op=MPI.SUM),
            "shear": self.comm.allreduce(shear, op=MPI.SUM),
        }

    def state_tags(self) -> dolfinx.mesh.MeshTags:
        """Failure state per interface (0 intact, 1 tensile, 2 shear) as facet tags."""
        order = np.argsort(self.facets)
        return dolfinx.mesh.meshtags(
            self.mesh,
            self.mesh.topology.dim - 1,
            self.facets[order].astype(np.int32),
            self.state[order].astype(np.int32),
        )

    def total_stress(self) -> ufl.core.expr.Expr:
        """Total stress sigma0 + C : eps(u) (tension positive)."""
        return ufl.as_matrix(self.sigma0.tolist()) + stress(self.u, self.material)


def combine(base: Loads, unit: Loads, lam: float) -> Loads:
    """Return ``base + lam * unit`` (cavity pressures, crack pressure, in-situ factor)."""
    cavity = dict(base.cavity)
    for name, p in unit.cavity.items():
        cavity[name] = cavity.get(name, 0.0) + lam * p
    return Loads(
        cavity=cavity,
        crack_pressure=np.asarray(base.crack_pressure) + lam * np.asarray(unit.crack_pressure)
        if not (np.isscalar(base.crack_pressure) and np.isscalar(unit.crack_pressure))
        else float(base.crack_pressure) + lam * float(unit.crack_pressure),  # type: ignore[arg-type]
        in_situ_factor=base.in_situ_factor + lam * unit.in_situ_factor,
    )


__all__ = [
    "AUTO_DIRECT_MAX_DOFS",
    "BreakEvent",
    "CDEMSolid",
    "InterfaceSnapshot",
    "Loads",
    "ZoneMarker",
    "combine",
]
