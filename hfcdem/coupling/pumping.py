"""Pumping into a cavity past the first break: seepage in the joints, fluid in the cracks.

Fluid is pumped at a constant rate into the cavity (wellbore and tunnels).
The intact joints of the fracturable zone take it by the seepage of
:mod:`hfcdem.flow.seepage` (dry at the start, saturation filling) and their
pressure loads both faces, so they fail on effective stress.  A broken
interface joined to the cavity through broken ones belongs to the cavity: its
fluid stands at the cavity pressure (the "uniform" rung of the fidelity
ladder) and its opening adds to the cavity's volume.  Broken interfaces not
joined to it stay in the seepage network with the joints' aperture.

Each step finds the cavity pressure ``P`` that holds the fluid pumped so far::

    V(P) (1 + P / Kw) + J(P) = M0 + Q t

``V`` is the cavity's volume (mesh, wall motion and crack openings), linear
in ``P`` at fixed interface states (its slope from a unit solve); ``J`` the
joints' content after the seepage step with the cavity at ``P``.  ``P`` and
the joints are one Newton (:meth:`JointSeepage.step_pumped`); a bracketed
secant on trial seepage steps is the fallback where that Newton fails.
``V`` follows the joints' pressures too: by reciprocity ``dV/dp_j`` of a
joint is its volume change under a unit cavity pressure
(:func:`cavity_joint_coupling`, from the same unit solve), so the balance
predicts the walls the joints push.  The solid is then solved at ``P`` with
the joint pressures and ``V`` measured; the balance is repeated until the
measured volume is the balanced one, so the fluid is conserved at the solved
state (what is left to iterate: joints that start or stop holding pressure
within the step, contacts that switch).  Contacts switch
and interfaces break as in the coupled step, each change followed by a new
balance in the same step, so the pressure drops as a crack joined to the
cavity opens.  A step in which an interface would cross its envelope is
shortened to the crossing (the loads interpolated linearly within it).

The breakdown is found as for every coupled run
(:func:`~hfcdem.coupling.breakdown.detect_breakdown`: the highest peak that a
sustained drop confirms; a peak cut off by the end of the run is flagged, not
published), on the cavity pressure with each step's highest pressure, and only
by a drop once some interface has broken (a dip while the dry joints take fluid
and nothing breaks is not one; a pressure that only falls, the joints taking
more than the pump delivers, has none).  The first break is
reported separately: in 3D it is often a shear breakout at the tunnel wall
that takes no fluid and leaves the pressure rising.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from hfcdem.config.materials import Fluid
from hfcdem.coupling.breakdown import detect_breakdown
from hfcdem.coupling.checkpoint import interface_rows, restore_interfaces
from hfcdem.coupling.condense import cavity_vertices, mesh_cavity_volume
from hfcdem.coupling.events import (
    check_small_displacement,
    facets_to_break,
    most_overstressed,
    release_debris,
    switch_contacts,
)
from hfcdem.coupling.groups import joined_cracks
from hfcdem.coupling.penetration import (
    CavityPumping,
    cavity_fluid_loads,
    excavation_loads,
    illinois_root,
    settle_excavation,
    settled_failures,
)
from hfcdem.coupling.stepping import StepController
from hfcdem.flow.apertures import JointAperture, network_apertures
from hfcdem.flow.network import Network, gather_rows
from hfcdem.flow.seepage import (
    CavityDry,
    CavityStorage,
    JointSeepage,
    joint_network,
    network_positions,
    network_values,
)
from hfcdem.io.progress import Cadence, TimeLeft
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.equilibrium import critical_factor
from hfcdem.solid.forms import Loads
from hfcdem.solid.fragments import Fragments
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import OPEN, CascadeStopped, InterfaceStates
from hfcdem.solvers import ValidityLimit

#: called with the time, the fluid pressure and the saturation per local facet
Frames = Callable[[float, np.ndarray, np.ndarray], None]

#: called after every step with its :attr:`PumpingResult.history` and ``costs`` rows
Records = Callable[[tuple[float, ...], tuple[float, ...]], None]

#: columns of :attr:`PumpingResult.costs`, one row per pumped step
COST_COLUMNS = (
    "time_s",
    "step_s",
    "broken",
    "solid_solves",
    "factorisations",
    "low_rank_events",
    "rebalances",
    "factorise_s",
    "low_rank_s",
    "wall_s",
)

#: the measured cavity volume must match the balanced one to this fraction of a step's volume
_VOLUME_TOLERANCE = 1e-8

#: ... or to this fraction of the volume itself (3x the solves' round-off).  No. 2 with seepage
#: at 109.12 s (a step landed short on a crossing) measured 1e-13 of the volume from pass to
#: pass, above the step's share, and balanced again 200 times without a change
_VOLUME_ROUNDOFF = 3e-13

#: ... or, once re-balancing stops shrinking the mismatch for this many passes in a row, to
#: _STALLED_ROUNDOFF of the volume: the mismatch is then the solves' noise, not a state that
#: moves.  No. 2 with seepage at apertures held at 5 mm (coarse, 9 low-rank events on the
#: kept factor) measured 1e-15 to 8e-15 m^3 of its 1.15e-4 m^3 (1e-11 to 7e-11) from pass to
#: pass at the same pressure and states, and balanced again 200 times
_STALLED_PASSES = 3
_STALLED_ROUNDOFF = 1e-9

#: ... or, stalled so, to this fraction of a scene step's injection: the borehole pumped at 500
#: times its rate (coarse, 202 MPa, 330 cracks joined to the cavity and debris) measured
#: 4e-9 of its 0.0135 m^3 from pass to pass (5e-7 of the step's 1e-4 m^3) with nothing
#: changing, and balanced again 197 times
_STALLED_SHARE = 1e-6

#: a step whose first crossing lies before this fraction of it is not shortened
_MIN_FRACTION = 1e-3

#: a shortened step ends this fraction of itself past the crossing, so the facet breaks in it
_PAST = 1e-6

#: shortenings of one step to land on a crossing
_MAX_LANDINGS = 3

#: a step grows by half (up to ``CavityPumping.max_dt``) after one that broke nothing, was
#: not shortened, and moved the cavity pressure as the last step's rate carried on would
#: have, to this fraction of its change (linear in time: a longer step loses nothing) ...
_GROWTH_LINEARITY = 0.1
#: ... and the share of joints holding pressure by at most this much.  A step that broke
#: goes back to the base step ``CavityPumping.dt``; one off the line shrinks by a third
_GROWTH_WET = 0.01


@dataclass
class Course:
    """Where a pumped run stands after a step: what a resumed run goes on from.

    ``steps`` taken to ``t``; ``dt``: the next step's size (None: the scene's);
    ``rate``: the cavity pressure's rate over the last step (Pa/s; None after a
    break); ``first``: the first break's (cavity pressure, time, mode,
    location); ``peak`` at ``peak_time``; ``curve_t``, ``curve_p``: the
    pressure curve the breakdown is read from (each step's highest, then its
    end); ``history`` and ``costs``: the rows of :class:`PumpingResult`.
    """

    t: float = 0.0
    steps: int = 0
    dt: float | None = None
    rate: float | None = None
    first: tuple[float, float, int, np.ndarray] | None = None
    peak: float = 0.0
    peak_time: float = 0.0
    curve_t: list[float] = field(default_factory=list)
    curve_p: list[float] = field(default_factory=list)
    history: list[tuple[float, ...]] = field(default_factory=list)
    costs: list[tuple[float, ...]] = field(default_factory=list)


@dataclass(frozen=True)
class Resume:
    """A stopped pumped run to go on with: its last ``checkpoint`` and the rows of its files.

    ``history`` and ``costs``: the rows of ``history.csv`` and
    ``step_costs.csv`` up to the checkpoint's step (:class:`PumpingResult`).
    """

    checkpoint: Mapping[str, Any]
    history: list[tuple[float, ...]]
    costs: list[tuple[float, ...]]


#: offered, after every step, a function that returns the run's checkpoint (collective: a
#: taker must call it on every rank or on none)
Checkpoint = Callable[[Callable[[], dict[str, Any]]], None]


@dataclass(frozen=True)
class PumpingResult:
    """What a pumped run with seepage found.

    ``first_pressure``, ``first_time``, ``first_mode`` (1 tensile, 2 shear),
    ``first_location``: the first interface to break during pumping (None:
    none broke); ``breakdown``, ``breakdown_time``: the peak cavity pressure
    that a sustained drop confirmed (None: no such peak), and
    ``breakdown_drop``: how far (Pa) the pressure fell after it;
    ``peak_pressure``, ``peak_time``: the highest pressure of the run, and
    ``peak_cut_off``: no drop confirmed a breakdown before the run ended;
    ``history`` rows: ``(time, cavity pressure, fluid in the joints, crack
    volume joined to the cavity, tensile, shear, share of joints holding
    pressure)``; ``max_mass_error``: the largest ``|pumped - held|`` over the
    pumped volume at a step's solved state; ``joint_pressure`` and
    ``saturation`` per local facet of the solid at the end (the cracks joined
    to the cavity at its pressure, saturation 1); ``secant_balances``: cavity
    balances the joint Newton failed and the secant did; ``unsettled_retries``:
    steps taken again at half the step because their interface states did not
    settle (down to the scene's step over 2^4; the run stops past that);
    ``validity_limit``:
    the run stopped where the small-displacement solid no longer holds
    (``stopped`` says where), its history up to there standing;
    ``debris_cells``: cells of the blocks cut loose from the walls, whose faces
    the fluid took (:mod:`hfcdem.solid.fragments`); ``rebalances``: balances
    repeated because the solved volume was not the balanced one;
    ``solid_solves``: the solid's solves during pumping; ``factorisations``:
    the stiffness factorisations during pumping (fresh or numeric only);
    ``low_rank_events``: changes of the interfaces' states taken as a low-rank
    correction of the kept factor instead (:mod:`hfcdem.solid.lowrank`);
    ``costs`` rows, one per step, of :data:`COST_COLUMNS`: where the run spent
    its solves and seconds (the seconds are each rank's own, the counts the
    same on every rank); ``ended_on_first_break``: the run ended after its first
    break as asked (``CavityPumping.until_first_break``), so no breakdown was
    sought.
    """

    first_pressure: float | None
    first_time: float | None
    first_mode: int | None
    first_location: np.ndarray | None
    breakdown: float | None
    breakdown_time: float | None
    peak_pressure: float
    peak_time: float
    peak_cut_off: bool
    initial_failures: int
    steps: int
    history: list[tuple[float, ...]] = field(default_factory=list)
    max_mass_error: float = 0.0
    joint_pressure: np.ndarray | None = None
    saturation: np.ndarray | None = None
    tensile: int = 0
    shear: int = 0
    stopped: str | None = None
    validity_limit: bool = False
    secant_balances: int = 0
    unsettled_retries: int = 0
    debris_cells: int = 0
    breakdown_drop: float | None = None
    rebalances: int = 0
    solid_solves: int = 0
    factorisations: int = 0
    low_rank_events: int = 0
    costs: list[tuple[float, ...]] = field(default_factory=list)
    ended_on_first_break: bool = False


def pump_with_seepage(
    solid: CDEMSolid,
    cavity: Sequence[str],
    fluid: Fluid,
    aperture: float | JointAperture,
    pumping: CavityPumping,
    progress: Callable[[str], None] | None = None,
    max_state_iterations: int = 200,
    frames: Frames | None = None,
    supports: Sequence[str] = (),
    at_first_break: Callable[[float, np.ndarray], None] | None = None,
    contact_hysteresis: bool = True,
    records: Records | None = None,
    checkpoint: Checkpoint | None = None,
    resume: Resume | None = None,
) -> PumpingResult:
    """Pump into the ``cavity`` facet groups and follow breaks and pressure (collective).

    ``solid``: full, or reduced (every interface of its zone is freed first:
    the joints' pressure loads them all, so only the rock outside the zone stays
    continuous); ``aperture``: hydraulic aperture of the joints (m), or a
    :class:`~hfcdem.flow.apertures.JointAperture` that follows the mesh size;
    ``supports``: walls that hold the blocks cut loose against them (a cased
    wellbore's; :func:`~hfcdem.coupling.events.release_debris`).  Runs for
    ``pumping.duration`` in steps of ``pumping.dt``, shortened onto a break
    and, with ``pumping.max_dt``, grown by half after each quiet step up to
    it (no break, the cavity pressure on the line of the last step's rate to
    10 %, the share of joints holding pressure within 1 % of the last step's).
    ``frames`` is called (collectively) at the start and after every step with
    the time and the fluid pressure and saturation per local facet
    (:meth:`_PumpedCavity.fields`); ``at_first_break``
    (collectively) with the time and each local facet's failure ratio when the
    first facets broke, after the step of the first break, when the solid holds
    that step's state.  ``contact_hysteresis``: see
    :meth:`~hfcdem.solid.states.InterfaceStates.switch_contacts`.  ``records``
    is called after every step with its history and cost rows (on every rank),
    so that a run stopped from outside keeps what it did; ``checkpoint`` is
    offered its state after every step (:meth:`_PumpedCavity.checkpoint`), from
    which ``resume`` goes on (the same solid, excavated again; raises
    ValueError for a checkpoint that does not fit it).
    """
    if not isinstance(aperture, JointAperture):
        aperture = JointAperture(aperture)  # checks it
    for name in (*cavity, *supports):
        solid.tmesh.facet_tag(name)  # clear error for unknown groups
    solid.free_interfaces(np.ones(solid.num_facets, dtype=bool))  # (0 in the full mode)
    try:  # blocks the excavation cuts loose from the walls are debris, as in a step
        start = excavation_loads(solid, cavity, pumping.initial_pressure, pumping.joint_pressure)
        initial_failures = settle_excavation(
            solid, start, fragments=Fragments(solid, cavity), supports=supports
        )
    except CascadeStopped as stop:
        why = f"the excavated rock fails before pumping: {stop}"
        return _stopped_before_pumping(pumping, stop.broken, why)
    except ValidityLimit as stop:
        why = f"the excavated rock is past the validity limit before pumping: {stop}"
        failures = settled_failures(solid, stop)
        return _stopped_before_pumping(pumping, failures, why, validity_limit=True)
    if progress is not None and initial_failures and resume is None:  # before the steps' lines
        progress(f"initial state: {initial_failures} interfaces fail before pumping")
    try:
        run = _PumpedCavity(
            solid, tuple(cavity), fluid, aperture, pumping, tuple(supports), contact_hysteresis
        )
    except ValidityLimit as stop:
        why = f"the excavated rock is past the validity limit before pumping: {stop}"
        return _stopped_before_pumping(pumping, initial_failures, why, validity_limit=True)
    try:
        course = None
        if resume is not None:  # the excavated state stays the volumes' reference
            course = run.resume(resume.checkpoint)
            course.history, course.costs = list(resume.history), list(resume.costs)
            initial_failures = int(resume.checkpoint["initial_failures"])
        return run.run(
            initial_failures,
            progress,
            max_state_iterations,
            frames,
            at_first_break,
            records,
            course,
            checkpoint,
        )
    finally:
        run.seep.destroy()


def _stopped_before_pumping(
    pumping: CavityPumping, failures: int, why: str, validity_limit: bool = False
) -> PumpingResult:
    """Return the result of a run that ended before its first step."""
    p0 = pumping.initial_pressure
    return PumpingResult(
        None, None, None, None, None, None, p0, 0.0, True, failures, 0,
        stopped=why, validity_limit=validity_limit,
    )  # fmt: skip


def facet_openings(solid: CDEMSolid, u: dolfinx.fem.Function) -> np.ndarray:
    """Per local facet, the opening of its faces at the midpoint (m) in the displacement ``u``."""
    return -np.einsum("fi,fi->f", solid.jumps(u), solid.normals)


def cavity_joint_coupling(solid: CDEMSolid, opening: np.ndarray) -> np.ndarray:
    """Per local facet, its fluid volume's change (m^3/Pa) under the unit cavity pressure.

    ``opening``: the :func:`facet_openings` of the solid's response to a unit
    pressure in the cavity (at the midpoint, the point at which a facet
    pressure loads the solid); the volume is the facet's area times it.  By
    reciprocity this is also ``dV / dp`` of the cavity's volume under a
    pressure on that facet.  Zero on the facets a fluid pressure does not load
    (broken and closed) and on ghost facets.
    """
    loaded = (solid.state == FacetState.INTACT) | (solid.contact == OPEN)
    return np.where(loaded & solid.owned, solid.areas * opening, 0.0)


def balanced(gap: float, stalled: int, volume: float, injected: float, base: float) -> bool:
    """Whether a cavity balance holds: the measured volume is the balanced one to ``gap`` (m^3).

    To :data:`_VOLUME_TOLERANCE` of the step's ``injected`` volume or
    :data:`_VOLUME_ROUNDOFF` of the cavity's ``volume``; or, once ``stalled``
    re-balances in a row did not halve the gap, to the solves' noise: the larger
    of :data:`_STALLED_ROUNDOFF` of the volume and :data:`_STALLED_SHARE` of
    ``base``, the injection of a step of the scene's size (a step halved to
    settle is held to the same noise, not to a tighter one).
    """
    held = abs(volume)
    if gap <= max(_VOLUME_TOLERANCE * injected, _VOLUME_ROUNDOFF * held):
        return True
    noise = max(_STALLED_ROUNDOFF * held, _STALLED_SHARE * base)
    return stalled >= _STALLED_PASSES and gap <= noise


class _PumpedCavity:
    """The cavity, its cracks and the joints' seepage, stepped together."""

    def __init__(
        self,
        solid: CDEMSolid,
        cavity: tuple[str, ...],
        fluid: Fluid,
        aperture: JointAperture,
        pumping: CavityPumping,
        supports: tuple[str, ...] = (),
        hysteresis: bool = True,
    ) -> None:
        self.solid, self.cavity, self.fluid = solid, cavity, fluid
        self.supports, self.hysteresis = supports, hysteresis
        self.aperture, self.pumping = aperture, pumping
        self.kw = fluid.bulk_modulus
        self.walls = cavity_vertices(solid, cavity, None)
        self.fragments = Fragments(solid, cavity)
        self.debris_cells = 0
        self.debris_news: list[str] = []  # for the progress output
        self.release_debris(0.0)
        self.v_mesh = mesh_cavity_volume(solid, cavity) + pumping.extra_volume
        n = ufl.FacetNormal(solid.mesh)
        ds = solid.tmesh.ds
        self._wall_forms = [
            dolfinx.fem.form(sum(-ufl.dot(u, n) * ds(name) for name in cavity))
            for u in (solid.u, solid.u_unit)
        ]
        self.cracks = self._joined_cracks()
        self.shut: np.ndarray = np.zeros(solid.num_facets, dtype=bool)  # set by _volume
        self._friction_ref = solid.friction_traction.copy()  # set by _volume
        self._unit_jumps = np.zeros((solid.num_facets, solid.gdim))  # set by _linearise
        self.facets, self.net, self.positions, self.seep = self._network(None, None)
        self.p = pumping.initial_pressure
        loads = self.loads(self.p, self.seep.pressure)
        solid.solve(loads)
        try:  # a block the excavation cut loose (and that is not debris) has no volume to hold
            check_small_displacement(solid, 0.0)
        except ValidityLimit:
            self.seep.destroy()
            raise
        self.wall_ref = self._wall(0)
        self.volume = self._volume(loads)  # at self.p
        self._linearise()
        self.rebalances = 0  # balances repeated on the measured volume
        self.solves_before = solid.solves
        self.factorisations_before = self._factorisations()
        self.m0 = self.volume * (1.0 + self.p / self.kw) + self.joint_content()
        self.worst = 0.0
        self.secant_balances = 0  # balances the joint Newton could not do
        self.unsettled_retries = 0  # steps taken again, halved, for states that did not settle
        # the step's start state and the joints after its last balance: the next one's guess
        self._last_balance: tuple[np.ndarray, np.ndarray] | None = None

    # ------------------------------------------------------------- network

    def _factorisations(self) -> tuple[int, int, float, float]:
        """Count the solid's factorisations (fresh and numeric) and low-rank events so far.

        Returns the two counts and their seconds.
        """
        counts, seconds = self.solid.operator.counts, self.solid.operator.seconds
        return (
            counts["assembled"] + counts["updated"],
            counts["low_rank"],
            seconds["factorise"],
            seconds["low_rank"],
        )

    def _joined_cracks(self) -> np.ndarray:
        """Per local facet: broken and joined to the cavity (:func:`joined_cracks`)."""
        return joined_cracks(self.solid, self.walls)

    def release_debris(self, t: float) -> int:
        """Hold open the faces of blocks newly cut loose from the walls; their count.

        See :func:`~hfcdem.coupling.events.release_debris`.
        """
        count, cells, held = release_debris(self.solid, self.fragments, self.supports)
        if held:
            self.debris_news.append(
                f"  t {t:.4g} s: {held} loose cell(s) against a supporting wall held by it"
            )
        if count or cells > self.debris_cells:  # (count 0: released by the excavation's settle)
            faces = f"{count} broken faces" if count else "the broken faces"
            self.debris_news.append(
                f"  t {t:.4g} s: {cells - self.debris_cells} cell(s) cut loose from the wall "
                f"are debris: {faces} around them take the cavity pressure"
            )
            self.debris_cells = cells
        return count

    def _network(
        self, old: Network | None, old_q: np.ndarray | None
    ) -> tuple[np.ndarray, Network, np.ndarray, JointSeepage]:
        """Seepage on every facet not joined to the cavity; fluid carried over by facet.

        Returns the local facets in the network, the network, their positions
        in it and its seepage.
        """
        solid = self.solid
        mine = self.cracks & solid.owned
        crack_vertices = gather_rows(solid.comm, solid.vertex_ids[mine].reshape(-1))
        boundary = np.union1d(self.walls, crack_vertices)
        facets = np.flatnonzero(~self.cracks)
        net = joint_network(solid, boundary, facets)
        # the joints not met before hold what the zone's joints started with
        wet = self.pumping.joint_pressure
        q = np.full(net.size, -self.kw if wet is None else wet)
        if old is not None and old_q is not None:
            j = old.positions(net.keys)
            met = j >= 0
            q[met] = old_q[j[met]]
        sat = np.clip(np.where(q < 0.0, 1.0 + q / self.kw, 1.0), 0.0, 1.0)
        positions = network_positions(solid, net, facets)
        hydraulic, void = network_apertures(solid, net, facets, self.aperture, positions)
        seep = JointSeepage(
            net,
            hydraulic,
            self.fluid,
            pressure=np.maximum(q, 0.0),
            filling="saturation",
            saturation=sat,
            void_aperture=void,
        )
        return facets, net, positions, seep

    def joint_content(self) -> float:
        """Fluid in the seepage network (m^3 at zero pressure)."""
        return float(self.seep.content.sum())

    def fields(self) -> tuple[np.ndarray, np.ndarray]:
        """Fluid pressure (Pa) and saturation per local facet; the joined cracks at the cavity's."""
        sat = self.per_facet(self.seep.saturation)
        sat[self.cracks] = 1.0
        pj = self.per_facet(self.seep.pressure)
        pj[self.cracks] = self.p
        return pj, sat

    def per_facet(self, values: np.ndarray) -> np.ndarray:
        """Network values on the solid's local facets (0 on the cracks joined to the cavity)."""
        out = np.zeros(self.solid.num_facets)
        out[self.facets] = values[self.positions]
        return out

    # ------------------------------------------------------------- solid

    def loads(self, p: float, pj: np.ndarray, in_situ: float = 1.0) -> Loads:
        """Cavity and joined cracks at ``p``; the network's pressures ``pj`` elsewhere."""
        return cavity_fluid_loads(
            self.solid, self.cavity, p, self.cracks, self.per_facet(pj), in_situ
        )

    def unit_loads(self) -> Loads:
        """Return a unit pressure in the cavity and its joined cracks but the shut ones.

        Shut cracks (:attr:`shut`) hold no fluid, so their faces' motion is not
        part of the cavity's volume: the load conjugate to that volume leaves
        them out (:meth:`_linearise`).
        """
        return Loads(
            cavity={name: 1.0 for name in self.cavity},
            crack_pressure=(self.cracks & ~self.shut).astype(float),
            in_situ_factor=0.0,
        )

    def _wall(self, which: int) -> float:
        local = dolfinx.fem.assemble_scalar(self._wall_forms[which])
        return float(self.solid.comm.allreduce(local, op=MPI.SUM))

    def _crack_mask(self) -> np.ndarray:
        solid = self.solid
        return self.cracks & solid.owned & (solid.contact == OPEN)

    def _volume(self, loads: Loads) -> float:
        """Cavity volume at the solved state (m^3; per metre in 2D) (collective).

        Keeps the part of it in the open cracks joined to the cavity in
        :attr:`crack_volume`.  Sets :attr:`shut`: the open joined cracks (owned:
        a facet's owner assembles its load) whose faces are pressed together;
        their physical opening is clipped at 0, so their volume does not follow
        the loads until they part.
        """
        solid = self.solid
        mask = self._crack_mask()
        opening = solid.snapshot(loads).opening if mask.any() else np.zeros(solid.num_facets)
        self.shut = mask & (opening <= 0.0)
        self._friction_ref = solid.friction_traction.copy()
        cracks = float(np.sum(solid.areas[mask] * opening[mask]))
        self.crack_volume = float(solid.comm.allreduce(cracks, op=MPI.SUM))
        return self.v_mesh + self._wall(0) - self.wall_ref + self.crack_volume

    def _linearise(self, solved: bool = False) -> None:
        """Slope and coupling of the cavity's volume at the solved state (collective).

        Solves for :meth:`unit_loads` into ``u_unit`` with the current
        factorisation (``solved``: it is there already); the volume of
        :meth:`_volume` (and :attr:`shut`) must be of the solved state.
        """
        solid = self.solid
        if not solved:
            a_form, ksp = solid.factorize()  # the one of the last solve: no new factorisation
            solid.solve_load(ksp, a_form, solid.load_form(self.unit_loads()), solid.u_unit)
        self._unit_jumps = solid.jumps(solid.u_unit)  # one evaluation for all three
        opening = -np.einsum("fi,fi->f", self._unit_jumps, solid.normals)  # facet_openings
        self.slope = self._slope(opening)
        self.coupling = self._coupling(opening)
        self.volume_joints = self.seep.pressure  # the joints' pressures of self.volume

    def _friction_shift(self) -> float:
        """Return the cavity volume's change by the friction set since it was measured (collective).

        Sliding faces carry a friction set from their normal traction at each
        contact check (:meth:`InterfaceStates.switch_contacts`), a load that
        changes without a state change.  By reciprocity its effect on the
        volume is the friction's work on the unit solution's jumps (the load
        acts at the midpoint, where the jumps are taken).
        """
        solid = self.solid
        change = solid.friction_traction - self._friction_ref
        work = np.einsum("fi,fi->f", change, self._unit_jumps)
        local = float(np.sum(solid.areas[solid.owned] * work[solid.owned]))
        return float(solid.comm.allreduce(local, op=MPI.SUM))

    def _slope(self, opening: np.ndarray) -> float:
        """``dV/dP`` of the cavity from the unit solution in ``u_unit`` (collective).

        ``opening``: the unit solution's :func:`facet_openings`.  The pressure
        loads every open joined crack, shut or not, while the volume counts the
        cracks that are not shut; ``u_unit`` is the response to the load
        conjugate to that volume, so by reciprocity the slope is the work of the
        whole unit pressure on it, plus the fluid's own overlap ``1 / kn`` of the
        cracks not shut (:meth:`CDEMSolid.snapshot`).
        """
        solid = self.solid
        mask = self._crack_mask()
        w = opening + np.where(self.shut, 0.0, 1.0 / solid.kn)
        cracks = float(np.sum(solid.areas[mask] * w[mask]))
        # the cavity's wall term of the same work: the wall's volume change under u_unit
        return self._wall(1) + float(solid.comm.allreduce(cracks, op=MPI.SUM))

    def _coupling(self, opening: np.ndarray) -> np.ndarray:
        """How the cavity's volume moves with each network facet's pressure (m^3/Pa).

        By reciprocity (the stiffness is symmetric) ``dV / dp_j`` of a facet is
        the change of its fluid volume, area times opening, under a unit cavity
        pressure (``opening``: the :func:`facet_openings` of ``u_unit``): the
        joint pressure's load is the work-conjugate of that volume as the
        cavity pressure's is of ``V``.  Zero on the facets the joint pressure
        does not load (closed cracks).
        """
        g = cavity_joint_coupling(self.solid, opening)
        return network_values(self.solid, self.net, self.facets, self.positions, g)

    def resolve(self, loads: Loads, t: float) -> None:
        """Solve at ``loads`` after a state change at time ``t``: new volume, slope and coupling.

        The unit load goes with the load in one solve, on the shut cracks as
        they were; only if the load's solution shuts or parts one is it solved
        again.  Raises :class:`ValidityLimit` as every solve does: a block the
        change cut loose must stop the run before its volume enters a balance
        (No. 2's seepage rung at the default mesh read 3.8e-3 m^3 of cracks,
        thirty times its cavity, and stopped as "the cavity runs dry").
        """
        shut = self.shut
        self.solid.solve(loads, self.unit_loads())
        check_small_displacement(self.solid, t)
        self.volume = self._volume(loads)
        moved = not np.array_equal(shut, self.shut)
        self._linearise(solved=not self.solid.comm.allreduce(moved, op=MPI.LOR))

    # ------------------------------------------------------------- balance

    def balance(self, dt: float, target: float, saved: np.ndarray, shift: float = 0.0) -> float:
        """Cavity pressure that holds ``target`` fluid; steps the seepage there.

        One Newton on the joints and the cavity pressure together
        (:meth:`JointSeepage.step_pumped`), from the joints of the last balance
        from the same start; should it fail, the bracketed secant on trial
        seepage steps (:meth:`balance_by_secant`).  ``shift``: the volume's
        change by the friction set since it was measured (:meth:`_friction_shift`).
        """
        last = self._last_balance
        guess = last[1] if last is not None and last[0] is saved else None
        self.seep.restore(saved)
        storage = CavityStorage(
            self.volume + shift, self.slope, self.p, self.kw, self.coupling, self.volume_joints
        )
        try:
            p = self.seep.step_pumped(dt, storage, target, guess)
            self._last_balance = (saved, self.seep.save())
            return p
        except CavityDry as dry:
            raise _Dry(str(dry)) from None
        except RuntimeError:
            self.secant_balances += 1
            return self.balance_by_secant(dt, target, saved, shift)

    def balance_by_secant(
        self, dt: float, target: float, saved: np.ndarray, shift: float = 0.0
    ) -> float:
        """Do :meth:`balance` by a secant on the cavity pressure, a seepage step per trial."""
        v0, p0, slope, kw, seep = self.volume + shift, self.p, self.slope, self.kw, self.seep
        storage = CavityStorage(v0, slope, p0, kw, self.coupling, self.volume_joints)

        def residual(p: float) -> float:
            seep.restore(saved)
            seep.step(dt, p)
            return storage.held(p, seep.pressure) + float(seep.content.sum()) - target

        tol = _VOLUME_TOLERANCE * self.pumping.rate * dt
        stiffness = max(slope + v0 / kw, 1e-300)
        r0 = residual(p0)
        if abs(r0) <= tol:
            return p0
        if r0 < 0.0:
            lo, r_lo = p0, r0
            hi = p0 - 1.01 * r0 / stiffness
            r_hi = residual(hi)
            while r_hi < 0.0:  # the joints take more than the cavity's storage says
                lo, r_lo, hi = hi, r_hi, hi + 2.0 * (hi - p0)
                r_hi = residual(hi)
        else:
            hi, r_hi = p0, r0
            lo = max(p0 - 1.01 * r0 / stiffness, 0.0)
            r_lo = residual(lo)
            while r_lo > 0.0 and lo > 0.0:
                hi, r_hi, lo = lo, r_lo, max(lo - 2.0 * (p0 - lo), 0.0)
                r_lo = residual(lo)
            if r_lo > 0.0:
                raise _Dry(f"the cavity runs dry (holds {r_lo:.3g} m^3 more than pumped at 0 Pa)")
        p, _, converged = illinois_root(residual, (lo, r_lo), (hi, r_hi), tol, 1e-13, 80)
        if converged:
            return p
        raise _Dry(f"the cavity balance did not converge (dt {dt:.3g} s); use more steps")

    # ------------------------------------------------------------- stepping

    def save_step(self) -> _StepStart:
        """Return what a step changes, as it is at the step's start (:meth:`restore_step`)."""
        solid = self.solid
        return _StepStart(
            states=solid.states.copy(),
            events=len(solid.events),
            u=solid.u.x.array.copy(),
            u_unit=solid.u_unit.x.array.copy(),
            cracks=self.cracks.copy(),
            net=self.net,
            q=self.seep.save(),
            scalars={name: getattr(self, name) for name in _STEP_SCALARS},
            arrays={name: getattr(self, name).copy() for name in _STEP_ARRAYS},
        )

    def restore_step(self, start: _StepStart) -> None:
        """Go back to ``start``: interface states, displacements, cracks and the joints' fluid.

        A network rebuilt in the step (new cracks joined the cavity) is built
        again for the start's cracks, with the start's fluid.  The solid
        refactorises for the restored states at its next solve.
        """
        solid = self.solid
        solid.states.restore(start.states)
        del solid.events[start.events :]
        solid.u.x.array[:] = start.u
        solid.u_unit.x.array[:] = start.u_unit
        self.cracks = start.cracks.copy()  # a start may be restored more than once
        if self.net is not start.net:
            self.seep.destroy()
            self.facets, self.net, self.positions, self.seep = self._network(start.net, start.q)
        else:
            self.seep.restore(start.q)
        for name, value in start.scalars.items():
            setattr(self, name, value)
        for name, value in start.arrays.items():
            setattr(self, name, value.copy())
        self._last_balance = None

    def step(
        self, t: float, dt: float, max_iterations: int, start: _StepStart | None = None
    ) -> tuple[float, int, tuple | None, float]:
        """Advance from ``t`` by ``dt`` or less.

        Returns the step taken, the facets broken, the first break ``(cavity
        pressure, mode, location, ratio)`` of the most over-stressed facet when the
        step's first facets break, with every local facet's failure ratio then (or
        None), and the highest cavity pressure of
        the step's states (the one at which the first facets break, before the
        pressure drops).  ``max_iterations`` bounds the passes between two
        breaks: a cascade (breakdown, one facet per pass) may take any number,
        since each break is for good, but contacts that keep switching or a
        balance that keeps moving without a break stop the run.  ``start``: the
        step's start from :meth:`save_step`, if taken already (its displacements and
        joints' state serve the step's landings too).
        """
        solid = self.solid
        target = self.m0 + self.pumping.rate * (t + dt)
        start = self.save_step() if start is None else start
        start_net, start_q = self.net, start.q
        start_p, start_pj = self.p, self.seep.pressure
        start_volume, start_slope, start_joints = self.volume, self.slope, self.volume_joints
        start_friction = self._friction_ref
        start_loads = self.loads(start_p, start_pj)
        u_start = start.u
        saved, landings, broken, rounds, first, top = start_q, 0, 0, 0, None, -math.inf
        passes = 0  # since the last break
        stalled, last_gap = 0, math.inf  # re-balances in a row that did not halve the gap
        while passes < max_iterations:
            passes += 1
            shift = self._friction_shift()
            p = self.balance(dt, target, saved, shift)
            pj = self.seep.pressure
            loads = self.loads(p, pj)
            predicted = self.volume + shift + self.slope * (p - self.p)
            predicted += float(self.coupling @ (pj - self.volume_joints))
            solid.solve(loads)
            check_small_displacement(solid, t + dt)
            self.volume, self.p, self.volume_joints = self._volume(loads), p, pj
            gap = abs(self.volume - predicted) * (1.0 + p / self.kw)
            stalled = stalled + 1 if gap > 0.5 * last_gap else 0
            last_gap = gap
            rate = self.pumping.rate
            if not balanced(gap, stalled, self.volume, rate * dt, rate * self.pumping.dt):
                # the joints changed which of them hold pressure, or contacts moved:
                # balance again on the measured volume
                self.rebalances += 1
                continue
            stalled, last_gap = 0, math.inf
            land = self.pumping.land_on_breaks and broken == 0 and rounds == 0
            tol = self.pumping.landing_tolerance
            if land and tol > 0.0:  # unlanded, a break is off by |p - start_p| at most
                land = abs(p - start_p) > tol * max(p, start_p)
            if land and landings < _MAX_LANDINGS:
                s = self._crossing(start_loads, loads, u_start)
                # land just past the crossing (a landed step finds it at 1 / (1 + _PAST))
                if _MIN_FRACTION < s and s * (1.0 + _PAST) < 1.0:
                    dt, landings = min(s * (1.0 + _PAST), 1.0) * dt, landings + 1
                    target = self.m0 + self.pumping.rate * (t + dt)
                    self.seep.restore(saved)
                    self.p, self.volume, self.slope = start_p, start_volume, start_slope
                    self.volume_joints, self._friction_ref = start_joints, start_friction
                    solid.u.x.array[:] = u_start
                    continue
            top = max(top, p)
            if switch_contacts(solid, loads, rounds >= 1, self.hysteresis):
                rounds += 1
                self.resolve(loads, t + dt)
                continue
            ratio, mode = solid.overstress(loads)
            chosen = facets_to_break(solid, ratio, None)
            count = int(solid.comm.allreduce(len(chosen), op=MPI.SUM))
            if count == 0:
                return dt, broken, first, top
            if first is None:  # with every facet's ratio then: how near the others came
                first = (p, *most_overstressed(solid, ratio, mode), ratio.copy())
            solid.break_facets(chosen, mode[chosen], t + dt)
            broken, rounds, passes = broken + count, 0, 0
            self.release_debris(t + dt)
            cracks = self._joined_cracks()
            if solid.comm.allreduce(not np.array_equal(cracks, self.cracks), op=MPI.LOR):
                self.cracks = cracks
                # the joints' fluid at the step's start, on the network without the new cracks
                old = self.seep
                self.facets, self.net, self.positions, self.seep = self._network(start_net, start_q)
                old.destroy()
                saved = self.seep.save()
                start_net, start_q = self.net, saved
            self.resolve(self.loads(p, self.seep.pressure), t + dt)
        raise _Unsettled(
            f"interface states did not settle in {max_iterations} iterations without a break "
            f"at t = {t + dt:.6g} s ({broken} facets broke in the step)"
        )

    def _wet_share(self) -> float:
        """Share of the network's joints holding pressure (the same on every rank)."""
        pj = self.seep.pressure
        return float(np.mean(pj > 0.0)) if pj.size else 0.0

    def _crossing(self, start: Loads, end: Loads, u_start: np.ndarray) -> float:
        """Fraction of the step at which an intact facet first fails (inf: none)."""
        solid = self.solid
        u_end = solid.u.x.array.copy()
        solid.u_unit.x.array[:] = u_end - u_start
        solid.u.x.array[:] = u_start
        diff = Loads(
            cavity={k: end.cavity[k] - start.cavity[k] for k in self.cavity},
            crack_pressure=np.asarray(end.crack_pressure) - np.asarray(start.crack_pressure),
            joint_pressure=np.asarray(end.joint_pressure) - np.asarray(start.joint_pressure),
            in_situ_factor=0.0,
        )
        crit = critical_factor(solid, start, diff, 0.0, 1.0, 8)
        solid.u.x.array[:] = u_end
        solid.u_unit.x.array[:] = 0.0  # not the unit solution any more: slope kept from before
        return float(solid.comm.allreduce(float(crit.min()) if crit.size else math.inf, MPI.MIN))

    def run(
        self,
        initial_failures: int,
        progress: Callable[[str], None] | None,
        max_iterations: int,
        frames: Frames | None = None,
        at_first_break: Callable[[float, np.ndarray], None] | None = None,
        records: Records | None = None,
        course: Course | None = None,
        checkpoint: Checkpoint | None = None,
    ) -> PumpingResult:
        """Pump for the whole duration, or on from ``course`` (a resume); return the result.

        ``checkpoint`` is offered the run's state after every step (:meth:`checkpoint`).
        """
        solid, pumping = self.solid, self.pumping
        c = course if course is not None else Course(peak=self.p, curve_t=[0.0], curve_p=[self.p])
        stopped, limit = None, False
        cadence = Cadence(pumping.steps, solid.comm)
        if frames is not None:
            frames(c.t, *self.fields())
        stepper = StepController(
            dt=pumping.dt, dt_min=pumping.dt, dt_max=max(pumping.max_dt or 0.0, pumping.dt)
        )
        if c.dt is not None:
            stepper.retry_with(c.dt)
        wet = self._wet_share()
        started = time.perf_counter()
        pace = TimeLeft(pumping.duration, c.t)
        while c.t < pumping.duration * (1.0 - 1e-12):
            if pumping.until_first_break and c.first is not None:  # a resumed run's
                break
            stepper.limit(pumping.duration - c.t)
            tried, p_before, wet_before = stepper.dt, self.p, wet
            before = (solid.solves, self.rebalances, *self._factorisations(), time.perf_counter())
            start = self.save_step()
            try:
                dt, broken, worst, top = self.step(c.t, tried, max_iterations, start)
            except _Unsettled as stop:
                # states or a balance that did not settle may settle over a shorter step
                if tried > pumping.dt / 2**_SETTLE_HALVINGS * (1.0 + 1e-9):
                    self.restore_step(start)
                    stepper.retry_with(tried / 2.0)
                    self.unsettled_retries += 1
                    if progress is not None:
                        progress(f"  t {c.t:.4g} s: {stop}; the step again at {tried / 2.0:.3g} s")
                    continue
                stopped = (
                    f"{stop}, with steps halved down to {tried:.3g} s (at most "
                    f"1/{2**_SETTLE_HALVINGS} of solver.time_step, {pumping.dt:.3g} s)"
                )
                break
            except _Dry as stop:
                stopped = str(stop)
                break
            except ValidityLimit as stop:
                stopped, limit = str(stop), True
                break
            t = c.t = c.t + dt
            c.steps += 1
            pace.add(t, time.perf_counter() - started)
            change, last_rate = self.p - p_before, c.rate
            c.rate, wet = change / dt, self._wet_share()
            if broken or dt < tried:
                stepper.retry_with(pumping.dt)  # breaks come in cascades: the base step again
                c.rate = None
            elif last_rate is not None:
                off = abs(change - last_rate * dt)  # from the last step's rate carried on
                linear = off <= _GROWTH_LINEARITY * max(abs(change), 1e-3 * max(p_before, 1e6))
                if linear and abs(wet - wet_before) <= _GROWTH_WET:
                    stepper.accepted(dt, changed=False, newton_iterations=0)
                else:
                    stepper.retry_with(max(dt / stepper.growth, pumping.dt))
            c.dt = stepper.dt
            events = self._factorisations()
            c.costs.append(
                (t, dt, broken, solid.solves - before[0], events[0] - before[2],
                 events[1] - before[3], self.rebalances - before[1], events[2] - before[4],
                 events[3] - before[5], time.perf_counter() - before[6])
            )  # fmt: skip
            if frames is not None:
                frames(t, *self.fields())
            if worst is not None and c.first is None:
                c.first = (worst[0], t, worst[1], worst[2])
                if at_first_break is not None:
                    at_first_break(t, worst[3])
            held = self.volume * (1.0 + self.p / self.kw) + self.joint_content()
            error = abs(held - self.m0 - pumping.rate * t) / (pumping.rate * t)
            self.worst = max(self.worst, error)
            counts = solid.broken_counts()
            crack = self.crack_volume
            c.history.append(
                (t, self.p, self.joint_content(), crack, counts["tensile"], counts["shear"], wet)
            )
            if records is not None:
                records(c.history[-1], c.costs[-1])
            if top > c.peak:
                c.peak, c.peak_time = top, t
            if top > self.p:
                c.curve_t.append(t)
                c.curve_p.append(top)
            c.curve_t.append(t)
            c.curve_p.append(self.p)
            if checkpoint is not None:
                checkpoint(lambda: self.checkpoint(c, initial_failures))
            if pumping.until_first_break and c.first is not None:
                if progress is not None:
                    progress(f"  t {t:.4g} s: the first break; the run ends here (until)")
                break
            if progress is not None:
                for news in self.debris_news:
                    progress(news)
            self.debris_news.clear()
            if progress is not None and cadence.due(c.steps, bool(broken)):
                progress(
                    f"  t {t:.4g} s, cavity {self.p / 1e6:.4g} MPa, {counts['tensile']} tensile "
                    f"{counts['shear']} shear, joints holding pressure {wet:.1%}, "
                    f"cracks joined to the cavity {crack:.3g} m^3, {pace.words()}"
                )
        counts = solid.broken_counts()
        pj, sat = self.fields()
        first = c.first
        # a fall before the first break is the joints' intake, not a breakdown; a run
        # ended on its first break seeks none
        ended = pumping.until_first_break and first is not None
        breakdown = detect_breakdown(
            c.curve_t, c.curve_p, not_before=math.inf if first is None or ended else first[1]
        )
        return PumpingResult(
            first_pressure=None if first is None else first[0],
            first_time=None if first is None else first[1],
            first_mode=None if first is None else int(first[2]),
            first_location=None if first is None else first[3],
            breakdown=None if breakdown is None else breakdown.pressure,
            breakdown_time=None if breakdown is None else breakdown.time,
            breakdown_drop=None if breakdown is None else breakdown.drop,
            peak_pressure=c.peak,
            peak_time=c.peak_time,
            peak_cut_off=breakdown is None and c.peak_time > 0.0 and not ended,
            initial_failures=initial_failures,
            steps=c.steps,
            history=c.history,
            max_mass_error=self.worst,
            joint_pressure=pj,
            saturation=sat,
            tensile=counts["tensile"],
            shear=counts["shear"],
            stopped=stopped,
            validity_limit=limit,
            secant_balances=self.secant_balances,
            unsettled_retries=self.unsettled_retries,
            debris_cells=self.debris_cells,
            rebalances=self.rebalances,
            solid_solves=solid.solves - self.solves_before,
            factorisations=self._factorisations()[0] - self.factorisations_before[0],
            low_rank_events=self._factorisations()[1] - self.factorisations_before[1],
            costs=c.costs,
            ended_on_first_break=ended,
        )

    # ------------------------------------------------------------- resume

    def checkpoint(self, course: Course, initial_failures: int) -> dict[str, Any]:
        """Return the run's state after a step, JSON-ready and the same on every rank (collective).

        The interface states (keyed by global vertex ids, as every checkpoint's),
        the joints' fluid by network facet, the cavity's pressure and counters,
        and ``course`` but its history and cost rows (those are in the run's
        files).  :meth:`resume` continues from it on any number of ranks.
        """
        solid, c = self.solid, course
        first = None
        if c.first is not None:
            p, t, mode, location = c.first
            where = [float(x) for x in location]
            first = {"pressure": p, "time": t, "mode": int(mode), "location": where}
        counts = self._factorisations()
        return {
            "t": c.t,
            "steps": c.steps,
            "dt": c.dt,
            "rate": c.rate,
            "first": first,
            "peak": c.peak,
            "peak_time": c.peak_time,
            "curve_t": list(c.curve_t),
            "curve_p": list(c.curve_p),
            "initial_failures": initial_failures,
            "cavity": {
                "p": self.p,
                "m0": self.m0,
                "worst": self.worst,
                "debris_cells": self.debris_cells,
                "rebalances": self.rebalances,
                "secant_balances": self.secant_balances,
                "unsettled_retries": self.unsettled_retries,
                "solid_solves": solid.solves - self.solves_before,
                "factorisations": counts[0] - self.factorisations_before[0],
                "low_rank_events": counts[1] - self.factorisations_before[1],
            },
            "interfaces": interface_rows(solid),
            "joints": {"keys": self.net.keys.reshape(-1).tolist(), "q": self.seep.save().tolist()},
        }

    def resume(self, data: Mapping[str, Any]) -> Course:
        """Take the state of a :meth:`checkpoint`; return its course, without rows (collective).

        Raises ValueError when the checkpoint's joints are not those its
        interface states give on this mesh.  The solid is solved at the
        restored state (a new factorisation); the counters go on from the
        checkpoint's.
        """
        solid, cav = self.solid, data["cavity"]
        t = float(data["t"])
        restore_interfaces(solid, data["interfaces"])
        self.release_debris(t)  # the cells a supporting wall holds are found again
        self.debris_news.clear()
        self.debris_cells = int(cav["debris_cells"])
        self.cracks = self._joined_cracks()
        self.seep.destroy()
        self.facets, self.net, self.positions, self.seep = self._network(None, None)
        keys = np.asarray(data["joints"]["keys"], dtype=np.int64)
        keys = keys.reshape(-1, self.net.keys.shape[1])
        where = self.net.positions(keys) if keys.size and self.net.size else np.zeros(0, int)
        if keys.shape[0] != self.net.size or np.any(where < 0):
            raise ValueError(
                f"the checkpoint holds {keys.shape[0]} joints, not the {self.net.size} of "
                "its interface states on this mesh"
            )
        q = np.empty(self.net.size)
        q[where] = np.asarray(data["joints"]["q"], dtype=float)
        self.seep.restore(q)
        self.p, self.m0, self.worst = float(cav["p"]), float(cav["m0"]), float(cav["worst"])
        self.rebalances = int(cav["rebalances"])
        self.secant_balances = int(cav["secant_balances"])
        self.unsettled_retries = int(cav["unsettled_retries"])
        self._last_balance = None
        self.resolve(self.loads(self.p, self.seep.pressure), t)
        self.solves_before = solid.solves - int(cav["solid_solves"])
        counts = self._factorisations()
        self.factorisations_before = (
            counts[0] - int(cav["factorisations"]),
            counts[1] - int(cav["low_rank_events"]),
            counts[2],
            counts[3],
        )
        first = data["first"]
        return Course(
            t=t,
            steps=int(data["steps"]),
            dt=None if data["dt"] is None else float(data["dt"]),
            rate=None if data["rate"] is None else float(data["rate"]),
            first=None
            if first is None
            else (
                float(first["pressure"]),
                float(first["time"]),
                int(first["mode"]),
                np.asarray(first["location"], dtype=float),
            ),
            peak=float(data["peak"]),
            peak_time=float(data["peak_time"]),
            curve_t=[float(x) for x in data["curve_t"]],
            curve_p=[float(x) for x in data["curve_p"]],
        )


#: the pumped cavity's values a step changes, restored with it (:meth:`_PumpedCavity.save_step`)
_STEP_SCALARS = ("p", "volume", "slope", "crack_volume", "debris_cells")
_STEP_ARRAYS = ("volume_joints", "coupling", "shut", "_friction_ref", "_unit_jumps")
#: how many times an unsettled step is halved below the scene's step before the run stops
_SETTLE_HALVINGS = 4


@dataclass(frozen=True)
class _StepStart:
    """A pumped step's start (:meth:`_PumpedCavity.save_step`)."""

    states: InterfaceStates
    events: int
    u: np.ndarray
    u_unit: np.ndarray
    cracks: np.ndarray
    net: Network
    q: np.ndarray
    scalars: dict[str, Any]
    arrays: dict[str, np.ndarray]


class _Dry(RuntimeError):
    """A pumped step that cannot go on (the message says why)."""


class _Unsettled(_Dry):
    """A pumped step whose interface states kept changing with no break (shorter may settle)."""


__all__ = [
    "PumpingResult",
    "balanced",
    "cavity_joint_coupling",
    "facet_openings",
    "pump_with_seepage",
]
