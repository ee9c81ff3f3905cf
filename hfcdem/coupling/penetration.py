"""Breakdown of a cavity under a pressure ramp, the fluid seeping into the joints as it rises.

The cavity pressure rises at a set rate, ``Pw(t) = P0 + A t``.  Every intact
joint of the fracturable zone takes fluid from the cavity by the joint seepage
of :mod:`hfcdem.flow.seepage` and its pressure loads both faces of the joint,
so its springs carry the effective traction (total traction plus joint
pressure) and the failure check of the joints is an effective-stress check.
The joints' hydraulic aperture is a rock property (it does not follow the
solid before the first break), so until then the coupling is one way: one
seepage step, then one back-solve of the solid with the factorisation kept.
Within a step the loads are interpolated linearly between its two ends and
the first crossing of the failure envelope is located there (the ramp
machinery of :mod:`hfcdem.solid.equilibrium`), so the breakdown pressure
carries the time-step error of the seepage only.

The two classical limits follow from the rate alone: fast, the joints are dry
when the wall breaks (Hubbert-Willis, fluid not penetrating); slow, the joints
stand at the cavity pressure (Haimson-Fairhurst, penetrating; with eta about 0
for stiff joints in impermeable blocks, see docs/seepage.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from hfcdem.config.materials import Fluid
from hfcdem.coupling.condense import cavity_vertices, mesh_cavity_volume
from hfcdem.coupling.events import (
    check_small_displacement,
    facets_to_break,
    release_debris,
    switch_contacts,
)
from hfcdem.coupling.groups import joined_cracks
from hfcdem.flow.apertures import JointAperture, network_apertures
from hfcdem.flow.network import gather_rows
from hfcdem.flow.seepage import JointSeepage, joint_network, network_positions
from hfcdem.io.progress import Cadence
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.equilibrium import critical_factor
from hfcdem.solid.forms import Loads, combine
from hfcdem.solid.fragments import Fragments
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import OPEN, CascadeStopped
from hfcdem.solvers import ValidityLimit

#: the cavity balance of a pumped step holds to this fraction of the step's volume
_BALANCE_TOLERANCE = 1e-10
_BALANCE_ITERATIONS = 60


@dataclass(frozen=True)
class PressureRamp:
    """Cavity pressure ``P0 + rate t`` up to ``max_pressure``, in ``steps`` equal steps.

    ``rate`` in Pa/s, pressures in Pa; ``filling``: ``"saturation"`` (joints
    start dry and take their volume ``a A`` before they hold pressure) or
    ``"compressible"`` (joints start full at ``P0``).
    """

    rate: float
    max_pressure: float
    steps: int = 200
    initial_pressure: float = 0.0
    filling: str = "saturation"

    def __post_init__(self) -> None:
        for name, value in (
            ("rate", self.rate),
            ("max_pressure", self.max_pressure),
            ("initial_pressure", self.initial_pressure),
        ):
            if not math.isfinite(value):
                raise ValueError(f"PressureRamp.{name} must be finite, got {value!r}")
        if not self.rate > 0.0:
            raise ValueError(f"PressureRamp.rate must be > 0 Pa/s, got {self.rate!r}")
        if not self.max_pressure > self.initial_pressure:
            raise ValueError(
                "PressureRamp.max_pressure must exceed initial_pressure (Pa), got "
                f"{self.max_pressure!r} <= {self.initial_pressure!r}"
            )
        if not (isinstance(self.steps, int) and 1 <= self.steps <= 10**7):
            raise ValueError(
                f"PressureRamp.steps must be an integer in [1, 1e7], got {self.steps!r}"
            )
        if self.filling not in ("saturation", "compressible"):
            raise ValueError(
                f"PressureRamp.filling must be 'saturation' or 'compressible', got {self.filling!r}"
            )

    @property
    def dt(self) -> float:
        """Time step (s)."""
        return (self.max_pressure - self.initial_pressure) / self.rate / self.steps


@dataclass(frozen=True)
class CavityPumping:
    """Pump ``rate`` (m^3/s; per metre in 2D) into the cavity for ``duration`` s.

    The cavity stores ``V / Kw`` per pascal for its fluid (``V`` from the mesh
    plus ``extra_volume``) and ``dV/dP`` of its walls (from the solid: one
    solve at a unit cavity pressure); the joints at its wall take their share
    each step, the cavity pressure being the one that balances the step's
    volume.  ``steps`` equal steps; ``initial_pressure`` in the cavity at t = 0.
    ``joint_pressure``: the joints start full at this pressure (Pa; the rock's
    pore pressure), or dry (None).  ``max_dt`` (s): the pumped run of
    :mod:`hfcdem.coupling.pumping` may grow a quiet step up to it; None keeps
    every step at :attr:`dt`.  ``land_on_breaks``: a step in which an
    interface first fails is shortened to land on it (False: the interfaces
    overstressed at the step's end break then, at most a step late).
    ``landing_tolerance``: a step lands only when it moved the cavity pressure
    by more than this fraction of it, so a break that is not landed is off by
    about that fraction at most (0: every step lands).  ``until_first_break``:
    end the run after the step of the first break (the pumping's first crack,
    without the cascade after it).
    """

    rate: float
    duration: float
    steps: int = 200
    initial_pressure: float = 0.0
    extra_volume: float = 0.0
    max_dt: float | None = None
    land_on_breaks: bool = True
    landing_tolerance: float = 0.0
    joint_pressure: float | None = None
    until_first_break: bool = False

    def __post_init__(self) -> None:
        for name in ("rate", "duration", "initial_pressure", "extra_volume"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(
                    f"CavityPumping.{name} must be finite, got {getattr(self, name)!r}"
                )
        if not 0.0 < self.rate <= 10.0:
            raise ValueError(f"CavityPumping.rate must be in (0, 10] m^3/s, got {self.rate!r}")
        if not self.duration > 0.0:
            raise ValueError(f"CavityPumping.duration must be > 0 s, got {self.duration!r}")
        if self.initial_pressure < 0.0 or self.extra_volume < 0.0:
            raise ValueError(
                "CavityPumping.initial_pressure (Pa) and extra_volume (m^3) must be >= 0"
            )
        if not (isinstance(self.steps, int) and 1 <= self.steps <= 10**7):
            raise ValueError(
                f"CavityPumping.steps must be an integer in [1, 1e7], got {self.steps!r}"
            )
        for name in ("land_on_breaks", "until_first_break"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(
                    f"CavityPumping.{name} must be True or False, got {getattr(self, name)!r}"
                )
        if not 0.0 <= self.landing_tolerance <= 1.0:
            raise ValueError(
                "CavityPumping.landing_tolerance must be a fraction in [0, 1], got "
                f"{self.landing_tolerance!r}"
            )
        if self.max_dt is not None and not (math.isfinite(self.max_dt) and self.max_dt > 0.0):
            raise ValueError(
                f"CavityPumping.max_dt must be a finite time > 0 s or None, got {self.max_dt!r}"
            )
        p = self.joint_pressure
        if p is not None and not (math.isfinite(p) and 0.0 <= p <= 1e9):
            raise ValueError(
                f"CavityPumping.joint_pressure must be None (dry joints) or a pressure in "
                f"[0, 1 GPa] (Pa), got {p!r}"
            )

    @property
    def dt(self) -> float:
        """Time step (s)."""
        return self.duration / self.steps

    filling = "saturation"


@dataclass(frozen=True)
class RampBreakdown:
    """First break of a :class:`PressureRamp` (``pressure`` None: nothing broke).

    ``wet_fraction``: share of the zone's joints holding pressure at the break;
    ``wall_joint_pressure``: mean joint pressure of the joints on the cavity
    wall over the cavity pressure, at the break;
    ``joint_pressure``, ``saturation``: per local facet of the solid (0 off the
    joints) at the break, or at the end of the ramp;
    ``cavity_storage``: m^3 per Pa of the pumped cavity (None for a ramp);
    ``max_mass_error``: largest ``|pumped - stored in the cavity - in the
    joints|`` of a step over the pumped volume;
    ``stopped``: why no ramp ran (the excavated state cascades);
    ``initial_failures``: joints broken at the start, before the ramp (not
    the breakdown; they hold no fluid); ``history``: per step
    ``(time, cavity pressure, fluid in the joints (m^3), load fraction of the step
    at which the first joint fails or inf)``.
    """

    pressure: float | None
    time: float | None
    mode: int | None
    location: np.ndarray | None
    wet_fraction: float
    wall_joint_pressure: float
    steps: int
    initial_failures: int = 0
    history: list[tuple[float, float, float, float]] = field(default_factory=list)
    joint_pressure: np.ndarray | None = None
    saturation: np.ndarray | None = None
    stopped: str | None = None
    cavity_storage: float | None = None
    max_mass_error: float = 0.0


def joints_at_start(loading: PressureRamp | CavityPumping) -> float | None:
    """Return the joints' pressure at t = 0 (Pa), or None: they start dry.

    A compressible ramp's joints start full at its initial pressure; pumping's
    at its ``joint_pressure`` when it has one.
    """
    if isinstance(loading, CavityPumping):
        return loading.joint_pressure
    return loading.initial_pressure if loading.filling == "compressible" else None


def ramp_breakdown(
    solid: CDEMSolid,
    cavity: Sequence[str],
    fluid: Fluid,
    aperture: float | np.ndarray | JointAperture,
    ramp: PressureRamp | CavityPumping,
    progress: Callable[[str], None] | None = None,
) -> RampBreakdown:
    """Raise the pressure of the ``cavity`` facet groups until the first joint breaks (collective).

    ``ramp``: the cavity pressure as a :class:`PressureRamp`, or a
    :class:`CavityPumping` rate into the cavity (its pressure follows from its
    storage and the joints' intake).

    ``solid`` with every interface intact or a pre-existing crack, full or
    reduced (a reduced solid's zone is freed first: the joints' pressure loads
    every interface of it); ``aperture``: hydraulic aperture of the joints (m), one
    value or one per network facet, or a :class:`~hfcdem.flow.apertures.JointAperture`
    that follows the mesh size.
    """
    for name in cavity:
        solid.tmesh.facet_tag(name)  # clear error for unknown groups
    solid.free_interfaces(np.ones(solid.num_facets, dtype=bool))  # (0 in the full mode)
    # the state the ramp starts from (excavated, cavity at P0): what fails there, e.g. on
    # stress noise where the wall mesh changes, breaks first and is not the breakdown
    start = excavation_loads(solid, cavity, ramp.initial_pressure, joints_at_start(ramp))
    try:  # blocks the excavation cuts loose from the wall are debris, as in a pumped run
        initial_failures = settle_excavation(solid, start, fragments=Fragments(solid, cavity))
    except (CascadeStopped, ValidityLimit) as stop:  # the excavated rock does not stand
        return RampBreakdown(
            None,
            None,
            None,
            None,
            0.0,
            0.0,
            0,
            settled_failures(solid, stop),
            stopped=f"the excavated rock fails before the ramp: {stop}",
        )
    if progress is not None and initial_failures:  # said before the ramp's lines
        progress(f"initial state: {initial_failures} interfaces fail before the ramp")
    drive = _Drive(solid, tuple(cavity), fluid, aperture, ramp)
    t, pw, pj = 0.0, ramp.initial_pressure, drive.seep.pressure
    history: list[tuple[float, float, float, float]] = []
    cadence = Cadence(ramp.steps, solid.comm)
    try:
        for n in range(1, ramp.steps + 1):
            pw_new = drive.advance(n, pw)
            pj_new = drive.seep.pressure
            base = drive.loads(pw, pj)
            unit = drive.loads(pw_new - pw, pj_new - pj, in_situ=0.0)
            solid.solve(base, unit)
            crit = critical_factor(solid, base, unit, 0.0, 1.0, 8)
            s = solid.comm.allreduce(float(crit.min()) if crit.size else math.inf, op=MPI.MIN)
            history.append((t + ramp.dt, pw_new, float(drive.seep.content.sum()), s))
            if progress is not None and cadence.due(n, math.isfinite(s)):
                progress(
                    f"  t {t + ramp.dt:.4g} s, cavity {pw_new / 1e6:.4g} MPa, "
                    f"joints holding pressure {np.mean(pj_new > 0) if pj_new.size else 0.0:.1%}"
                )
            if math.isfinite(s):
                mode, where = _first_facet(solid, base, unit, s, crit)
                broke = (pw + s * (pw_new - pw), t + s * ramp.dt, mode, where)
                return drive.result(broke, pj + s * (pj_new - pj), n, initial_failures, history)
            t, pw, pj = t + ramp.dt, pw_new, pj_new
    finally:
        drive.seep.destroy()
    return drive.result(None, pj, ramp.steps, initial_failures, history)


class _Drive:
    """The joints' seepage and the cavity pressure that drives it, step by step."""

    def __init__(
        self,
        solid: CDEMSolid,
        cavity: tuple[str, ...],
        fluid: Fluid,
        aperture: float | np.ndarray | JointAperture,
        ramp: PressureRamp | CavityPumping,
    ) -> None:
        self.solid, self.cavity, self.ramp = solid, cavity, ramp
        # as in a pumped run: what the excavation broke and joined to the cavity takes its
        # pressure; every other interface of the zone, broken ones too, is a joint
        walls = cavity_vertices(solid, cavity, None)
        self.cracks = joined_cracks(solid, walls) & ~solid.is_crack
        self.joints = np.flatnonzero(~solid.is_crack & ~self.cracks)
        mine = self.cracks & solid.owned
        boundary = np.union1d(walls, gather_rows(solid.comm, solid.vertex_ids[mine].reshape(-1)))
        self.net = joint_network(solid, boundary, self.joints)
        self.local = network_positions(solid, self.net, self.joints)
        void = None
        if isinstance(aperture, JointAperture):
            aperture, void = network_apertures(solid, self.net, self.joints, aperture, self.local)
        wet = joints_at_start(ramp)
        if ramp.filling == "saturation":  # dry joints hold no pressure
            self.seep = JointSeepage(
                self.net,
                aperture,
                fluid,
                pressure=wet or 0.0,
                filling="saturation",
                saturation=0.0 if wet is None else 1.0,
                void_aperture=void,
            )
        else:
            self.seep = JointSeepage(
                self.net, aperture, fluid, pressure=ramp.initial_pressure, void_aperture=void
            )
        self.wall = np.unique(self.seep.cavity_facets)
        self.storage = None
        if isinstance(ramp, CavityPumping):
            self.storage = _cavity_storage(solid, cavity, fluid, ramp.extra_volume, self.cracks)
        self.joints0 = float(self.seep.content.sum())
        self.worst = 0.0  # largest relative mass balance error of a pumped step

    def per_facet(self, values: np.ndarray) -> np.ndarray:
        """Network values on the solid's local facets (0 off the joints)."""
        out = np.zeros(self.solid.num_facets)
        out[self.joints] = values[self.local]
        return out

    def loads(self, pw: float, pj: np.ndarray, in_situ: float = 1.0) -> Loads:
        """Return the loads of the cavity at ``pw`` and the joints at ``pj`` (network order)."""
        return cavity_fluid_loads(
            self.solid, self.cavity, pw, self.cracks, self.per_facet(pj), in_situ
        )

    def advance(self, n: int, pw: float) -> float:
        """Step the seepage to the end of step ``n``; return the cavity pressure there."""
        ramp, dt = self.ramp, self.ramp.dt
        if isinstance(ramp, PressureRamp):
            pw_new = ramp.initial_pressure + ramp.rate * n * dt
            self.seep.step(dt, pw_new)
            return pw_new
        assert self.storage is not None
        pw_new = _balance_cavity(self.seep, dt, pw, ramp.rate * dt, self.storage)
        pumped = ramp.rate * n * dt
        stored = self.storage * (pw_new - ramp.initial_pressure)
        error = pumped - stored - (float(self.seep.content.sum()) - self.joints0)
        self.worst = max(self.worst, abs(error) / pumped)
        return pw_new

    def result(
        self,
        broke: tuple[float, float, int, np.ndarray] | None,
        pj: np.ndarray,
        steps: int,
        initial_failures: int,
        history: list[tuple[float, float, float, float]],
    ) -> RampBreakdown:
        """Return the answer; ``broke``: (pressure, time, mode, location) of the first break."""
        wet = float(np.mean(pj > 0.0)) if self.net.size else 0.0
        wall = 0.0
        if broke is not None and self.wall.size:
            wall = float(np.mean(pj[self.wall]) / broke[0])
        return RampBreakdown(
            pressure=None if broke is None else broke[0],
            time=None if broke is None else broke[1],
            mode=None if broke is None else broke[2],
            location=None if broke is None else broke[3],
            wet_fraction=wet,
            wall_joint_pressure=wall,
            steps=steps,
            initial_failures=initial_failures,
            history=history,
            joint_pressure=self.per_facet(pj),
            saturation=self.per_facet(self.seep.saturation),
            cavity_storage=self.storage,
            max_mass_error=self.worst,
        )


def cavity_fluid_loads(
    solid: CDEMSolid,
    cavity: Sequence[str],
    pressure: float,
    joined: np.ndarray,
    fluid: np.ndarray,
    in_situ: float = 1.0,
) -> Loads:
    """Return the loads of a cavity at ``pressure`` and of the fluid in the zone's interfaces.

    The broken facets ``joined`` to the cavity (a mask per local facet) hold its
    pressure; ``fluid`` (per local facet) loads the inside of the intact
    interfaces and the faces of the other broken ones.  The one rule of the
    settle, the ramp and the pumped run.
    """
    intact = solid.state == FacetState.INTACT
    return Loads(
        cavity={name: pressure for name in cavity},
        crack_pressure=np.where(joined, pressure, np.where(intact, 0.0, fluid)),
        joint_pressure=np.where(intact, fluid, 0.0),
        in_situ_factor=in_situ,
    )


def excavation_loads(
    solid: CDEMSolid, cavity: Sequence[str], pressure: float, joint_pressure: float | None
) -> Callable[[], Loads]:
    """Return the excavated state's loads at the solid's states then (collective).

    The cavity holds ``pressure``, and so do the broken facets joined to it
    through broken facets (its fluid fills them).  Joints full at
    ``joint_pressure`` (None: dry) hold it inside the intact ones and on the
    faces of the other broken ones (the pore fluid stays in them).  A ramp and
    a pumped run start from these loads, so what the excavation breaks is
    settled under them.
    """
    walls = cavity_vertices(solid, cavity, None)
    wet = 0.0 if joint_pressure is None else joint_pressure

    def loads() -> Loads:
        joined = joined_cracks(solid, walls) & ~solid.is_crack
        fluid = np.where(solid.is_crack, 0.0, wet)
        return cavity_fluid_loads(solid, cavity, pressure, joined, fluid)

    return loads


def settle_excavation(
    solid: CDEMSolid,
    loads: Loads | Callable[[], Loads],
    max_iterations: int = 200,
    fragments: Fragments | None = None,
    supports: Sequence[str] = (),
) -> int:
    """Break what ``loads`` over-stress, switching contacts, until nothing changes.

    ``loads``: fixed, or a function of the solid's states (e.g.
    :func:`excavation_loads`, where a break joined to the cavity takes its
    pressure), called after every change.  As a pumped step does
    (:meth:`hfcdem.coupling.pumping._PumpedCavity.step`): every solved state
    is checked against the small-displacement limit, its contacts are switched
    (:func:`hfcdem.coupling.events.switch_contacts`; after one round since the
    last break faces may only close, which ends the chatter of dry broken faces
    at the excavated wall) and only then its strength, so a new tensile break,
    which starts open, is not taken for an unloaded face by its neighbours
    while the rock presses it shut; and after a break the blocks cut loose from
    the walls are debris (``fragments``: the walls' :class:`Fragments`;
    ``supports``: walls that hold the loose blocks against them; see
    :func:`hfcdem.coupling.events.release_debris`).  It ends on a free round
    that switches nothing (or that its closing rounds undo), so the first step
    does not go on breaking the excavation.  Checking the strength first, with
    no debris, a wedge cut out of the wall at Weibull m = 2 and 3 flew hundreds
    of metres on its residual springs and every interface of the borehole plate
    broke (1,530 at 0 MPa); now a breakout of 62 and 25 at the wall.  Returns
    the global number broken; :class:`CascadeStopped` if it does not settle,
    :class:`~hfcdem.solvers.ValidityLimit` at a block cut loose that is not
    debris (none given, or one away from the walls).
    """
    at = loads if callable(loads) else (lambda: loads)
    broken, rounds, last = 0, 0, None
    for _ in range(max_iterations):
        current = at()
        solid.solve(current)
        check_small_displacement(solid, 0.0)
        if switch_contacts(solid, current, only_closing=rounds >= 1):
            rounds += 1
            continue
        ratio, mode = solid.overstress(current)
        chosen = facets_to_break(solid, ratio, None)
        count = int(solid.comm.allreduce(len(chosen), op=MPI.SUM))
        if count == 0:
            if rounds == 0:  # a free round switched nothing: nor will the next step's
                return broken
            # the closing-only rounds may hold faces shut or stuck that a free round
            # (the next step's first) lets open or slip: one more, unless the last one
            # came back to these contacts (chatter)
            same = last is not None and np.array_equal(last, solid.contact)
            if solid.comm.allreduce(same, op=MPI.LAND):
                return broken
            last, rounds = solid.contact.copy(), 0
            continue
        solid.break_facets(chosen, mode[chosen], 0.0)
        broken, rounds, last = broken + count, 0, None
        if fragments is not None:
            release_debris(solid, fragments, supports)
    raise CascadeStopped(0.0, broken, max_iterations)


def settled_failures(solid: CDEMSolid, stop: CascadeStopped | ValidityLimit) -> int:
    """Interfaces a :func:`settle_excavation` that stopped broke (global; collective).

    The settle starts from intact interfaces and pre-existing cracks, so every
    failure of the solid is its own.
    """
    if isinstance(stop, CascadeStopped):
        return stop.broken
    return sum(solid.broken_counts().values())


def _cavity_storage(
    solid: CDEMSolid, cavity: Sequence[str], fluid: Fluid, extra: float, joined: np.ndarray
) -> float:
    """Fluid the cavity takes per pascal: ``V / Kw`` plus its walls' ``dV/dP`` (collective).

    The wall term is one solve at a unit cavity pressure, which loads the
    broken facets ``joined`` to the cavity too (its fluid fills them; e.g. the
    faces of debris the excavation cut loose, which its pressure surrounds):
    ``-int u.n ds`` with ``n`` out of the rock (the walls move into the rock as
    the pressure rises), plus the open joined facets' opening, with their
    fluid's overlap ``1 / kn`` (as a pumped run's slope,
    :meth:`hfcdem.coupling.pumping._PumpedCavity._slope`).
    """
    volume = mesh_cavity_volume(solid, cavity) + extra
    none = np.zeros(solid.num_facets)
    solid.solve(cavity_fluid_loads(solid, cavity, 1.0, joined, none, in_situ=0.0))
    n = ufl.FacetNormal(solid.mesh)
    form = sum(-ufl.dot(solid.u, n) * solid.tmesh.ds(name) for name in cavity)
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form))
    wall = float(solid.comm.allreduce(local, op=MPI.SUM))
    cracks = joined & solid.owned & (solid.state != FacetState.INTACT) & (solid.contact == OPEN)
    if solid.comm.allreduce(bool(cracks.any()), op=MPI.LOR):
        opening = -np.einsum("fi,fi->f", solid.jumps(solid.u), solid.normals)
        mine = float(np.sum(solid.areas[cracks] * (opening[cracks] + 1.0 / solid.kn[cracks])))
        wall += float(solid.comm.allreduce(mine, op=MPI.SUM))
    return volume / fluid.bulk_modulus + wall


def _balance_cavity(
    seep: JointSeepage, dt: float, p_old: float, volume: float, storage: float
) -> float:
    """Cavity pressure at the end of a step that pumps ``volume`` into it; steps ``seep`` there.

    The pressure balances ``storage (P - P_old) + (intake of the joints) = volume``;
    the intake grows with ``P``, so the residual is monotone: a bracketed secant
    (Illinois) finds it, each evaluation one seepage step from the same state.
    """
    saved = seep.save()

    def residual(p: float) -> float:
        seep.restore(saved)
        seep.step(dt, p)
        return storage * (p - p_old) + seep.flux_into_network() - volume

    tol = _BALANCE_TOLERANCE * volume
    lo, hi = p_old, p_old + volume / storage
    r_lo, r_hi = residual(lo), residual(hi)
    while r_hi < 0.0:  # the joints push fluid back into the cavity: look higher
        lo, r_lo, hi = hi, r_hi, hi + 2.0 * (hi - p_old)
        r_hi = residual(hi)
    if r_lo > 0.0:  # the joints take more than is pumped: the pressure falls
        lo, r_lo = 0.0, residual(0.0)
    p, r, converged = illinois_root(
        residual, (lo, r_lo), (hi, r_hi), tol, 1e-12, _BALANCE_ITERATIONS
    )
    if converged:
        return p
    raise RuntimeError(
        f"cavity balance did not converge in {_BALANCE_ITERATIONS} seepage steps "
        f"(dt = {dt!r} s, residual {r:.3g} m^3 of {volume:.3g}); try a smaller time step"
    )


def illinois_root(
    residual: Callable[[float], float],
    low: tuple[float, float],
    high: tuple[float, float],
    tol: float,
    width: float,
    iterations: int,
) -> tuple[float, float, bool]:
    """Root of an increasing ``residual`` bracketed by ``low`` and ``high`` (Illinois).

    ``low``, ``high``: ``(x, residual(x))`` with the residual <= 0 at ``low``,
    >= 0 at ``high``.  Stops when ``|r| <= tol`` or the bracket is narrower than
    ``width`` times ``max(|x_high|, 1)``; returns ``(x, r, converged)``.
    """
    (lo, r_lo), (hi, r_hi) = low, high
    p, r, side = lo, r_lo, 0
    for _ in range(iterations):
        p = (lo * r_hi - hi * r_lo) / (r_hi - r_lo) if r_hi != r_lo else 0.5 * (lo + hi)
        r = residual(p)
        if abs(r) <= tol or hi - lo <= width * max(abs(hi), 1.0):
            return p, r, True
        if r > 0.0:
            hi, r_hi = p, r
            if side == 1:
                r_lo *= 0.5
            side = 1
        else:
            lo, r_lo = p, r
            if side == -1:
                r_hi *= 0.5
            side = -1
    return p, r, False


def _first_facet(
    solid: CDEMSolid, base: Loads, unit: Loads, s: float, crit: np.ndarray
) -> tuple[int, np.ndarray]:
    """Failure mode and midpoint of the facet that breaks first (the same on every rank)."""
    solid.u.x.array[:] += s * solid.u_unit.x.array
    _, modes = solid.overstress(combine(base, unit, s))  # collective
    best = np.full(solid.gdim + 1, np.inf)
    if crit.size and float(crit.min()) == s:
        intact = np.flatnonzero((solid.state == FacetState.INTACT) & solid.owned)
        f = intact[int(np.argmin(crit))]
        best = np.concatenate([[float(modes[f])], solid.midpoints[f, : solid.gdim]])
    # the lowest rank holding the first break speaks for all
    holder = solid.comm.rank if np.isfinite(best[0]) else solid.comm.size
    best = solid.comm.bcast(best, root=solid.comm.allreduce(holder, op=MPI.MIN))
    return int(best[0]), np.asarray(best[1:])


__all__ = [
    "CavityPumping",
    "PressureRamp",
    "RampBreakdown",
    "cavity_fluid_loads",
    "excavation_loads",
    "illinois_root",
    "joints_at_start",
    "ramp_breakdown",
    "settle_excavation",
    "settled_failures",
]
