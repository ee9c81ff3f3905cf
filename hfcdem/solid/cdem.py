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

:class:`CDEMSolid` composes the interface facets and their geometry
(:mod:`~hfcdem.solid.facets`), their states (:mod:`~hfcdem.solid.states`) and the
forms (:mod:`~hfcdem.solid.forms`); it owns the solver and the break state machine.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.band import SOLID_MODES, InterfaceBand, StressRecovery
from hfcdem.solid.elastic import stress
from hfcdem.solid.equilibrium import equilibrate, ramp
from hfcdem.solid.facets import FacetFunctions, InterfaceFacets, ZoneMarker
from hfcdem.solid.forms import (
    GLUE,
    OPEN_FACETS,
    SLIP_FACETS,
    SPRING,
    LoadForm,
    Loads,
    LoadTerms,
    SolidForms,
    change_tags,
    combine,
    dg_boundary_conditions,
    interface_tags,
    interface_values,
    load_terms,
    rigid_body_modes,
)
from hfcdem.solid.interfaces import (
    FacetState,
    check_failure,
    stable_facet_hash,
    weibull_scatter,
)
from hfcdem.solid.nonlocal_strength import StressFilter
from hfcdem.solid.operator import StiffnessOperator
from hfcdem.solid.points import PointValues
from hfcdem.solid.reduction import ReducedSystem, glued_facet_set
from hfcdem.solid.retag import TaggedForm
from hfcdem.solid.states import OPEN, SLIP, STICK, CascadeStopped, InterfaceStates, faces_overlap
from hfcdem.solvers import (
    DIRECT_CHOLESKY,
    check_ksp,
    create_ksp,
    setup_factorisation,
    solve_together,
)

# solver="auto": direct (MUMPS) up to this many unknowns, CG + GAMG beyond. No. 2's
# default mesh (404,844) factorises in 4 GB for both ranks and back-substitutes in
# 0.5 s, where a CG + GAMG solve to 1e-10 takes about a minute; the paper mesh
# (1.2M) would need 22.7 GB (benchmarks/README.md)
AUTO_DIRECT_MAX_DOFS = 600_000
# a direct solver takes interface events as a low-rank correction of its factor for
# up to this many columns (9 per 3D DG1 facet: its jump), and for no more than
# LOW_RANK_BYTES of correction columns over all ranks; PETSc option
# -hfcdem_cdem_low_rank_columns overrides (0: refactorise at every event)
LOW_RANK_COLUMNS = 256
LOW_RANK_BYTES = 1 << 30


@dataclass(frozen=True)
class InterfaceSnapshot:
    """Per-facet values of the interfaces owned by this rank."""

    opening: np.ndarray  # normal opening w (m), physical aperture for open facets
    slip: np.ndarray  # tangential jump magnitude (m)
    normal_traction: np.ndarray  # tension positive (Pa)
    shear_traction: np.ndarray  # magnitude (Pa)
    shear_vector: np.ndarray  # on the + face
    gap: np.ndarray  # w past the pre-compression offset, unclipped (m; negative: overlap)


@dataclass(frozen=True)
class HeldShut:
    """What contact hysteresis held shut at a contact check (global).

    ``count`` facets that would have opened; ``excess`` the largest share of
    the fluid pressure by which it exceeds the compression their springs hold.
    """

    count: int = 0
    excess: float = 0.0


@dataclass
class BreakEvent:
    """Interfaces broken at one load level."""

    load_factor: float
    facets: np.ndarray  # local facet indices
    modes: np.ndarray
    midpoints: np.ndarray


#: right-hand sides handed to MUMPS at once: its solve phase reads the factor once
#: for all of them (No. 2's default mesh: one 0.47 s, two 0.52 s, four 0.59 s),
#: while the dense block costs a vector's memory per column
SOLVE_BATCH = 8


def _homogeneous(bcs: list[dolfinx.fem.DirichletBC]) -> bool:
    """Return whether every condition prescribes a constant zero."""
    for bc in bcs:
        g = bc.g
        if not hasattr(g, "value") or np.any(np.asarray(g.value) != 0.0):
            return False
    return True


class CDEMSolid:
    """Blocks and springs on a :class:`TaggedMesh`, with a quasi-static solver.

    ``walls`` maps exterior facet groups to the fluid pressure (Pa) they were
    drilled at (a wellbore drilled in the stressed rock, then cased): the rock is
    first solved with those walls at that pressure (the drilled state, the stress
    concentration around the hole), then the casing holds them there, as springs
    as stiff as the interfaces' (``alpha E / h``), so later loads move them little.
    Both parts go with the in-situ load, nothing with a unit load.  Other exterior
    groups not loaded as a cavity keep the in-situ traction.
    """

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
        walls: Mapping[str, float] | None = None,
        nitsche_penalty: float | None = None,
        solver: str = "auto",
        strength_points: str = "vertices",
        mode: str = "full",
        band: tuple[float, int] = (0.3, 2),
        petsc_options: Mapping[str, object] | None = None,
        prefix: str = "hfcdem_cdem_",
    ) -> None:
        if degree not in (1, 2):
            raise ValueError(f"degree must be 1 or 2 (DG blocks), got {degree!r}")
        if solver not in ("direct", "iterative", "auto"):
            raise ValueError(f"solver must be 'direct', 'iterative' or 'auto', got {solver!r}")
        if strength_points not in ("vertices", "midpoint"):
            raise ValueError(
                f"strength_points must be 'vertices' or 'midpoint', got {strength_points!r}"
            )
        if mode not in SOLID_MODES:
            raise ValueError(f"mode must be one of {SOLID_MODES}, got {mode!r}")
        if mode == "reduced" and degree != 1:
            raise ValueError(f"the reduced mode needs DG1 blocks (degree 1), got {degree!r}")
        self.tmesh = tmesh
        self.mesh = mesh = tmesh.mesh
        self.mode = mode
        self.comm: MPI.Comm = mesh.comm
        self.material = material
        self.in_situ = in_situ
        self.model = interfaces
        self.degree = degree
        self.prefix = prefix
        self.solver_kind = solver
        self.petsc_options = dict(petsc_options or {})
        low_rank = self.petsc_options.pop("low_rank_columns", None)
        tdim = mesh.topology.dim
        self.gdim = gdim = mesh.geometry.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        mesh.topology.create_connectivity(tdim, tdim - 1)
        mesh.topology.create_connectivity(tdim - 1, 0)

        self.V = dolfinx.fem.functionspace(mesh, ("DG", degree, (gdim,)))
        if solver == "auto":
            # MUMPS is robust for any alpha; past this size its memory outgrows the machine
            dofs = self.V.dofmap.index_map.size_global * gdim
            self.solver_kind = "direct" if dofs <= AUTO_DIRECT_MAX_DOFS else "iterative"
        self.u = dolfinx.fem.Function(self.V, name="displacement")
        self.u_unit = dolfinx.fem.Function(self.V)  # response to a unit load (solve(unit=...))
        self.sigma0 = in_situ.tensor(gdim)

        self.interface_facets = InterfaceFacets.build(tmesh, zone, cracks)
        self.facet_functions = FacetFunctions(mesh, self.interface_facets)
        self.kn = interfaces.alpha * material.youngs_modulus / self.h
        self.ks = self.kn * interfaces.shear_stiffness_ratio(material.poisson_ratio)
        if strength_points == "midpoint":
            self.strength_points = [self.midpoints]
        else:
            vx = self.vertex_coords
            self.strength_points = [vx[:, k] for k in range(vx.shape[1])]
        self.t0, self.c0 = self._strengths()
        self._fixed_bcs = dg_boundary_conditions(self.V, tmesh, degree, rollers or {}, fixed)
        self._bcs = list(self._fixed_bcs)
        self.fixed_groups = tuple(fixed)  # faces held in every component: blocks there stay
        # cells held in place by a supporting wall (hold_cells), and a count of their changes
        self.held_cells: np.ndarray = np.zeros(0, dtype=np.int64)  # global indices, sorted
        self.held_version = 0
        nitsche = nitsche_penalty if nitsche_penalty is not None else 10.0 * (degree + 1) ** 2
        walls = dict(walls or {})
        for name, pressure in walls.items():
            if name not in tmesh.facet_names:
                raise ValueError(f"wall {name!r} is not a facet group of the mesh")
            if not math.isfinite(pressure) or abs(pressure) > 1e10:
                raise ValueError(
                    f"wall pressure on {name!r} must be finite, in Pa, got {pressure!r}"
                )
        self.walls = walls
        self.forms = SolidForms(
            tmesh,
            self.V,
            material,
            interfaces,
            self.sigma0,
            nitsche,
            self.facet_functions,
            walls,
        )
        # facets that ever broke, and their contact sub-state
        self.states = InterfaceStates.initial(self.is_crack, gdim)
        self.held_shut = HeldShut()
        # reduced mode: free springs only in a band, glued (continuous) elsewhere
        self.band = InterfaceBand(mesh, self.interface_facets, *band, all_free=mode == "full")
        self._recovery = StressRecovery(self.u, material)
        self._probes: list[tuple[np.ndarray, PointValues, PointValues]] = []  # _point_values
        # strength over a material length: the check reads the filtered stress
        self._filter = (
            StressFilter(self.u, material, self.facets, self.cells[:, 0],
                         interfaces.strength_length, prefix=f"{prefix}filter_")
            if interfaces.strength_length > 0.0
            else None
        )  # fmt: skip
        self._reduced: ReducedSystem | None = None
        self._reduced_version: tuple[int, int] | None = None
        # the stiffness form of the last interface states (retagged: _stiffness_form_now)
        self._stiffness_form: tuple[np.ndarray, int, dolfinx.fem.Form] | None = None
        # load forms by their terms, compiled once; retagged when the states or band change
        self._load_forms: dict[LoadTerms, LoadForm] = {}
        self._load_forms_stamp: tuple[np.ndarray, int] | None = None
        self._tags: tuple[int, dolfinx.mesh.MeshTags | None] = (0, None)  # version, tags
        # the stiffness and its change, compiled once (retag.TaggedForm)
        self._stiffness_tagged: TaggedForm | None = None
        self._change_tagged: TaggedForm | None = None
        if low_rank is None:
            dofs = self.V.dofmap.index_map.size_global * gdim
            low_rank = min(LOW_RANK_COLUMNS, LOW_RANK_BYTES // (8 * dofs))
        if not isinstance(low_rank, int) or isinstance(low_rank, bool):
            raise ValueError(f"low_rank_columns must be a whole number, got {low_rank!r}")
        columns = PETSc.Options(prefix).getInt("low_rank_columns", low_rank)
        if columns < 0:
            raise ValueError(f"low_rank_columns must be 0 or more, got {columns}")
        self.operator = StiffnessOperator(
            self.comm,
            lambda: self.assemble_stiffness()[1],
            self.assemble_change,
            self._create_solver,
            max_columns=columns,
        )
        self.solves = 0
        self.solve_seconds = 0.0
        self.events: list[BreakEvent] = []
        self.progress: Callable[[str], None] | None = None
        if walls:
            self._drill_walls()

    def _drill_walls(self) -> None:
        """Solve the drilled state, with no casing, as the reference the casing holds."""
        self.forms.casing.value = 0.0
        a_form, A = self.assemble_stiffness()
        if self.mode == "reduced":
            A_dg, A = A, self.reduced_system().reduce(A)
            A_dg.destroy()
        ksp = self._create_solver(A)
        rhs = self.assemble_load(a_form, self.load_form(Loads()))
        self.solve_assembled(ksp, [rhs], [self.forms.wall_reference])
        ksp.destroy()
        A.destroy()
        self.forms.casing.value = 1.0

    # ------------------------------------------------------- facets and states

    @property
    def facets(self) -> np.ndarray:
        """Local facet indices of this rank's interfaces (owned and ghost)."""
        return self.interface_facets.facets

    @property
    def num_facets(self) -> int:
        """Number of interface facets on this rank (owned and ghost)."""
        return self.interface_facets.num_facets

    @property
    def cells(self) -> np.ndarray:
        """(F, 2) cells on either side of each interface; n+ points out of the first."""
        return self.interface_facets.cells

    @property
    def is_crack(self) -> np.ndarray:
        """Per interface: a pre-existing crack."""
        return self.interface_facets.is_crack

    @property
    def glue_facets(self) -> np.ndarray:
        """Local indices of the glued interior facets (outside the zone)."""
        return self.interface_facets.glue_facets

    @property
    def owned(self) -> np.ndarray:
        """Per interface: owned by this rank."""
        return self.interface_facets.owned

    @property
    def vertex_coords(self) -> np.ndarray:
        """(F, nv, 3) vertex coordinates of each interface."""
        return self.interface_facets.vertex_coords

    @property
    def midpoints(self) -> np.ndarray:
        """(F, 3) midpoint of each interface."""
        return self.interface_facets.midpoints

    @property
    def normals(self) -> np.ndarray:
        """(F, gdim) unit normal n+ of each interface."""
        return self.interface_facets.normals

    @property
    def areas(self) -> np.ndarray:
        """Area (2D: length) of each interface."""
        return self.interface_facets.areas

    @property
    def h(self) -> np.ndarray:
        """Mean diameter of the two cells of each interface."""
        return self.interface_facets.h

    @property
    def vertex_ids(self) -> np.ndarray:
        """(F, nv) global input ids of the vertices of each interface."""
        return self.interface_facets.vertex_ids

    @property
    def state(self) -> np.ndarray:
        """Failure state per interface: 0 intact, 1 tensile, 2 shear."""
        return self.states.state

    @property
    def contact(self) -> np.ndarray:
        """Contact sub-state per interface: open, stick or slip."""
        return self.states.contact

    @property
    def friction_traction(self) -> np.ndarray:
        """(F, gdim) Coulomb traction of sliding interfaces on their + face."""
        return self.states.friction_traction

    @property
    def released(self) -> np.ndarray:
        """Per interface: a face of a block cut loose, held open (see ``release_facets``)."""
        return self.states.released

    def _strengths(self) -> tuple[np.ndarray, np.ndarray]:
        """Tensile strength and cohesion per interface (Weibull scatter keyed by vertex ids)."""
        m = self.model
        if m.weibull_modulus is None:
            return np.full(self.num_facets, m.tensile_strength), np.full(
                self.num_facets, m.cohesion
            )
        u1 = stable_facet_hash(self.vertex_ids, m.seed)
        u2 = stable_facet_hash(self.vertex_ids, m.seed + 7919)
        return (
            weibull_scatter(m.tensile_strength, m.weibull_modulus, u1),
            weibull_scatter(m.cohesion, m.weibull_modulus, u2),
        )

    # ------------------------------------------------------------------ forms

    def interface_tags(self) -> dolfinx.mesh.MeshTags:
        """Tag interface facets by their integral: SPRING, OPEN_FACETS, SLIP_FACETS or GLUE."""
        return interface_tags(self.mesh, self.interface_facets, self.states)

    def facet_dofs(self, shape: tuple[int, ...] = ()) -> np.ndarray:
        """Dofs of the Crouzeix-Raviart space of ``shape`` at this rank's interface facets."""
        return self.facet_functions.dofs(shape)

    def facet_function(
        self, values: np.ndarray, shape: tuple[int, ...] = ()
    ) -> dolfinx.fem.Function:
        """Return per-facet values as a Crouzeix-Raviart function (exact at facet midpoints)."""
        return self.facet_functions.function(values, shape)

    def _measure(self) -> ufl.Measure:
        return ufl.Measure("dS", domain=self.mesh, subdomain_data=self.interface_tags())

    # ------------------------------------------------------------------ solve

    def _ksp(self, A: PETSc.Mat) -> PETSc.KSP:
        if self.solver_kind == "direct":
            # K is symmetric (SIPG glue, symmetric springs, symmetric Dirichlet rows and
            # columns): MUMPS LDL^T factorises it in about half the time of LU
            defaults: dict[str, object] = dict(DIRECT_CHOLESKY)
            A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        else:
            defaults = {"ksp_type": "cg", "pc_type": "gamg", "ksp_rtol": 1e-10, "ksp_max_it": 2000}
            space, self._modes = rigid_body_modes(self.V)  # kept: PETSc holds no copy
            A.setNearNullSpace(space)
        return create_ksp(A, self.prefix, {**defaults, **self.petsc_options}, self.comm)

    @property
    def bcs(self) -> list[dolfinx.fem.DirichletBC]:
        """The (homogeneous) Dirichlet conditions on the DG dofs."""
        return self._bcs

    def hold_cells(self, cells: np.ndarray) -> int:
        """Hold the cells with global indices ``cells`` in place from now on (collective).

        Their displacement from the in-situ state is zero (a Dirichlet condition on
        all their DG unknowns): a block cut loose against a wall that supports the
        rock, such as a cased wellbore's, is held by it.  Cells already held stay
        held.  Returns the number of cells newly held (the same on every rank).
        """
        cells = np.unique(np.concatenate(self.comm.allgather(np.asarray(cells, np.int64))))
        held = np.union1d(self.held_cells, cells)
        new = int(held.size - self.held_cells.size)
        if new == 0:
            return 0
        self.held_cells = held
        tdim = self.mesh.topology.dim
        imap = self.mesh.topology.index_map(tdim)
        local = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
        mine = local[np.isin(imap.local_to_global(local), held)]
        dofs = [self.V.dofmap.cell_dofs(int(c)) for c in mine]
        blocks = np.unique(np.concatenate(dofs)).astype(np.int32) if dofs else np.zeros(0, np.int32)
        zero = np.zeros(self.gdim, dtype=dolfinx.default_scalar_type)
        self._bcs = [*self._fixed_bcs, dolfinx.fem.dirichletbc(zero, blocks, self.V)]
        self.held_version += 1
        return new

    def assemble_stiffness(self) -> tuple[dolfinx.fem.Form, PETSc.Mat]:
        """Assemble the stiffness of the current interface states (Dirichlet rows/columns set).

        Returns the compiled form and the matrix; the caller owns (destroys) the matrix.
        """
        a_form = self._stiffness_form_now()
        A = dolfinx.fem.petsc.assemble_matrix(a_form, bcs=self._bcs)
        A.assemble()
        return a_form, A

    def _stiffness_form_now(self) -> dolfinx.fem.Form:
        """Return the stiffness form over the current interface tags (compiled once; collective)."""
        if self._stiffness_tagged is None:
            self._stiffness_tagged = TaggedForm(self.forms.stiffness(self._measure()))
        return self._stiffness_tagged.form(self.interface_tags())

    def assemble_load(self, a_form: dolfinx.fem.Form, L_form: dolfinx.fem.Form) -> PETSc.Vec:
        """Assemble the right-hand side of ``L_form`` (lifted and with the Dirichlet values)."""
        b = dolfinx.fem.petsc.assemble_vector(L_form)
        if not _homogeneous(self._bcs):  # zero values lift nothing (46 ms a load at No. 2 default)
            dolfinx.fem.petsc.apply_lifting(b, [a_form], bcs=[self._bcs])
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, self._bcs)
        return b

    def assemble_change(self, old: np.ndarray, new: np.ndarray) -> PETSc.Mat:
        """Assemble the stiffness change of interfaces whose integral went ``old`` -> ``new``.

        ``old`` and ``new`` hold :func:`~hfcdem.solid.forms.interface_values`; the
        Dirichlet rows and columns are zero.  The caller destroys the matrix.
        """
        tags = change_tags(self.mesh, self.interface_facets, old, new)
        if self._change_tagged is None:
            dS = ufl.Measure("dS", domain=self.mesh, subdomain_data=tags)
            self._change_tagged = TaggedForm(self.forms.stiffness_change(dS))
        form = self._change_tagged.form(tags)
        dK = dolfinx.fem.petsc.assemble_matrix(form, bcs=self._bcs, diagonal=0.0)
        dK.assemble()
        return dK

    def _create_solver(self, A: PETSc.Mat) -> PETSc.KSP:
        if self.mode == "reduced":
            return self.reduced_system().create_solver(A)
        if self.solver_kind == "direct":
            # factorised here, with more room if MUMPS's dynamic scheduling needs it
            return setup_factorisation(lambda: self._ksp(A), self.comm)
        return self._ksp(A)

    def factorize(self) -> tuple[dolfinx.fem.Form, PETSc.KSP]:
        """Factorise the stiffness of the current interface states; return its form and solver.

        The solid owns the KSP (valid until the next call; :meth:`solve_load` reuses
        it for any number of right-hand sides).  Between events only the change of
        the interfaces that changed is assembled and refactorised numerically
        (:class:`~hfcdem.solid.operator.StiffnessOperator`).
        """
        t0 = time.perf_counter()
        values = interface_values(self.states)
        cached = self._stiffness_form
        stale = cached is None or cached[1] != self.band.version
        stale = stale or not np.array_equal(cached[0], values)  # type: ignore[index]
        if self.comm.allreduce(stale, op=MPI.LOR):  # compiling a form is collective
            form = self._stiffness_form_now()
            self._stiffness_form = cached = (values.copy(), self.band.version, form)
        assert cached is not None
        a_form = cached[2]
        reduced = self.reduced_system() if self.mode == "reduced" else None
        ksp = self.operator.solver(
            values,
            (self.band.version, self.held_version),  # new Dirichlet rows: assemble afresh
            reduced.reduce if reduced is not None else None,
        )
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
        self.solve_assembled(ksp, [self.assemble_load(a_form, L_form)], [target])

    def solve_assembled(
        self,
        ksp: PETSc.KSP,
        rhs: Sequence[PETSc.Vec],
        targets: Sequence[dolfinx.fem.Function],
    ) -> None:
        """Solve for every right-hand side of :meth:`assemble_load` in ``rhs`` (destroyed).

        With a direct solver they go to MUMPS together, :data:`SOLVE_BATCH` at a
        time.
        """
        t0 = time.perf_counter()
        if len(rhs) != len(targets):
            raise ValueError(f"{len(rhs)} right-hand sides for {len(targets)} targets")
        if self.mode == "reduced":
            self.reduced_system().solve_many(ksp, rhs, targets)
        elif len(rhs) > 1 and ksp.getType() == PETSc.KSP.Type.PREONLY:
            for start in range(0, len(rhs), SOLVE_BATCH):
                part = slice(start, start + SOLVE_BATCH)
                solved = solve_together(ksp, rhs[part])
                for i, target in enumerate(targets[part]):
                    target.x.array[: solved.shape[0]] = solved[:, i]
        else:
            for b, target in zip(rhs, targets, strict=True):
                ksp.solve(b, target.x.petsc_vec)
        for b in rhs:
            b.destroy()
        check_ksp(
            ksp,
            "CDEM solve",
            "a failed factorisation means a block may be detached (raise "
            "InterfaceModel.residual_stiffness) or held by no boundary condition; "
            "an iterative solve that does not converge wants the direct solver",
        )
        for target in targets:
            target.x.scatter_forward()
            if not np.all(np.isfinite(target.x.array)):
                raise FloatingPointError(
                    "CDEM solve produced non-finite displacements: check that every block "
                    "is held (rollers/fixed faces) and that alpha is not extreme"
                )
        self.solve_seconds += time.perf_counter() - t0

    def reduced_system(self) -> ReducedSystem:
        """Return the reduced system of the current band (rebuilt when the band grew)."""
        version = (self.band.version, self.held_version)
        if self._reduced is None or self._reduced_version != version:
            glued = glued_facet_set(self.interface_facets, ~self.band.free)
            if self._reduced is not None:
                self._reduced.destroy()
            self._reduced = ReducedSystem(
                self.V, self._bcs, glued, self.petsc_options, prefix=self.prefix
            )
            self._reduced_version = version
        return self._reduced

    @property
    def num_dofs(self) -> int:
        """Global number of unknowns solved for (reduced or DG)."""
        if self.mode == "reduced":
            return self.reduced_system().num_dofs
        return int(self.V.dofmap.index_map.size_global * self.gdim)

    def load_form(self, loads: Loads) -> dolfinx.fem.Form:
        """Compiled right-hand side of ``loads`` at the current interface states (collective).

        The form of each :class:`~hfcdem.solid.forms.LoadTerms` is compiled once,
        retagged when the interface states or the band change, and its values set
        for every call: it is valid until the next call with loads of the same
        terms.
        """
        values = interface_values(self.states)
        stamp = self._load_forms_stamp
        stale = stamp is None or stamp[1] != self.band.version
        stale = stale or not np.array_equal(stamp[0], values)  # type: ignore[index]
        if self.comm.allreduce(stale, op=MPI.LOR):
            self._load_forms_stamp = (values.copy(), self.band.version)
            self._tags = (self._tags[0] + 1, None)
        version, tags = self._tags
        if tags is None:
            tags = self.interface_tags()
            self._tags = (version, tags)
        terms = load_terms(loads, self.states, self.comm)
        form = self._load_forms.get(terms)
        if form is None:
            form = self._load_forms[terms] = LoadForm(self.forms, terms, self._measure())
        form.set(loads, self.states)
        return form.form_at(tags, version)

    def solve(self, loads: Loads, unit: Loads | None = None) -> None:
        """Solve for ``loads`` (and, with the same matrix, for ``unit`` into ``u_unit``)."""
        a_form, ksp = self.factorize()
        pairs = [(x, t) for x, t in ((loads, self.u), (unit, self.u_unit)) if x is not None]
        rhs = [self.assemble_load(a_form, self.load_form(x)) for x, _ in pairs]
        self.solve_assembled(ksp, rhs, [t for _, t in pairs])
        self.solves += 1

    # ------------------------------------------------------------- interfaces

    def jumps(self, u: dolfinx.fem.Function, x: np.ndarray | None = None) -> np.ndarray:
        """Displacement jump u+ - u- at one point per facet (default: midpoints)."""
        x = self.midpoints if x is None else x
        if not len(x):
            return np.zeros((0, self.gdim))
        sides = self._point_values(x) if u.function_space is self.V else None
        if sides is not None:
            return sides[0](u) - sides[1](u)
        up = u.eval(x, self.cells[:, 0])
        um = u.eval(x, self.cells[:, 1])
        return np.asarray(up - um).reshape(-1, self.gdim)

    def _point_values(self, x: np.ndarray) -> tuple[PointValues, PointValues] | None:
        """Return the precomputed values on both sides at ``x`` if it is a fixed point set.

        The midpoints and the strength points are read after every solve; any
        other points go through ``Function.eval``.
        """
        for held, plus, minus in self._probes:
            if held is x:
                return plus, minus
        fixed = x is self.midpoints or any(x is p for p in self.strength_points)
        if not fixed or not PointValues.applies(self.V):
            return None
        plus, minus = (PointValues(self.V, x, self.cells[:, k]) for k in (0, 1))
        self._probes.append((x, plus, minus))
        return plus, minus

    def snapshot(
        self,
        loads: Loads,
        u: dolfinx.fem.Function | None = None,
        points: np.ndarray | None = None,
        recover: bool = True,
    ) -> InterfaceSnapshot:
        """Return openings and tractions at one point per facet (default: midpoints).

        ``recover``: glued facets (reduced mode) take the traction of their cells' stress;
        without it they keep the spring value (their in-situ traction).
        """
        u = u or self.u
        jump = self.jumps(u, points)
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
        glued = ~self.band.free
        if recover and u is self.u and glued.any():
            # glued facets carry no jump: their traction is the cells' stress
            tn_rec, shear_rec = self._recovery.tractions(self.interface_facets, s0, glued)
            tn = np.where(glued, tn_rec, tn)
            tau_vec = np.where(glued[:, None], shear_rec, tau_vec)
        # physical aperture of an open facet: the pre-compression offset removed, the
        # contact overlap of its fluid pressure added (coupling.condense.closure_offsets)
        broken = ~self.is_crack
        offset = np.where(t0n < 0.0, -t0n / self.kn, 0.0)
        overlap = np.maximum(self._crack_pressure(loads), 0.0) / self.kn
        opening = np.where(intact_like, w, np.maximum(w - (offset - overlap) * broken, 0.0))
        return InterfaceSnapshot(
            opening=opening,
            slip=np.linalg.norm(jt, axis=1),
            normal_traction=tn,
            shear_traction=np.linalg.norm(tau_vec, axis=1),
            shear_vector=tau_vec,
            gap=w - offset,
        )

    def filtered_tractions(self, loads: Loads) -> tuple[np.ndarray, np.ndarray]:
        """Return the normal (tension +) and shear traction of the filtered stress; collective.

        The stress filtered over ``strength_length`` (:class:`StressFilter`) plus
        the in-situ stress, on each facet's plane; fluid held in an intact joint
        pushes its faces apart, so its pressure adds to the normal traction
        (effective stress).  Requires a positive ``strength_length``.
        """
        if self._filter is None:
            raise ValueError("filtered_tractions needs a positive strength_length")
        s = self._filter.midpoint_stress() + loads.in_situ_factor * self.sigma0
        n = self.normals
        t = np.einsum("fij,fj->fi", s, n)
        tn = np.einsum("fi,fi->f", t, n)
        shear = np.linalg.norm(t - tn[:, None] * n, axis=1)
        if loads.joint_pressure is not None:
            tn = tn + np.asarray(loads.joint_pressure, dtype=float)
        return tn, shear

    def _crack_pressure(self, loads: Loads) -> np.ndarray:
        return np.broadcast_to(np.asarray(loads.crack_pressure, dtype=float), (self.num_facets,))

    def update_contact(self, loads: Loads, hysteresis: bool = False) -> int:
        """Open/close/slip switches of broken facets; returns the global count of changes.

        ``hysteresis``: a facet opens only once its fluid pressure has passed
        the one it last closed at (:meth:`InterfaceStates.switch_contacts`).
        ``held_shut`` keeps what that rule held shut at this check (global):
        the number of facets and the largest share of the fluid pressure by
        which the pressure exceeds the compression their springs hold.
        """
        snap = self.snapshot(loads)
        # pre-existing cracks and the faces of loose blocks stay open
        broken = (self.state != FacetState.INTACT) & ~self.is_crack & ~self.states.released
        old = self.contact.copy()
        # both directions compare the normal spring traction t0n + kn w with the fluid
        # pressure (faces_overlap)
        pressure = self._crack_pressure(loads)
        held = (
            self.states.switch_contacts(
                broken,
                snap.normal_traction,
                snap.shear_vector,
                pressure,
                faces_overlap(snap.gap, pressure, self.kn),
                self.model.friction,
                hysteresis,
            )
            & self.owned
        )
        counts = np.array(
            [np.count_nonzero((old != self.contact) & self.owned), np.count_nonzero(held)],
            dtype=np.int64,
        )
        self.comm.Allreduce(MPI.IN_PLACE, counts, op=MPI.SUM)  # one reduction when none held
        changed, count = int(counts[0]), int(counts[1])
        excess = 0.0
        if count:  # the same on every rank
            local = (pressure[held] + snap.normal_traction[held]) / pressure[held]
            excess = float(self.comm.allreduce(float(local.max(initial=0.0)), op=MPI.MAX))
        self.held_shut = HeldShut(count, excess)
        return changed

    def overstress(self, loads: Loads) -> tuple[np.ndarray, np.ndarray]:
        """Failure ratio and mode of the intact owned facets (others get ratio 0).

        The check runs at every strength point of a facet (its vertices, like the
        nodal springs of CDEM, or its midpoint) and keeps the worst.
        """
        ratio: np.ndarray = np.zeros(self.num_facets)
        mode: np.ndarray = np.full(self.num_facets, FacetState.TENSILE, dtype=np.int8)
        if self._filter is not None:  # one filtered stress per facet, no strength points
            tractions = [self.filtered_tractions(loads)]
        else:
            # glued facets are zeroed below: recovering their traction here is wasted work
            snaps = (self.snapshot(loads, points=p, recover=False) for p in self.strength_points)
            tractions = [(snap.normal_traction, snap.shear_traction) for snap in snaps]
        for tn, tau in tractions:
            check = check_failure(tn, tau, self.t0, self.c0, self.model.friction)
            worse = check.ratio > ratio
            ratio = np.where(worse, check.ratio, ratio)
            mode = np.where(worse, check.mode, mode)
        # a glued facet breaks only once freed (grow_band): its springs decide then
        breakable = (self.state == FacetState.INTACT) & self.owned & self.band.free
        ratio = np.where(breakable, ratio, 0.0)
        return ratio, mode

    def grow_band(self, loads: Loads) -> int:
        """Free the glued facets whose recovered traction nears their strength (reduced mode).

        Collective.  Returns the global number of facets freed (always 0 in the full
        mode); the caller solves again when it is not 0.
        """
        if self.mode == "full":
            return 0
        if self._filter is not None:
            tractions = self.filtered_tractions(loads)
        else:
            snap = self.snapshot(loads)
            tractions = (snap.normal_traction, snap.shear_traction)
        check = check_failure(*tractions, self.t0, self.c0, self.model.friction)
        near = ~self.band.free & self.owned & (check.ratio >= self.band.threshold)
        return self.band.include(near)

    def free_interfaces(self, flags: np.ndarray, rings: int = 0) -> int:
        """Free the interfaces ``flags`` marks and ``rings`` vertex rings around; collective.

        E.g. joints under fluid pressure: a glued facet carries no jump, so a load on
        its faces would do no work.  Returns the global number freed (0 in the full mode).
        """
        return 0 if self.mode == "full" else self.band.include(flags, rings=rings)

    def break_facets(self, facets: np.ndarray, modes: np.ndarray, load_factor: float) -> None:
        """Break local ``facets`` in ``modes`` (1 tensile, 2 shear) at ``load_factor``."""
        # tensile breaks start open, shear breaks closed; update_contact corrects both
        self.states.break_facets(facets, modes)
        self.sync_ghost_states()
        self._forget_closings_near(facets)
        if self.mode == "reduced":  # the new crack tip's neighbours get springs
            flags = np.zeros(self.num_facets, dtype=bool)
            flags[facets] = True
            self.band.include(flags)
        mids = self.midpoints[facets]
        self.events.append(BreakEvent(load_factor, facets, modes, mids))

    def _forget_closings_near(self, facets: np.ndarray) -> None:
        """Forget where the facets sharing a cell with the new breaks ``facets`` closed.

        Contact hysteresis keeps a closed facet shut until the fluid passes the
        pressure it closed at; a break beside it unloads its springs, so that
        pressure no longer says what holds it shut (collective: the cells'
        flags are gathered over the ranks, so any rank count forgets the same).
        """
        closed = bool(np.any(np.isfinite(self.states.shut_at[self.owned])))
        if not self.comm.allreduce(closed, MPI.LOR):  # no closing kept: nothing to forget
            return
        cmap = self.mesh.topology.index_map(self.mesh.topology.dim)
        vec = dolfinx.la.vector(cmap, 1)
        vec.array[:] = 0.0
        vec.array[self.interface_facets.cells[facets].reshape(-1)] = 1.0
        vec.scatter_reverse(dolfinx.la.InsertMode.add)
        vec.scatter_forward()
        near = (vec.array[self.interface_facets.cells] > 0.0).any(axis=1) & self.owned
        self.states.shut_at[near] = np.nan
        self.sync_ghost_states()

    def release_facets(self, facets: np.ndarray) -> None:
        """Hold the broken local ``facets`` open from now on (collective).

        The faces of a block cut loose from the rock (:mod:`hfcdem.solid.fragments`):
        the fluid around it carries its faces, so it can no longer slide on them.
        """
        self.states.release(facets)
        self.sync_ghost_states()

    def sync_ghost_states(self) -> None:
        """Owners decide; ghosts copy (states live on facets shared by two ranks)."""
        imap = self.mesh.topology.index_map(self.mesh.topology.dim - 1)
        self.states.sync_ghosts(imap, self.facets)

    def equilibrate(self, loads: Loads, max_iterations: int = 200, load_factor: float = 0.0) -> int:
        """Break and switch contacts at fixed ``loads`` until nothing changes (collective).

        See :func:`hfcdem.solid.equilibrium.equilibrate`.
        """
        return equilibrate(self, loads, max_iterations, load_factor)

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

        See :func:`hfcdem.solid.equilibrium.ramp`.
        """
        return ramp(self, base, unit, max_factor, stop_after_first, samples, max_iterations)

    def destroy(self) -> None:
        """Free the solid's factorisations and PETSc matrices now (collective).

        Python alone would leave them, on more than one rank, in their
        communicator's garbage until it is cleaned, and for as long as anything
        (a traceback) still refers to the solid.  Call it when the solid is done with.
        """
        self.operator.destroy()
        if self._filter is not None:
            self._filter.destroy()
        if self._reduced is not None:
            self._reduced.destroy()
            self._reduced, self._reduced_version = None, None

    # ---------------------------------------------------------------- results

    @property
    def breakable(self) -> np.ndarray:
        """Owned interfaces that can break: every one but the pre-existing cracks."""
        return self.owned & ~self.is_crack

    def intact_count(self) -> int:
        """Global number of breakable interfaces still intact."""
        intact = self.breakable & (self.state == FacetState.INTACT)
        return int(self.comm.allreduce(int(np.count_nonzero(intact)), op=MPI.SUM))

    def fracture_degree(self) -> float:
        """Broken interface area / breakable interface area (pre-existing cracks excluded)."""
        breakable = self.breakable
        broken = breakable & (self.state != FacetState.INTACT)
        num = self.comm.allreduce(float(self.areas[broken].sum()), op=MPI.SUM)
        den = self.comm.allreduce(float(self.areas[breakable].sum()), op=MPI.SUM)
        return num / den if den > 0 else 0.0

    def broken_counts(self) -> dict[str, int]:
        """Global numbers of tensile and shear failures (pre-existing cracks excluded)."""
        mask = self.breakable
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


__all__ = [
    "AUTO_DIRECT_MAX_DOFS",
    "GLUE",
    "OPEN",
    "OPEN_FACETS",
    "SLIP",
    "SLIP_FACETS",
    "SPRING",
    "STICK",
    "BreakEvent",
    "CDEMSolid",
    "CascadeStopped",
    "HeldShut",
    "InterfaceSnapshot",
    "Loads",
    "ZoneMarker",
    "combine",
]
