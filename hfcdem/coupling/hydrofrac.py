"""Fluid-driven fracturing: the CDEM solid coupled to flow in its fractures and cavity.

Unknowns and equations (implicit Euler, one step ``dt``):

- The solid is linear between interface events, so its response to fluid
  pressure is condensed: with the stiffness factorised once per event,
  ``u = u_base + sum_g p_g u_g`` where ``u_g`` answers a unit pressure on the
  open facets (and walls) of pressure group ``g``.  The void volume of every
  fracture facet and the cavity volume are then linear in the group pressures:
  ``V = V0 + H p``, exactly the work-conjugate of the pressure loads.
- Fluid content is tracked as volume at the reference density,
  ``M = V (1 + p / Kw)``.  Each wet group satisfies
  ``M_g(p) - M_g^n - dt (sum of inflows) - injected + leaked = 0``; fluxes follow
  the cubic law on the :class:`~hfcdem.flow.network.Network`.
- Filling (``filling="saturation"``, the seed paper's eqs. (14)-(19)): a dry
  facet is at zero pressure with saturation ``S = M / V``; it gains fluid from
  wet neighbours through ``ks = S^2 (3 - 2S)`` and turns wet when full.  With
  ``filling="no_lag"`` every broken facet joined to the cavity is wet at once.
- ``fidelity="uniform"`` collapses the cavity and every facet joined to it into
  one pressure group (one solve per event): the cheap setting for
  storage/toughness-dominated scenes.

The small nonlinear system of group pressures is solved by PETSc SNES (Newton,
line search, finite-difference Jacobian).  After each converged step the
interfaces are checked: contacts that switch, or facets that break, change the
stiffness, so the operator is rebuilt and the step repeated until nothing
changes.  The step size adapts: cut on divergence, grown when easy.  Every step
records mass balance: injected = fluid in cavity + fractures + leaked.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.flow.fluid import CarterLeakOff, Fluid, Injection
from hfcdem.flow.network import Network, build_network, gather_rows
from hfcdem.io.files import write_csv
from hfcdem.solid.cdem import OPEN, OPEN_FACETS, SPRING, CDEMSolid, Loads
from hfcdem.solid.interfaces import FacetState, select_breaking

# a floor on storage and aperture keeps a closed, dry facet's equations regular
_APERTURE_FLOOR = 1e-9  # m
# rounds of contact switches in one step's state loop that may open faces (see _try_step)
_CONTACT_ROUNDS = 1


class SimulationStopped(RuntimeError):
    """The coupled run could not continue; the history so far is kept."""


@dataclass(frozen=True)
class FlowSettings:
    """How the fluid is modelled and stepped (SI units).

    ``cavity``: facet groups of the cavity walls (wellbore, tunnels); fluid is
    injected into the cavity.  ``injection_point``: a point (a mesh vertex is
    chosen) where fluid enters when there is no cavity, e.g. a KGD inlet.
    ``cavity_volume`` defaults to the volume the walls enclose in the mesh
    (symmetry planes through the origin); ``extra_volume`` adds storage outside
    the model (the rest of the wellbore and lines).
    ``breaks_need_fluid``: an interface may break only next to fluid (a wet
    fracture facet or the cavity), the pressurisation rule of seed 000.
    ``wet_wall_joints``: the intact interfaces that meet the cavity wall along an
    edge (a vertex in 2D) hold fluid at the cavity pressure, so they break on
    effective stress (p - sigma_n >= T0); the paper's CDEM lets fluid into its
    wall joints through their initial opening.
    ``permeate_joints`` (with ``wet_wall_joints``): the fluid also stands in the
    intact interfaces along every open crack at the cavity pressure, so it
    permeates the joints ahead of the fracture as it grows (the paper's
    saturation front through its joints, taken as instantaneous).
    ``rigid_cavity``: the stored cavity volume ignores the wall motion (the
    pressure still loads the wall): the paper's CDEM stores fluid only in its
    joints, so its pressurisation rate is Kw Q / V alone.
    """

    cavity: tuple[str, ...] = ()
    injection_point: tuple[float, ...] | None = None
    fidelity: str = "viscous"
    filling: str = "saturation"
    cavity_volume: float | None = None
    extra_volume: float = 0.0
    initial_pressure: float = 0.0
    breaks_need_fluid: bool = True
    wet_wall_joints: bool = False
    permeate_joints: bool = False
    rigid_cavity: bool = False
    leak_off: CarterLeakOff | None = None
    dt_initial: float = 0.01
    dt_min: float = 1e-9
    dt_max: float = math.inf
    dt_growth: float = 1.5
    max_state_iterations: int = 100
    break_tolerance: float = 0.01
    max_pressure_change: float = math.inf
    max_breaks_per_iteration: int | None = None
    newton_tolerance: float = 1e-10
    max_newton_iterations: int = 40

    def __post_init__(self) -> None:
        if self.fidelity not in ("viscous", "uniform"):
            raise ValueError(f"fidelity must be 'viscous' or 'uniform', got {self.fidelity!r}")
        if self.filling not in ("saturation", "no_lag"):
            raise ValueError(f"filling must be 'saturation' or 'no_lag', got {self.filling!r}")
        if not self.cavity and self.injection_point is None:
            raise ValueError(
                "give the cavity wall groups or an injection_point: fluid needs a way in"
            )
        for name in ("dt_initial", "dt_min", "dt_max"):
            value = getattr(self, name)
            if not value > 0.0:
                raise ValueError(f"{name} must be a positive time in s, got {value!r}")
        if self.dt_min > self.dt_initial:
            raise ValueError("dt_min must not exceed dt_initial")
        if not 1.0 <= self.dt_growth <= 10.0:
            raise ValueError(f"dt_growth must be in [1, 10], got {self.dt_growth!r}")
        if self.cavity_volume is not None and not self.cavity_volume >= 0.0:
            raise ValueError(f"cavity_volume must be >= 0 m^3, got {self.cavity_volume!r}")
        if not (math.isfinite(self.extra_volume) and self.extra_volume >= 0.0):
            raise ValueError(f"extra_volume must be >= 0 m^3, got {self.extra_volume!r}")
        if not math.isfinite(self.initial_pressure):
            raise ValueError("initial_pressure must be a finite pressure in Pa")
        if not 0.0 < self.newton_tolerance < 1e-3:
            raise ValueError("newton_tolerance must be in (0, 1e-3) (relative volume)")


@dataclass
class StepRecord:
    """One accepted time step (SI units, global values)."""

    time: float
    dt: float
    injection_pressure: float
    injected_volume: float
    cavity_fluid: float
    fracture_fluid: float
    fracture_volume: float
    leaked_volume: float
    mass_error: float  # |injected - fluid held - leaked| / injected (bookkeeping)
    volume_mismatch: float  # |fluid held - compressed void volume| / injected (solver)
    wet_facets: int
    tensile: int
    shear: int
    fracture_degree: float
    newton_iterations: int
    rebuilds: int
    wall_time: float

    def as_row(self) -> dict[str, float]:
        """Return the record as a flat dict (the columns of history.csv)."""
        return dict(self.__dict__)

    @classmethod
    def from_row(cls, row: dict[str, float]) -> StepRecord:
        """Return the record of a row of history.csv (counts back to integers)."""
        kinds = {f.name: f.type for f in fields(cls)}
        values: dict[str, Any] = {
            k: int(v) if kinds[k] in (int, "int") else float(v) for k, v in row.items()
        }
        return cls(**values)


def relative_permeability(saturation: np.ndarray) -> np.ndarray:
    """Seed eq. (14): ks = S^2 (3 - 2S), S clipped to [0, 1]."""
    s = np.clip(saturation, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


@dataclass
class _Operator:
    """The condensed solid for the current interface states."""

    base: dolfinx.fem.Function
    columns: list[dolfinx.fem.Function]
    v0: np.ndarray  # (n,) void volume of each facet at zero pressure
    h: np.ndarray  # (n, m) d void / d group pressure
    vc0: float
    hc: np.ndarray  # (m,)


@dataclass
class HydraulicFracture:
    """Inject into a :class:`CDEMSolid` and follow breakdown and fracture growth."""

    solid: CDEMSolid
    fluid: Fluid
    injection: Injection
    settings: FlowSettings
    progress: Callable[[str], None] | None = None
    history: list[StepRecord] = field(default_factory=list)

    def __post_init__(self) -> None:
        s, solid = self.settings, self.solid
        self.comm: MPI.Comm = solid.comm
        self.gdim = solid.gdim
        self.t = 0.0
        self.dt = s.dt_initial
        self.injected = 0.0
        self.leaked = 0.0
        self.rebuilds = 0
        self.rebuild_seconds = 0.0
        self.first_break_time: float | None = None
        self.initial_failures = 0
        self._last_ratio = 0.0  # worst failure ratio of eligible facets, last accepted step
        self._step_ratio = 0.0
        self._event_cuts = 0
        self.wall_start = time.perf_counter()
        for name in s.cavity:
            solid.tmesh.facet_tag(name)  # clear error for unknown groups
        self._cavity_vertices = self._find_cavity_vertices()
        self._cavity_point = self._mean_point(self._cavity_vertices)
        self.cavity_volume = (
            s.cavity_volume if s.cavity_volume is not None else self._mesh_cavity_volume()
        ) + s.extra_volume
        # fluid state per facet key (survives network rebuilds)
        self._content: dict[tuple[int, ...], float] = {}
        self._wet_since: dict[tuple[int, ...], float] = {}
        self._pressure: dict[tuple[int, ...], float] = {}
        self.p_cavity = s.initial_pressure
        self._wall_joints = self._find_wall_joints()
        self._cav_form = self._cavity_load_form()
        self._cavity_reference: float | None = None
        self._rebuild()
        self._initialise_fluid()

    # ------------------------------------------------------------ geometry

    def _local_vertex_ids(self, facets: np.ndarray) -> np.ndarray:
        mesh, tdim = self.solid.mesh, self.solid.mesh.topology.dim
        if len(facets) == 0:  # entities_to_geometry divides by the count
            return np.zeros((0, tdim), dtype=np.int64)
        nodes = dolfinx.mesh.entities_to_geometry(mesh, tdim - 1, facets.astype(np.int32), False)
        return np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[nodes]

    @property
    def cavity_vertices(self) -> np.ndarray:
        """Global ids of the mesh vertices on the cavity walls."""
        return self._cavity_vertices

    @property
    def wall_joints(self) -> np.ndarray:
        """Per interface facet: True where it holds the cavity's fluid (a wet wall joint)."""
        return self._wall_joints

    def rebuild(self) -> None:
        """Refactorise the solid and recondense for the current interface states.

        Runs of :meth:`step` call it at every interface event; a benchmark calls it
        to time one event.
        """
        self._rebuild()

    def _find_cavity_vertices(self) -> np.ndarray:
        tm = self.solid.tmesh
        ids = [self._local_vertex_ids(tm.facets(name)).reshape(-1) for name in self.settings.cavity]
        local = np.unique(np.concatenate(ids)) if ids else np.zeros(0, dtype=np.int64)
        if self.settings.injection_point is not None:
            x = self.solid.mesh.geometry.x
            pt = np.zeros(3)
            ip = np.asarray(self.settings.injection_point, dtype=float)
            pt[: len(ip)] = ip
            d = np.linalg.norm(x - pt, axis=1)
            i = int(np.argmin(d)) if len(d) else -1
            best = (
                (float(d[i]), int(self.solid.mesh.geometry.input_global_indices[i]))
                if i >= 0
                else (math.inf, -1)
            )
            best = min(self.comm.allgather(best))
            local = np.append(local, best[1])
        return np.unique(gather_rows(self.comm, local.astype(np.int64)))

    def _mean_point(self, vertex_ids: np.ndarray) -> np.ndarray:
        geo = self.solid.mesh.geometry
        mask = np.isin(np.asarray(geo.input_global_indices), vertex_ids)
        total = self.comm.allreduce(geo.x[mask].sum(axis=0), op=MPI.SUM)
        count = self.comm.allreduce(int(mask.sum()), op=MPI.SUM)
        return total / max(count, 1)

    def _mesh_cavity_volume(self) -> float:
        """Volume enclosed by the walls: -(1/d) int x.n ds (n out of the rock)."""
        if not self.settings.cavity:
            return 0.0
        mesh = self.solid.mesh
        x, n = ufl.SpatialCoordinate(mesh), ufl.FacetNormal(mesh)
        form = sum(
            -ufl.dot(x, n) / self.gdim * self.solid.tmesh.ds(name) for name in self.settings.cavity
        )
        local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form))
        return float(self.comm.allreduce(local, op=MPI.SUM))

    def _find_wall_joints(self) -> np.ndarray:
        """Flag the interfaces that share an edge (2D: a vertex) with the cavity wall."""
        solid = self.solid
        if not (self.settings.wet_wall_joints and self.settings.cavity):
            return np.zeros(solid.num_facets, dtype=bool)
        ids = self._cavity_vertices
        if self.settings.permeate_joints and getattr(self, "net", None) is not None:
            feeding = (self.group == 0) & (self.is_open > 0)
            if feeding.any():
                ids = np.union1d(ids, self.net.keys[feeding].reshape(-1))
        touching = np.isin(solid.vertex_ids, ids).sum(axis=1)
        return (touching >= self.gdim - 1) & ~solid.is_crack

    def _intact_wall_joints(self) -> np.ndarray:
        return self._wall_joints & (self.solid.state == FacetState.INTACT)

    def _wall_joint_term(self, v: ufl.Argument, dS: ufl.Measure | None = None) -> ufl.Form | None:
        """Return the unit pressure in the intact wall joints, -int n+.[v] dS, or None.

        ``dS`` must be the interface measure of the form the term joins (one
        subdomain_data per measure and form).
        """
        solid = self.solid
        wet = self._intact_wall_joints()
        if not self.comm.allreduce(bool(wet.any()), op=MPI.LOR):
            return None
        jw = solid.facet_function(wet.astype(float))
        nrm = ufl.FacetNormal(solid.mesh)
        if dS is None:
            dS = ufl.Measure("dS", domain=solid.mesh, subdomain_data=solid.interface_tags())
        return (
            -jw("+")
            * ufl.dot(nrm("+"), ufl.jump(v))
            * dS(SPRING, metadata={"quadrature_degree": 1})
        )

    def _cavity_load_form(self) -> dolfinx.fem.Form | None:
        """Return the unit-pressure load on the cavity, -int n.v ds (also dV = c.u).

        With wet wall joints it includes their faces while they are intact.
        """
        if not self.settings.cavity:
            return None
        v, n = ufl.TestFunction(self.solid.V), ufl.FacetNormal(self.solid.mesh)
        L = sum(-ufl.dot(n, v) * self.solid.tmesh.ds(name) for name in self.settings.cavity)
        joints = self._wall_joint_term(v)
        return dolfinx.fem.form(L if joints is None else L + joints)

    # ------------------------------------------------------------- network

    def _fracture_facets(self) -> np.ndarray:
        solid = self.solid
        return np.flatnonzero(solid.state != FacetState.INTACT)

    def _rebuild_network(self) -> None:
        solid = self.solid
        local = self._fracture_facets()
        owned = local[solid.owned[local]]
        keys = solid.vertex_ids[
            owned
        ]  # unsorted: build_network orders ids and coordinates together
        net, _ = build_network(
            self.comm,
            keys,
            solid.areas[owned],
            solid.vertex_coords[owned],
            self._cavity_vertices,
        )
        self.net: Network = net
        index = net.index()
        self._local_fracture = local
        all_keys = np.sort(solid.vertex_ids[local], axis=1)
        self._local_pos = np.array(
            [index[tuple(int(v) for v in k)] for k in all_keys], dtype=np.int64
        )
        self._owned_sel = solid.owned[local]
        # open (fluid-loaded) facets in network order
        is_open = np.zeros(net.size)
        contact_open = (solid.contact[local] == OPEN).astype(float)
        is_open[self._local_pos[self._owned_sel]] = contact_open[self._owned_sel]
        self.is_open = self.comm.allreduce(is_open, op=MPI.SUM) > 0.5
        comp = net.components()
        self.joined = comp == 0
        n = net.size
        keys_t = [tuple(int(v) for v in k) for k in net.keys]
        self._keys_t = keys_t
        self.content = np.array([self._content.get(k, 0.0) for k in keys_t])
        self.wet_since = np.array([self._wet_since.get(k, math.inf) for k in keys_t])
        self.pressure = np.array([self._pressure.get(k, 0.0) for k in keys_t])
        # pre-existing cracks joined to the cavity start full (seed 000 pre-opens them)
        at_start = getattr(self, "op", None) is None
        if self.settings.filling == "no_lag" or self.settings.fidelity == "uniform" or at_start:
            newly = self.joined & ~np.isfinite(self.wet_since)
            self.wet_since[newly] = self.t
            self.pressure[newly] = self.p_cavity
        self.wet = np.isfinite(self.wet_since)
        if n == 0:
            self.wet = np.zeros(0, dtype=bool)

    def _store_state(self) -> None:
        for i, k in enumerate(self._keys_t):
            self._content[k] = float(self.content[i])
            self._wet_since[k] = float(self.wet_since[i])
            self._pressure[k] = float(self.pressure[i])

    def _groups(self) -> np.ndarray:
        """Pressure group of each facet: 0 the cavity, -1 dry, else 1.."""
        group = np.full(self.net.size, -1, dtype=np.int64)
        if self.settings.fidelity == "uniform":
            group[self.wet] = 0
        else:
            group[self.wet] = 1 + np.arange(int(self.wet.sum()))
        return group

    # ------------------------------------------------------------ operator

    def _openings(self, u: dolfinx.fem.Function) -> np.ndarray:
        """Mean normal opening of every network facet (midpoint jump), gathered."""
        solid = self.solid
        sel = self._local_fracture[self._owned_sel]
        if len(sel):
            mid = solid.midpoints[sel]
            jump = u.eval(mid, solid.cells[sel, 0]) - u.eval(mid, solid.cells[sel, 1])
            w = -np.einsum("fi,fi->f", np.asarray(jump).reshape(-1, self.gdim), solid.normals[sel])
        else:
            w = np.zeros(0)
        out = np.zeros(self.net.size)
        out[self._local_pos[self._owned_sel]] = w
        return self.comm.allreduce(out, op=MPI.SUM)

    def _rebuild(self) -> None:
        """Factorise the solid for the current states and condense it onto the groups."""
        t0 = time.perf_counter()
        self._rebuild_network()
        solid = self.solid
        self.group = self._groups()
        if self.settings.permeate_joints:
            self._wall_joints = self._find_wall_joints()
        m = 1 + (int(self.group.max()) if self.group.size and self.group.max() > 0 else 0)
        self.m = m
        a_form, ksp = solid.factorize()
        cavity_names = {name: 0.0 for name in self.settings.cavity}
        base = dolfinx.fem.Function(solid.V)
        solid.solve_load(ksp, a_form, solid.load_form(Loads(cavity=cavity_names)), base)
        # unit pressure per group on its open facets, plus the walls for the cavity group
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
        if self.settings.cavity:
            L += sum(
                -c_cav * ufl.dot(nrm, v) * solid.tmesh.ds(name) for name in self.settings.cavity
            )
            joints = self._wall_joint_term(v, dS)
            if joints is not None:
                L += c_cav * joints
            self._cav_form = self._cavity_load_form()  # the intact joints change with breaks
        L_form = dolfinx.fem.form(L)
        cr_dofs = solid.facet_dofs()
        local_group = np.full(solid.num_facets, -2, dtype=np.int64)
        local_group[self._local_fracture] = self.group[self._local_pos]
        local_open = np.zeros(solid.num_facets, dtype=bool)
        local_open[self._local_fracture] = self.is_open[self._local_pos]
        columns = []
        for g in range(m):
            cr.x.array[:] = 0.0
            cr.x.array[cr_dofs] = ((local_group == g) & local_open).astype(float)
            cr.x.scatter_forward()
            c_cav.value = 1.0 if g == 0 else 0.0
            col = dolfinx.fem.Function(solid.V)
            solid.solve_load(ksp, a_form, L_form, col)
            columns.append(col)
        ksp.destroy()
        solid.solves += 1
        area = self.net.area
        # void volume: the mechanical opening (minus the intact pre-compression offset
        # of broken facets, as in CDEMSolid.snapshot) plus the residual aperture
        w0 = self._openings(base) - self._offsets()
        v0 = np.where(self.is_open, area * w0, 0.0) + area * self.fluid.residual_aperture
        h = np.zeros((self.net.size, m))
        hc = np.zeros(m)
        wall = 0.0  # c.u of the base state: the cavity's change from the undeformed mesh
        track = self._cav_form is not None and not self.settings.rigid_cavity
        cvec = dolfinx.fem.petsc.assemble_vector(self._cav_form) if track else None
        if cvec is not None:
            cvec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            wall = cvec.dot(base.x.petsc_vec)
        for g, col in enumerate(columns):
            h[:, g] = np.where(self.is_open, area * self._openings(col), 0.0)
            if cvec is not None:
                hc[g] = cvec.dot(col.x.petsc_vec)
        if cvec is not None:
            cvec.destroy()
        if self._cavity_reference is None:
            # the mesh (and cavity_volume) is the cavity as it stands at the start, after
            # excavation and at the initial pressure: measure wall motion from that state
            self._cavity_reference = wall + float(hc.sum()) * self.settings.initial_pressure
        vc0 = self.cavity_volume + wall - self._cavity_reference
        self.op = _Operator(base=base, columns=columns, v0=v0, h=h, vc0=vc0, hc=hc)
        self.rebuilds += 1
        self.rebuild_seconds += time.perf_counter() - t0

    def _offsets(self) -> np.ndarray:
        """Return the intact pre-compression offset of each broken facet.

        Also stores the in-situ normal stress (compression positive) per facet in
        ``self.closure_stress``.
        """
        solid = self.solid
        sel = self._local_fracture[self._owned_sel]
        n = solid.normals[sel]
        t0n = np.einsum("fi,ij,fj->f", n, solid.sigma0, n)
        off = np.where((t0n < 0.0) & ~solid.is_crack[sel], -t0n / solid.kn[sel], 0.0)
        out = np.zeros((self.net.size, 2))
        out[self._local_pos[self._owned_sel]] = np.column_stack([off, -t0n])
        out = self.comm.allreduce(out, op=MPI.SUM)
        self.closure_stress = out[:, 1]
        return out[:, 0]

    # ---------------------------------------------------------------- flow

    def _facet_pressure(self, p: np.ndarray) -> np.ndarray:
        """Pressure of every facet (dry facets 0) for group pressures (m,) or (m, k)."""
        shape = (self.net.size, *p.shape[1:])
        pf = np.zeros(shape)
        wet = self.group >= 0
        pf[wet] = p[self.group[wet]]
        return pf

    def _volumes(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.op.v0.reshape(
            -1, *([1] * (p.ndim - 1))
        ) + self.op.h @ p, self.op.vc0 + self.op.hc @ p

    def _fluxes(
        self, p: np.ndarray, vf: np.ndarray, frozen: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Flux of every connection (from its first to its second end), and saturation.

        With ``frozen`` group pressures, apertures and saturations are taken from
        that state (a Picard linearisation): the flux is then linear in ``p``.
        """
        net, fl = self.net, self.fluid
        if frozen is not None:
            vf_k, _ = self._volumes(frozen)
            vf = _col(vf_k, p) * np.ones((1,) * p.ndim)
        area = net.area.reshape(-1, *([1] * (p.ndim - 1)))
        aperture = np.maximum(vf / area - fl.residual_aperture, 0.0) + max(
            fl.residual_aperture, _APERTURE_FLOOR
        )
        trans = net.transmissibility(aperture, fl.conductivity)
        pf = self._facet_pressure(p)
        pc = p[0]
        sat = np.ones_like(vf)
        dry = self.group < 0
        sat[dry] = np.clip(
            self.content[dry].reshape(-1, *([1] * (p.ndim - 1))) / np.maximum(vf[dry], 1e-300),
            0.0,
            1.0,
        )
        fa, fb, inner = net.pair_facets
        pa = pf[fa]
        pb = np.where(_col(inner, p), pf[fb], pc)
        sa = sat[fa]
        sb = np.where(_col(inner, p), sat[fb], 1.0)
        kr = relative_permeability(0.5 * (sa + sb))
        drive = pa - pb + _col(self._gravity_drive(fa, fb, inner), p)
        return trans * kr * drive, sat

    def _gravity_drive(self, fa: np.ndarray, fb: np.ndarray, inner: np.ndarray) -> np.ndarray:
        g = self.fluid.gravity
        if g is None:
            return np.zeros(len(fa))
        gv = np.zeros(3)
        gv[: len(g)] = g
        xa = self.net.centroid[fa]
        xb = np.where(inner[:, None], self.net.centroid[fb], self._cavity_point[None, :])
        return self.fluid.density * (xb - xa) @ gv

    def _residual(
        self,
        p: np.ndarray,
        dt: float,
        source: float,
        leak: np.ndarray,
        control: bool = True,
        frozen: np.ndarray | None = None,
    ) -> np.ndarray:
        """Group residuals (volume, m^3) for group pressures (m,) or (m, k).

        ``frozen``: conductivities and compressed volumes from that state, which
        makes the residual linear in ``p`` (see :meth:`_picard`).
        """
        kw = self.fluid.bulk_modulus
        vf, vc = self._volumes(p)
        flux, _ = self._fluxes(p, vf, frozen)
        pf = self._facet_pressure(p)
        r = np.zeros(p.shape)
        wet = self.group >= 0
        area = self.net.area.reshape(-1, *([1] * (p.ndim - 1)))
        floor = area * _APERTURE_FLOOR
        if frozen is None:
            stored = vf + np.maximum(vf, floor) * pf / kw
            cav_stored = vc + np.maximum(vc, 0.0) * p[0] / kw
        else:
            vf_k, vc_k = self._volumes(frozen)
            floor_k = np.maximum(vf_k, self.net.area * _APERTURE_FLOOR)
            stored = vf + _col(floor_k, p) * pf / kw
            cav_stored = vc + max(float(vc_k), 0.0) * p[0] / kw
        np.add.at(
            r, self.group[wet], stored[wet] - self.content[wet].reshape(-1, *([1] * (p.ndim - 1)))
        )
        r[0] += cav_stored - self.cavity_content
        net = self.net
        fa, fb, inner = net.pair_facets
        ga = self.group[fa]
        gb = np.where(inner, self.group[fb], 0)
        ok = ga >= 0
        np.add.at(r, ga[ok], dt * flux[ok])
        ok = gb >= 0
        np.add.at(r, gb[ok], -dt * flux[ok])
        np.add.at(r, self.group[wet], _col(leak[wet], p))
        if self.injection.rate_controlled or not control:
            r[0] -= source
        else:
            scale = max(self.cavity_volume / kw + abs(self.op.hc[0]), 1e-30)
            r[0] = (p[0] - source) * scale
        return r

    def _picard(
        self, dt: float, source: float, leak: np.ndarray, guess: np.ndarray, atol: float
    ) -> np.ndarray:
        """Fixed-point iterations with frozen conductivity (robust, linearly convergent).

        Used to bring Newton into its basin when it fails from the last state.
        """
        p = guess.copy()
        m = len(p)
        scale = np.maximum(np.abs(p), 1e5)
        for _ in range(100):
            r0 = self._residual(np.zeros(m), dt, source, leak, frozen=p)
            cols = self._residual(np.diag(scale), dt, source, leak, frozen=p)
            jac = (cols - r0[:, None]) / scale[None, :]
            try:
                p_new = np.linalg.solve(jac, -r0)
            except np.linalg.LinAlgError:
                break
            if not np.all(np.isfinite(p_new)):
                break
            p = 0.5 * p + 0.5 * p_new
            if np.max(np.abs(self._residual(p, dt, source, leak))) < atol:
                break
        return p

    def _newton(
        self, dt: float, source: float, leak: np.ndarray, guess: np.ndarray
    ) -> tuple[np.ndarray, int, bool]:
        """Solve the group equations with SNES (Picard-started if Newton fails first)."""
        p, its, ok = self._snes(dt, source, leak, guess)
        if ok:
            return p, its, ok
        start = self._picard(dt, source, leak, guess, self._atol(source))
        p, its2, ok = self._snes(dt, source, leak, start)
        return p, its + its2 + 100, ok

    def _atol(self, source: float) -> float:
        scale = max(
            self.cavity_content
            + float(self.content.sum())
            + abs(source if self.injection.rate_controlled else 0.0),
            float(self.net.area.sum()) * _APERTURE_FLOOR,
            1e-30,
        )
        return self.settings.newton_tolerance * scale

    def _snes(
        self, dt: float, source: float, leak: np.ndarray, guess: np.ndarray
    ) -> tuple[np.ndarray, int, bool]:
        """Solve the group equations with SNES; returns pressures, iterations, converged."""
        m = self.m
        atol = self._atol(source)
        snes = PETSc.SNES().create(PETSc.COMM_SELF)
        snes.setOptionsPrefix("hfcdem_flow_")
        x = PETSc.Vec().createSeq(m)
        f = PETSc.Vec().createSeq(m)
        jac = PETSc.Mat().createDense((m, m), comm=PETSc.COMM_SELF)
        jac.setUp()

        def residual(_snes, xv, fv) -> None:
            fv.array[:] = self._residual(xv.array_r.copy(), dt, source, leak)

        def jacobian(_snes, xv, J, _P) -> None:
            p = xv.array_r.copy()
            step = 1e-7 * np.maximum(np.abs(p), 1e3)
            batch = p[:, None] + np.diag(step)
            r0 = self._residual(p, dt, source, leak)
            rb = self._residual(batch, dt, source, leak)
            J.getDenseArray()[:] = (rb - r0[:, None]) / step[None, :]
            J.assemble()

        snes.setFunction(residual, f)
        snes.setJacobian(jacobian, jac)
        snes.setType("newtonls")
        snes.getKSP().setType("preonly")
        snes.getKSP().getPC().setType("lu")
        snes.setTolerances(
            rtol=1e-14,
            atol=atol,
            stol=1e-14,
            max_it=self.settings.max_newton_iterations,
        )
        snes.setFromOptions()
        x.array[:] = guess
        try:
            with np.errstate(all="ignore"):
                snes.solve(None, x)
            ok = snes.getConvergedReason() > 0
        except PETSc.Error:  # a singular Jacobian: cut the step
            ok = False
        p = x.array_r.copy()
        its = snes.getIterationNumber()
        if not ok and np.all(np.isfinite(p)):
            # stagnation just above the tolerance (finite-difference Jacobian near a
            # closing facet) still leaves a usable state: content is conserved exactly
            ok = float(np.max(np.abs(self._residual(p, dt, source, leak)))) <= 1e4 * self._atol(
                source
            )
        ok = ok and bool(np.all(np.isfinite(p)))
        if not ok:
            r = self._residual(p, dt, source, leak) if np.all(np.isfinite(p)) else p
            self._newton_failure = (
                f"SNES reason {snes.getConvergedReason()} after {its} iterations, "
                f"|R| {np.max(np.abs(r)):.3g} m^3 vs tolerance "
                f"{atol:.3g}, "
                f"worst group {int(np.argmax(np.abs(r)))} of {m}"
            )
        for obj in (snes, x, f, jac):
            obj.destroy()
        return p, its, ok

    # ------------------------------------------------------------ stepping

    def _initialise_fluid(self) -> None:
        """Cavity (and no-lag fractures) full at the initial pressure."""
        p = np.full(self.m, self.settings.initial_pressure)
        vf, vc = self._volumes(p)
        kw = self.fluid.bulk_modulus
        self.cavity_content = float(max(float(vc), 0.0) * (1.0 + p[0] / kw))
        wet = self.group >= 0
        self.content[wet] = vf[wet] * (1.0 + p[0] / kw)
        self.pressure[wet] = p[0]
        self.initial_fluid = self.cavity_content + float(self.content.sum())
        self._store_state()

    def _guess(self, added: float = 0.0) -> np.ndarray:
        """Last pressures; at the start, the uniform pressure that stores ``added`` more."""
        if self.history or not self.injection.rate_controlled:
            guess = np.full(self.m, self.p_cavity)
            wet = self.group > 0
            guess[self.group[wet]] = self.pressure[wet]
            return guess
        wet = self.group >= 0
        stiff = float(self.op.h[wet].sum() + self.op.hc.sum())
        volume = float(self.op.v0[wet].sum()) + self.op.vc0
        held = self.cavity_content + float(self.content[wet].sum()) + added
        p = (held - volume) / stiff if stiff > 0 else self.p_cavity
        return np.full(self.m, max(p, self.p_cavity))

    def _set_displacement(self, p: np.ndarray) -> Loads:
        u = self.solid.u
        u.x.array[:] = self.op.base.x.array
        for g, col in enumerate(self.op.columns):
            u.x.array[:] += p[g] * col.x.array
        pf = self._facet_pressure(p)
        local = np.zeros(self.solid.num_facets)
        local[self._local_fracture] = pf[self._local_pos]
        cavity = {name: float(p[0]) for name in self.settings.cavity}
        joints = np.where(self._intact_wall_joints(), float(p[0]), 0.0)
        return Loads(cavity=cavity, crack_pressure=local, joint_pressure=joints)

    def _eligible(self) -> np.ndarray:
        """Intact facets allowed to break: next to fluid when the settings say so."""
        solid = self.solid
        if not self.settings.breaks_need_fluid:
            return np.ones(solid.num_facets, dtype=bool)
        # the fluid has arrived where a wet facet's pressure exceeds its closure stress
        pressure = getattr(self, "_trial_pressure", self.pressure)
        if len(pressure) != self.net.size:
            pressure = self.pressure
        pressurised = self.wet & (pressure > self.closure_stress)
        wet_ids = (
            np.unique(self.net.keys[pressurised].reshape(-1))
            if self.net.size
            else np.zeros(0, np.int64)
        )
        ids = np.union1d(wet_ids, self._cavity_vertices)
        return np.asarray(np.isin(solid.vertex_ids, ids).any(axis=1), dtype=bool)

    def step(self) -> StepRecord:
        """Advance one accepted time step (cutting the step on failure)."""
        s = self.settings
        while True:
            dt = self.dt
            saved = self._save_states()
            record = self._try_step(dt)
            if isinstance(record, StepRecord):
                return record
            # a failed or shortened attempt leaves no breaks, fills or contacts behind
            self._restore_states(saved)
            if isinstance(record, float):  # land closer to the first break
                self.dt = record
                continue
            self.dt = dt * 0.5
            if self.dt < s.dt_min:
                raise SimulationStopped(
                    f"the coupled step failed down to dt = {dt:.3g} s (dt_min {s.dt_min:g} s) "
                    f"at t = {self.t:.6g} s: the flow equations did not converge; "
                    "try max_breaks_per_iteration=1, a residual aperture, a smaller "
                    "dt_initial, or fidelity='uniform' "
                    f"({getattr(self, '_newton_failure', '')})"
                )

    def _save_states(self) -> tuple:
        solid = self.solid
        return (
            solid.states.copy(),
            len(solid.events),
            dict(self._content),
            dict(self._wet_since),
            dict(self._pressure),
            self.first_break_time,
            self.rebuilds,
        )

    def _restore_states(self, saved: tuple) -> None:
        solid = self.solid
        changed = self.rebuilds != saved[6]
        solid.states.restore(saved[0])
        del solid.events[saved[1] :]
        self._content, self._wet_since, self._pressure = saved[2], saved[3], saved[4]
        self.first_break_time = saved[5]
        if changed:
            self._rebuild()

    def _try_step(self, dt: float) -> StepRecord | float | None:
        s, solid = self.settings, self.solid
        t1 = self.t + dt
        source = (
            self.injection.volume_between(self.t, t1)
            if self.injection.rate_controlled
            else self.injection.value_at(t1)
        )
        changed_states = False
        its_total = 0
        contact_iterations = 0
        for iteration in range(s.max_state_iterations):
            if self.progress is not None and iteration and iteration % 10 == 0:
                counts = solid.broken_counts()
                self.progress(
                    f"  t {t1:.6g} s, iteration {iteration}: {counts['tensile']} tensile, "
                    f"{counts['shear']} shear, {int(self.wet.sum())} wet, "
                    f"{self.rebuilds} rebuilds, "
                    f"last change: {getattr(self, '_last_change', '')}"
                )
            leak = self._leak(t1)
            start = self._guess(source)
            p, its, ok = self._newton(dt, source, leak, start)
            its_total += its
            last_its = its
            if not ok:
                return None
            # accuracy control: the cavity pressure may move by at most max_pressure_change
            # (relative, at least 1 MPa wide) per step, or the step is retried shorter
            if iteration == 0 and self.history and dt > 4.0 * s.dt_min:
                jump = abs(float(p[0]) - self.p_cavity)
                if jump > s.max_pressure_change * max(abs(self.p_cavity), 1e6):
                    return 0.5 * dt
            # a wet facet below zero pressure drains (saturation model)
            if s.filling == "saturation" and s.fidelity == "viscous":
                pf = self._facet_pressure(p)
                # (facets that filled during this step may hold suction until it ends)
                drained = (self.group > 0) & (pf < 0.0) & (self.wet_since < t1)
                # dry facets that fill during this step join the wet set at once,
                # so the front is not limited to one facet per step
                vf, _ = self._volumes(p)
                gain = self._dry_gain(p, vf, dt)
                full = (self.group < 0) & (gain > 0.0) & (self.content + gain >= vf)
                if drained.any() or full.any():
                    self._last_change = f"{int(drained.sum())} drained, {int(full.sum())} filled"
                    self.wet_since[drained] = math.inf
                    self.wet_since[full] = t1
                    self.wet = np.isfinite(self.wet_since)
                    self._store_state()
                    self._rebuild()
                    changed_states = True
                    continue
            loads = self._set_displacement(p)
            # contact chatter (a facet that keeps opening and closing under the same
            # pressure) is cut off: after one round of switches only closings are
            # allowed, so the loop ends, and no face is left open while its blocks
            # interpenetrate (an open face has only the residual stiffness: a block it
            # frees would fly).  An opening held back waits one step.  (Two rounds cost
            # No. 2 coarse 34 more rebuilds for the same breakdown to 10 digits.)
            saved = (solid.contact.copy(), solid.friction_traction.copy())
            switched = solid.update_contact(loads)
            if switched and contact_iterations >= _CONTACT_ROUNDS:
                keep = ~((saved[0] == OPEN) & (solid.contact != OPEN))
                solid.contact[keep] = saved[0][keep]
                solid.friction_traction[keep] = saved[1][keep]
                changed = np.count_nonzero((solid.contact != saved[0]) & solid.owned)
                switched = int(self.comm.allreduce(int(changed), op=MPI.SUM))
            contact_iterations += 1 if switched else 0
            if switched:
                self._last_change = f"{switched} contacts switched"
                solid.sync_ghost_states()
                self._store_state()
                self._rebuild()
                continue
            self._trial_pressure = self._facet_pressure(p)
            ratio, mode = solid.overstress(loads)
            ratio = np.where(self._eligible(), ratio, 0.0)
            worst = float(self.comm.allreduce(float(ratio.max(initial=0.0)), op=MPI.MAX))
            if iteration == 0:
                # event location: a step that overshoots the next break by more than
                # break_tolerance is shortened (ratio interpolated linearly in time)
                r0 = self._last_ratio
                # (the ratio may jump, e.g. when fluid reaches a facet: give up after a few cuts)
                if (
                    math.isfinite(worst)  # zero strength gives an infinite ratio
                    and worst > 1.0 + s.break_tolerance
                    and r0 < 1.0
                    and dt > 4.0 * s.dt_min
                    and self._event_cuts < 6
                ):
                    self._event_cuts += 1
                    frac = (1.0 - r0) / (worst - r0)
                    return max(dt * min(max(frac, 0.05), 0.9), s.dt_min)
                self._step_ratio = worst
                if r0 < 1.0 <= worst and math.isfinite(worst):
                    # landed on the next break: record this state (the peak before it
                    # breaks) and let the next step break it
                    break
            if s.max_breaks_per_iteration is None:
                rule, cap = solid.model.break_rule, solid.model.max_breaks
            else:  # fewer new fluid cells per solve keep Newton in its basin
                rule, cap = "cap", s.max_breaks_per_iteration
            chosen = select_breaking(ratio, solid.midpoints, rule, cap, self.comm)
            nbreak = self.comm.allreduce(len(chosen), op=MPI.SUM)
            if nbreak:
                self._event_cuts = 0
                self._last_change = f"{nbreak} broke"
                solid.break_facets(chosen, mode[chosen], t1)
                if self.first_break_time is None:
                    self.first_break_time = t1
                self._store_state()
                self._rebuild()
                changed_states = True
                continue
            break
        else:
            raise SimulationStopped(
                f"interface states did not settle in {s.max_state_iterations} iterations at "
                f"t = {t1:.6g} s; use a smaller time step"
            )
        self._last_its = last_its
        return self._accept(p, dt, t1, source, leak, its_total, changed_states)

    def _leak(self, t1: float) -> np.ndarray:
        lo = self.settings.leak_off
        if lo is None or self.net.size == 0:
            return np.zeros(self.net.size)
        vol = lo.volume(self.net.area, self.wet_since, self.t, t1)
        return np.where(self.wet, vol, 0.0)

    def _dry_gain(self, p: np.ndarray, vf: np.ndarray, dt: float) -> np.ndarray:
        """Volume each facet receives over the step from its connections (dry ones keep it)."""
        net = self.net
        flux, _ = self._fluxes(p, vf)
        fa, fb, inner = net.pair_facets
        gain = np.zeros(net.size)
        np.add.at(gain, fa, -dt * flux)
        np.add.at(gain, fb[inner], dt * flux[inner])
        return gain

    def _accept(
        self,
        p: np.ndarray,
        dt: float,
        t1: float,
        source: float,
        leak: np.ndarray,
        its: int,
        changed: bool,
    ) -> StepRecord:
        kw = self.fluid.bulk_modulus
        vf, vc = self._volumes(p)
        pf = self._facet_pressure(p)
        wet = self.group >= 0
        net = self.net
        gain = self._dry_gain(p, vf, dt)
        floor = net.area * _APERTURE_FLOOR
        stored = vf + np.maximum(vf, floor) * pf / kw
        cav_stored = float(vc) + max(float(vc), 0.0) * float(p[0]) / kw
        injected_step = source if self.injection.rate_controlled else 0.0
        if not self.injection.rate_controlled:
            # the balance of the cavity group gives the volume pumped in this step
            injected_step = float(self._residual(p, dt, 0.0, leak, control=False)[0])
        # Exact finite-volume bookkeeping: each group's content changes by what flowed
        # in, was injected and leaked; the solver residual (content vs the compressed
        # void volume) is reported as the mismatch and corrected by the next step.
        resid = self._residual(p, dt, injected_step, leak, control=False)
        self.volume_mismatch = float(np.sum(np.abs(resid)))
        exact = np.zeros(self.m)
        np.add.at(exact, self.group[wet], stored[wet])
        exact[0] += cav_stored
        share = np.zeros(self.m)
        np.add.at(share, self.group[wet], stored[wet])
        share[0] += cav_stored
        target = exact - resid
        factor = np.where(share != 0.0, target / np.where(share != 0.0, share, 1.0), 1.0)
        self.content = np.where(
            wet, stored * factor[np.maximum(self.group, 0)], self.content + gain
        )
        self.cavity_content = cav_stored * float(factor[0])
        self.pressure = np.where(wet, pf, 0.0)
        self.p_cavity = float(p[0])
        self.injected += injected_step
        self.leaked += float(leak.sum())
        # dry facets that filled up turn wet
        # (with uniform fidelity the wet set is the joined network: a rebuild changes nothing)
        full = (~wet) & (self.content >= vf * (1.0 - 1e-12))
        fills = bool(full.any()) and self.settings.fidelity == "viscous"
        if fills:
            self.wet_since[full] = t1
            self.wet = np.isfinite(self.wet_since)
            self.pressure[full] = 0.0
        self.t = t1
        self._store_state()
        if fills:
            self._rebuild()
        stored_total = self.cavity_content + float(self.content.sum()) - self.initial_fluid
        err = abs(self.injected - stored_total - self.leaked) / max(abs(self.injected), 1e-300)
        counts = self.solid.broken_counts()
        rec = StepRecord(
            time=t1,
            dt=dt,
            injection_pressure=self.p_cavity,
            injected_volume=self.injected,
            cavity_fluid=self.cavity_content,
            fracture_fluid=float(self.content.sum()),
            fracture_volume=float(np.maximum(vf, 0.0).sum()),
            leaked_volume=self.leaked,
            mass_error=err,
            volume_mismatch=self.volume_mismatch / max(abs(self.injected), 1e-300),
            wet_facets=int(self.wet.sum()),
            tensile=counts["tensile"],
            shear=counts["shear"],
            fracture_degree=self.solid.fracture_degree(),
            newton_iterations=its,
            rebuilds=self.rebuilds,
            wall_time=time.perf_counter() - self.wall_start,
        )
        if not (math.isfinite(rec.injection_pressure) and np.all(np.isfinite(self.pressure))):
            raise SimulationStopped(f"non-finite pressure at t = {t1:.6g} s")
        self.history.append(rec)
        self._last_ratio = self._step_ratio if not changed else 1.0
        if not changed and self._last_its <= 6:
            self.dt = min(dt * self.settings.dt_growth, self.settings.dt_max)
        return rec

    def settle(self) -> int:
        """Break what the initial state already over-stresses; return how many broke.

        The excavated rock at the initial pressure may fail before any fluid is
        pumped (e.g. shear at a tunnel root).  Those failures are counted here,
        at t = 0, and do not count as the first crack of the injection.
        """
        if self.t != 0.0 or self.history:
            raise RuntimeError("settle() must run before the first step")
        before = sum(self.solid.broken_counts().values())
        self._last_ratio = math.inf  # no event location: break at once
        dt = self.dt
        record = self._try_step(0.0)
        self.dt = dt
        if record is None:
            raise SimulationStopped(
                "the initial state did not settle: the flow equations did not converge "
                f"({getattr(self, '_newton_failure', '')})"
            )
        self.history.clear()
        self.first_break_time = None
        self.initial_failures = sum(self.solid.broken_counts().values()) - before
        return self.initial_failures

    def run(self, t_end: float, max_steps: int = 100_000) -> list[StepRecord]:
        """Step to ``t_end`` (s); progress lines go to ``progress`` if set."""
        if not (math.isfinite(t_end) and t_end > self.t):
            raise ValueError(
                f"t_end must be a time in s after the current {self.t} s, got {t_end!r}"
            )
        for count in range(max_steps + 1):
            if self.t >= t_end * (1.0 - 1e-12):
                break
            if count == max_steps:
                raise SimulationStopped(
                    f"{max_steps} steps reached at t = {self.t:.6g} s of {t_end:g} s "
                    f"(time step {self.dt:.3g} s): the step stayed small; the history is kept"
                )
            self.dt = min(self.dt, t_end - self.t)
            rec = self.step()
            if self.progress is not None:
                elapsed = rec.wall_time
                eta = elapsed / rec.time * (t_end - rec.time) if rec.time > 0 else math.nan
                self.progress(
                    f"t {rec.time:9.4g} s  p {rec.injection_pressure / 1e6:9.4f} MPa  "
                    f"broken {rec.tensile + rec.shear:5d}  wet {rec.wet_facets:5d}  "
                    f"dt {rec.dt:8.3g} s  wall {elapsed:7.1f} s  eta {eta:7.1f} s"
                )
        return self.history

    # ------------------------------------------------------------- results

    def wet_extent(self, origin: Sequence[float], direction: Sequence[float]) -> float:
        """Return the fluid front along ``direction`` from ``origin`` (m).

        The far end of the wet facets, plus the filled share of a dry facet beyond.
        """
        o = np.zeros(3)
        o[: len(origin)] = origin
        d = np.zeros(3)
        d[: len(direction)] = direction
        d /= np.linalg.norm(d)
        if not self.wet.any():
            return 0.0
        proj = (self.net.centroid - o) @ d
        half = 0.5 * self.net.area  # 2D: facet length
        reach = float(np.max(proj[self.wet] + half[self.wet]))
        dry = ~self.wet
        if dry.any():
            vf, _ = self._volumes(self._guess())
            sat = np.clip(self.content / np.maximum(vf, 1e-300), 0.0, 1.0)
            ahead = dry & (np.abs(proj - half - reach) < 1e-6 * max(reach, 1.0))
            if ahead.any():
                reach += float(np.max(sat[ahead] * 2 * half[ahead]))
        return reach

    # ------------------------------------------------------------ checkpoints

    _SCALARS = (
        "t",
        "dt",
        "injected",
        "leaked",
        "cavity_content",
        "p_cavity",
        "initial_fluid",
        "first_break_time",
        "_last_ratio",
        "initial_failures",
        "rebuilds",
        "rebuild_seconds",
    )

    def checkpoint(self) -> dict:
        """Return the state to continue from (the same on every rank, JSON-ready).

        Interfaces are keyed by their global vertex ids, so a run may resume on
        another number of ranks.
        """
        solid = self.solid
        sel = np.flatnonzero((solid.state != FacetState.INTACT) & solid.owned)
        rows = [
            [
                sorted(int(v) for v in solid.vertex_ids[i]),
                int(solid.state[i]),
                int(solid.contact[i]),
                [float(x) for x in solid.friction_traction[i]],
            ]
            for i in sel
        ]
        facets = [r for part in self.comm.allgather(rows) for r in part]

        def table(d: dict) -> list:
            return [[list(k), v] for k, v in sorted(d.items())]

        return {
            "scalars": {k: getattr(self, k) for k in self._SCALARS},
            "interfaces": sorted(facets),
            "content": table(self._content),
            "wet_since": [
                [k, (v if math.isfinite(v) else None)] for k, v in table(self._wet_since)
            ],
            "pressure": table(self._pressure),
        }

    def restore(self, data: dict, history: list[StepRecord] | None = None) -> None:
        """Continue from a :meth:`checkpoint` (collective), with the ``history`` so far.

        The checkpoint holds the state only; the step records come from
        ``history.csv`` (or an older checkpoint's ``history``).
        """
        solid = self.solid
        ids = np.sort(np.asarray(solid.vertex_ids, dtype=np.int64), axis=1)
        local: dict[tuple[int, ...], int] = {
            tuple(int(v) for v in ids[i]): i for i in range(len(ids))
        }
        for key, state, contact, friction in data["interfaces"]:
            i = local.get(tuple(key))
            if i is not None:
                solid.state[i] = state
                solid.contact[i] = contact
                solid.friction_traction[i] = friction
        for k, v in data["scalars"].items():
            setattr(self, k, v)
        self._content = {tuple(k): float(v) for k, v in data["content"]}
        self._wet_since = {
            tuple(k): (math.inf if v is None else float(v)) for k, v in data["wet_since"]
        }
        self._pressure = {tuple(k): float(v) for k, v in data["pressure"]}
        if history is None:
            history = [StepRecord.from_row(row) for row in data.get("history", [])]
        self.history = list(history)
        self._rebuild()

    def write_history(self, path: str | os.PathLike[str]) -> None:
        """Write the step records as CSV (rank 0, atomically: a stopped run keeps it)."""
        fields = list(StepRecord.__dataclass_fields__)
        rows = [[float(getattr(r, k)) for k in fields] for r in self.history]
        write_csv(path, fields, rows, self.comm)

    def facet_fields(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Vertex coordinates (F, nv, 3) and per-facet fluid data of this rank's owned facets.

        Data: fluid pressure (MPa), hydraulic aperture (m), saturation, failure
        state (1 tensile, 2 shear), open (1) or closed (0); for
        :func:`hfcdem.io.files.write_interfaces`.
        """
        sel = self._owned_sel
        pos = self._local_pos[sel]
        facets = self._local_fracture[sel]
        vf, _ = self._volumes(self._guess())
        sat = np.where(self.wet, 1.0, np.clip(self.content / np.maximum(vf, 1e-300), 0.0, 1.0))
        data = {
            "fluid_pressure_MPa": self.pressure[pos] / 1e6,
            "aperture_m": self.apertures()[pos],
            "saturation": sat[pos],
            "state": self.solid.state[facets].astype(float),
            "open": self.is_open[pos].astype(float),
        }
        return self.solid.vertex_coords[facets], data

    def interface_fields(self, loads: Loads) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Vertex coordinates (F, nv, 3) and data of every owned interface facet.

        Data: failure state (0 intact, 1 tensile, 2 shear), mechanical opening (m),
        normal traction (MPa, tension positive), and the fluid's pressure (MPa),
        saturation and hydraulic aperture (m), zero where no fluid cell is.
        ``loads`` must be the loads of the solid's current displacement.
        """
        solid = self.solid
        snap = solid.snapshot(loads)
        n = solid.num_facets
        pressure, saturation, aperture = np.zeros(n), np.zeros(n), np.zeros(n)
        if self.net.size:
            vf, _ = self._volumes(self._guess())
            sat = np.where(self.wet, 1.0, np.clip(self.content / np.maximum(vf, 1e-300), 0.0, 1.0))
            loc, pos = self._local_fracture, self._local_pos
            pressure[loc] = self.pressure[pos] / 1e6
            saturation[loc] = sat[pos]
            aperture[loc] = self.apertures()[pos]
        own = solid.owned
        data = {
            "state": solid.state[own].astype(float),
            "opening_m": snap.opening[own],
            "normal_traction_MPa": snap.normal_traction[own] / 1e6,
            "fluid_pressure_MPa": pressure[own],
            "saturation": saturation[own],
            "aperture_m": aperture[own],
        }
        return solid.vertex_coords[own], data

    def current_loads(self) -> Loads:
        """Set the solid's displacement to the last accepted state; return its loads."""
        return self._set_displacement(self._guess())

    def apertures(self) -> np.ndarray:
        """Hydraulic aperture of every network facet (m): never negative."""
        vf, _ = self._volumes(self._guess())
        w = np.maximum(vf / np.maximum(self.net.area, 1e-300) - self.fluid.residual_aperture, 0.0)
        return w + self.fluid.residual_aperture

    def opening_at_cavity(self) -> float:
        """Mean opening of the facets that touch the cavity or injection point (m)."""
        touch = self.net.touches_cavity
        if not touch.any():
            return 0.0
        vf, _ = self._volumes(self._guess())
        return float(np.sum(vf[touch]) / np.sum(self.net.area[touch]))


def _col(values: np.ndarray, like: np.ndarray) -> np.ndarray:
    """Broadcast a per-item array against a (m,) or (m, k) pressure array."""
    return values.reshape(values.shape + (1,) * (like.ndim - 1))


__all__ = [
    "FlowSettings",
    "HydraulicFracture",
    "SimulationStopped",
    "StepRecord",
    "relative_permeability",
]
