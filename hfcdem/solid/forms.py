"""The UFL forms of the CDEM solid, its loads and its boundary conditions.

Interior facets are tagged by the integral they carry (:func:`interface_tags`):
springs while intact or stuck, fluid pressure while open, normal spring and
friction while sliding, Nitsche glue outside the fracturable zone.  Every number
enters as a ``Constant`` (or a per-facet Crouzeix-Raviart function), so new
loads, stiffnesses or states never recompile a form.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.materials import ElasticMaterial, InterfaceModel
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.elastic import strain, stress
from hfcdem.solid.facets import FacetFunctions, InterfaceFacets
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.retag import TaggedForm
from hfcdem.solid.states import OPEN, SLIP, InterfaceStates

# interior-facet integral ids
SPRING = 1  # intact, or broken and closed in stick: kn and ks
OPEN_FACETS = 2  # broken/pre-existing and open: fluid pressure, no springs
SLIP_FACETS = 3  # broken, closed, sliding: kn and a friction traction
GLUE = 4  # outside the zone: Nitsche continuity


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


def combine(base: Loads, unit: Loads, lam: float) -> Loads:
    """Return ``base + lam * unit`` (cavity, crack and joint pressures, in-situ factor)."""
    cavity = dict(base.cavity)
    for name, p in unit.cavity.items():
        cavity[name] = cavity.get(name, 0.0) + lam * p
    joint: np.ndarray | None = None
    for item, factor in ((base.joint_pressure, 1.0), (unit.joint_pressure, lam)):
        if item is not None:
            term = factor * np.asarray(item, dtype=float)
            joint = term if joint is None else joint + term
    return Loads(
        cavity=cavity,
        crack_pressure=np.asarray(base.crack_pressure) + lam * np.asarray(unit.crack_pressure)
        if not (np.isscalar(base.crack_pressure) and np.isscalar(unit.crack_pressure))
        else float(base.crack_pressure) + lam * float(unit.crack_pressure),  # type: ignore[arg-type]
        joint_pressure=joint,
        in_situ_factor=base.in_situ_factor + lam * unit.in_situ_factor,
    )


def interface_values(states: InterfaceStates) -> np.ndarray:
    """Return the integral each interface carries: SPRING, OPEN_FACETS or SLIP_FACETS."""
    broken = states.state != FacetState.INTACT
    values = np.full(len(states.state), SPRING, dtype=np.int32)
    values[broken & (states.contact == OPEN)] = OPEN_FACETS
    values[broken & (states.contact == SLIP)] = SLIP_FACETS
    return values


def change_code(old: int, new: int) -> int:
    """Tag of an interface whose integral changed from ``old`` to ``new``."""
    return 10 * old + new


INTERFACE_INTEGRALS = (SPRING, OPEN_FACETS, SLIP_FACETS)
CHANGES = tuple(
    (old, new) for old in INTERFACE_INTEGRALS for new in INTERFACE_INTEGRALS if old != new
)


def change_tags(
    mesh: dolfinx.mesh.Mesh, facets: InterfaceFacets, old: np.ndarray, new: np.ndarray
) -> dolfinx.mesh.MeshTags:
    """Tag the interfaces whose integral changed by :func:`change_code` (others untagged)."""
    changed = old != new
    idx = facets.facets[changed].astype(np.int32)
    vals = (10 * old[changed] + new[changed]).astype(np.int32)
    order = np.argsort(idx)
    return dolfinx.mesh.meshtags(mesh, mesh.topology.dim - 1, idx[order], vals[order])


def interface_tags(
    mesh: dolfinx.mesh.Mesh, facets: InterfaceFacets, states: InterfaceStates
) -> dolfinx.mesh.MeshTags:
    """Tag interface facets by their integral: SPRING, OPEN_FACETS, SLIP_FACETS or GLUE."""
    values = interface_values(states)
    glue = facets.glue_facets
    idx = np.concatenate([facets.facets, glue]).astype(np.int32)
    vals = np.concatenate([values, np.full(len(glue), GLUE, dtype=np.int32)])
    order = np.argsort(idx)
    return dolfinx.mesh.meshtags(mesh, mesh.topology.dim - 1, idx[order], vals[order])


class SolidForms:
    """Stiffness and load forms of the blocks, springs, contacts and glue."""

    def __init__(
        self,
        tmesh: TaggedMesh,
        V: dolfinx.fem.FunctionSpace,
        material: ElasticMaterial,
        model: InterfaceModel,
        sigma0: np.ndarray,
        nitsche_penalty: float,
        facet_functions: FacetFunctions,
        walls: Mapping[str, float] | None = None,
    ) -> None:
        self.tmesh = tmesh
        self.mesh = mesh = tmesh.mesh
        self.V = V
        # exterior groups drilled at a fixed pressure, then cased: the casing holds them
        # (springs as stiff as the interfaces') at the drilled state, ``wall_reference``
        self.walls = dict(walls or {})
        self.wall_reference = dolfinx.fem.Function(V, name="drilled_state")
        self.casing = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
        self.material = material
        self.sigma0 = sigma0
        self.facet_functions = facet_functions
        scalar = dolfinx.default_scalar_type
        # stiffness factors as Constants: changing alpha or the rock never recompiles
        self._kn = dolfinx.fem.Constant(mesh, scalar(model.alpha * material.youngs_modulus))
        self._ratio = dolfinx.fem.Constant(
            mesh, scalar(model.shear_stiffness_ratio(material.poisson_ratio))
        )
        self._residual = dolfinx.fem.Constant(mesh, scalar(model.residual_stiffness))
        lam2mu = material.lame_lambda + 2.0 * material.shear_modulus
        self._glue = dolfinx.fem.Constant(mesh, scalar(nitsche_penalty * lam2mu))

    def casing_stiffness(self) -> ufl.core.expr.Expr:
        """Stiffness (Pa/m) of the casing's springs on a drilled wall (0 while drilling)."""
        return self.casing * self._kn / ufl.CellDiameter(self.mesh)

    def _interface_integrands(self) -> dict[int, ufl.core.expr.Expr]:
        """Return the integrand of each interface integral (SPRING, OPEN_FACETS, SLIP_FACETS)."""
        gdim = self.mesh.geometry.dim
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        npl = ufl.FacetNormal(self.mesh)("+")
        kn = self._kn / ufl.avg(ufl.CellDiameter(self.mesh))
        ks = kn * self._ratio
        eye = ufl.Identity(gdim)
        Pn = ufl.outer(npl, npl)
        K = kn * Pn + ks * (eye - Pn)
        ju, jv = ufl.jump(u), ufl.jump(v)
        return {
            SPRING: ufl.inner(K * ju, jv),
            # a residual spring on open and sliding faces keeps detached blocks attached
            OPEN_FACETS: self._residual * ufl.inner(K * ju, jv),
            SLIP_FACETS: ufl.inner(kn * Pn * ju, jv)
            + self._residual * ks * ufl.inner((eye - Pn) * ju, jv),
        }

    def stiffness_change(self, dS: ufl.Measure) -> ufl.Form:
        """Bilinear form of the change of interfaces tagged by :func:`change_code`."""
        terms = self._interface_integrands()
        changes = [(terms[new] - terms[old]) * dS(change_code(old, new)) for old, new in CHANGES]
        return functools.reduce(operator.add, changes)

    def stiffness(self, dS: ufl.Measure) -> ufl.Form:
        """Bilinear form: elasticity, springs by state, Nitsche glue (``dS`` tagged)."""
        mesh, material = self.mesh, self.material
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        npl = ufl.FacetNormal(mesh)("+")
        h = ufl.avg(ufl.CellDiameter(mesh))
        ju, jv = ufl.jump(u), ufl.jump(v)

        a = ufl.inner(stress(u, material), strain(v)) * ufl.dx
        for tag, integrand in self._interface_integrands().items():
            a += integrand * dS(tag)
        # Nitsche glue outside the zone (symmetric interior penalty)
        a += (
            -ufl.inner(ufl.avg(stress(u, material)) * npl, jv)
            - ufl.inner(ufl.avg(stress(v, material)) * npl, ju)
            + self._glue / h * ufl.inner(ju, jv)
        ) * dS(GLUE)
        for name in self.walls:
            a += self.casing_stiffness() * ufl.inner(u, v) * self.tmesh.ds(name)
        return a

    def load(self, loads: Loads, states: InterfaceStates, dS: ufl.Measure) -> ufl.Form:
        """Linear form of ``loads`` at ``states`` (collective: facet functions)."""
        form = LoadForm(self, load_terms(loads, states, self.mesh.comm), dS)
        form.set(loads, states)
        return form.ufl_form


@dataclass(frozen=True)
class LoadTerms:
    """Which terms a load form has: its shape, not its values (a new shape recompiles).

    ``cavity``: the loaded exterior groups; ``facet_crack``: the crack
    pressure is per facet (else one value); ``joints``: a pressure inside
    intact interfaces; ``slip``: friction and in-situ shear on sliding faces.
    """

    cavity: tuple[str, ...]
    facet_crack: bool
    joints: bool
    slip: bool


def load_terms(loads: Loads, states: InterfaceStates, comm: MPI.Comm) -> LoadTerms:
    """Return the terms of ``loads`` at ``states``, the same on every rank (collective)."""
    has_joints = loads.joint_pressure is not None and bool(np.any(loads.joint_pressure))
    flags = np.array([has_joints, bool(np.any(states.contact == SLIP))], dtype=np.int32)
    comm.Allreduce(MPI.IN_PLACE, flags, op=MPI.MAX)
    return LoadTerms(
        cavity=tuple(loads.cavity),
        facet_crack=not np.isscalar(loads.crack_pressure),
        joints=bool(flags[0]),
        slip=bool(flags[1]) and loads.in_situ_factor != 0.0,
    )


class LoadForm:
    """The load form of some :class:`LoadTerms`, its values set per solve.

    Every value is a ``Constant`` or a per-facet function set by :meth:`set`,
    and :meth:`form_at` retags the interface integrals for new states, so a
    solid compiles the form once for all its loads and states (the UFL
    processing and the JIT cache lookup cost 10-20 ms a form, more than a
    back-substitution of a small solid).
    """

    def __init__(self, forms: SolidForms, terms: LoadTerms, dS: ufl.Measure) -> None:
        mesh, gdim = forms.mesh, forms.mesh.geometry.dim
        scalar = dolfinx.default_scalar_type
        self.terms = terms
        self._forms, self._gdim = forms, gdim
        self._compiled: dolfinx.fem.Form | None = None
        self._tagged: TaggedForm | None = None  # form_at: compiled once, retagged per states
        self._at: tuple[int, dolfinx.fem.Form] | None = None

        def const(shape: tuple[int, ...] = ()) -> dolfinx.fem.Constant:
            return dolfinx.fem.Constant(mesh, np.zeros(shape, dtype=scalar))

        facet_function = forms.facet_functions.function
        zeros = np.zeros(forms.facet_functions.size)
        v, n = ufl.TestFunction(forms.V), ufl.FacetNormal(mesh)
        npl, eye = n("+"), ufl.Identity(gdim)
        self._sigma0 = sigma0 = const((gdim, gdim))
        self._cavity = {name: const() for name in terms.cavity}
        L = ufl.inner(const((gdim,)), v) * ufl.dx
        for name, p in self._cavity.items():
            L += -ufl.inner((p * eye + sigma0) * n, v) * forms.tmesh.ds(name)
        # a drilled wall loads with the in-situ stress, never with a unit load: its pressure,
        # and the casing holding it at the drilled state
        self._walls = {name: const() for name in forms.walls}
        self._drilled = const()
        for name, p in self._walls.items():
            held = self._drilled * forms.casing_stiffness() * forms.wall_reference
            L += (-ufl.inner((p * eye + sigma0) * n, v) + ufl.inner(held, v)) * forms.tmesh.ds(name)
        one = {"quadrature_degree": 1}  # per-facet values: exact at the midpoint
        jv = ufl.jump(v)
        self._crack = facet_function(zeros) if terms.facet_crack else const()
        if terms.facet_crack:
            pc = self._crack("+")
            L += -ufl.inner((pc * eye + sigma0) * npl, jv) * dS(OPEN_FACETS, metadata=one)
        else:
            L += -ufl.inner((self._crack * eye + sigma0) * npl, jv) * dS(OPEN_FACETS)
        self._joints = facet_function(zeros) if terms.joints else None
        if self._joints is not None:
            L += -ufl.inner(self._joints("+") * npl, jv) * dS(SPRING, metadata=one)
        self._friction = None
        if terms.slip:
            # friction minus in-situ shear on sliding faces, per facet (+ side); a unit
            # load (no in-situ part) is the linearisation about the current slip set
            self._friction = facet_function(np.zeros((len(zeros), gdim)), (gdim,))
            tau0 = sigma0 * npl - ufl.inner(sigma0 * npl, npl) * npl
            L += ufl.inner(self._friction("+") - tau0, jv) * dS(SLIP_FACETS, metadata=one)
        self.ufl_form = L

    @property
    def form(self) -> dolfinx.fem.Form:
        """The compiled form (collective the first time)."""
        if self._compiled is None:
            self._compiled = dolfinx.fem.form(self.ufl_form)
        return self._compiled

    def form_at(self, tags: dolfinx.mesh.MeshTags, version: int) -> dolfinx.fem.Form:
        """Return the form with its interface integrals over ``tags`` (collective at first).

        ``version`` names the tags: a call with the version of the last one
        returns its form.  Compiled once (:class:`~hfcdem.solid.retag.TaggedForm`).
        """
        if self._tagged is None:
            self._tagged = TaggedForm(self.ufl_form)
        if self._at is None or self._at[0] != version:
            self._at = (version, self._tagged.form(tags))
        return self._at[1]

    def set(self, loads: Loads, states: InterfaceStates) -> None:
        """Set the values of ``loads`` (with the terms of this form) at ``states`` (collective)."""
        if tuple(loads.cavity) != self.terms.cavity:
            raise ValueError(f"loads on {tuple(loads.cavity)}, the form on {self.terms.cavity}")
        assign = self._forms.facet_functions.assign
        self._sigma0.value[:] = loads.in_situ_factor * self._forms.sigma0
        for name, p in self._forms.walls.items():
            self._walls[name].value = loads.in_situ_factor * p
        self._drilled.value = loads.in_situ_factor
        for name, p in loads.cavity.items():
            if not math.isfinite(p):
                raise ValueError(f"cavity pressure on {name!r} must be finite, got {p!r}")
            self._cavity[name].value = p
        if isinstance(self._crack, dolfinx.fem.Constant):
            self._crack.value = float(loads.crack_pressure)
        else:
            assign(self._crack, np.broadcast_to(loads.crack_pressure, (len(states.state),)))
        if self._joints is not None:
            joint = loads.joint_pressure
            assign(self._joints, np.zeros(len(states.state)) if joint is None else joint)
        if self._friction is not None:
            assign(self._friction, states.friction_traction, (self._gdim,))


def dg_boundary_conditions(
    V: dolfinx.fem.FunctionSpace,
    tmesh: TaggedMesh,
    degree: int,
    rollers: Mapping[str, int],
    fixed: Sequence[str],
) -> list[dolfinx.fem.DirichletBC]:
    """Dirichlet conditions on DG dofs that lie on the named boundary facets.

    ``rollers`` hold one displacement component of a group at zero, ``fixed``
    every component.
    """
    import basix

    mesh, tdim, gdim = tmesh.mesh, tmesh.mesh.topology.dim, tmesh.mesh.geometry.dim
    cg = basix.create_element(
        basix.ElementFamily.P, mesh.basix_cell(), degree, basix.LagrangeVariant.gll_warped
    )
    closure = cg.entity_closure_dofs[tdim - 1]
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    bcs = []
    items = [(name, comp) for name, comp in rollers.items()]
    items += [(name, c) for name in fixed for c in range(gdim)]
    for name, comp in items:
        if not 0 <= comp < gdim:
            raise ValueError(f"roller component for {name!r} must be in [0, {gdim})")
        sub = V.sub(comp)
        dofs = []
        for f in tmesh.facets(name):
            for c in f2c.links(f):
                local = int(np.flatnonzero(c2f.links(c) == f)[0])
                cell_dofs = sub.dofmap.cell_dofs(c)
                dofs.extend(cell_dofs[closure[local]])
        dofs_arr = np.unique(np.asarray(dofs, dtype=np.int32))
        bcs.append(dolfinx.fem.dirichletbc(dolfinx.default_scalar_type(0.0), dofs_arr, sub))
    return bcs


def rigid_body_modes(V: dolfinx.fem.FunctionSpace) -> tuple[PETSc.NullSpace, list]:
    """Rigid-body modes of a vector DG space, for algebraic multigrid.

    Returns the near-null space and its vectors: PETSc keeps references to the
    vectors only, so the caller must keep them alive.
    """
    x = V.tabulate_dof_coordinates()
    gdim = V.mesh.geometry.dim
    modes = [dolfinx.la.vector(V.dofmap.index_map, gdim) for _ in range(3 if gdim == 2 else 6)]
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
    space = PETSc.NullSpace().create(vectors=[m.petsc_vec for m in modes], comm=V.mesh.comm)
    return space, modes


__all__ = [
    "CHANGES",
    "GLUE",
    "INTERFACE_INTEGRALS",
    "OPEN_FACETS",
    "SLIP_FACETS",
    "SPRING",
    "LoadForm",
    "LoadTerms",
    "Loads",
    "SolidForms",
    "change_code",
    "change_tags",
    "combine",
    "dg_boundary_conditions",
    "interface_tags",
    "interface_values",
    "load_terms",
    "rigid_body_modes",
]
