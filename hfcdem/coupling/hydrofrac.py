"""Fluid-driven fracturing: the CDEM solid coupled to flow in its fractures and cavity.

Implicit Euler steps of the group pressures: the solid, linear between
interface events, is condensed onto the pressure groups
(:mod:`~hfcdem.coupling.groups`, :mod:`~hfcdem.coupling.condense`), so void
volumes are linear in the pressures; each wet group balances its fluid content
``M = V (1 + p / Kw)`` against cubic-law fluxes, injection and leak-off
(:mod:`~hfcdem.flow.balance`, solved by SNES in :mod:`~hfcdem.flow.newton`).
Filling ``"saturation"`` (seed eqs. (14)-(19)) lets dry facets fill through
``ks = S^2 (3 - 2S)``; ``"no_lag"`` wets every facet joined to the cavity at once;
fidelity ``"uniform"`` makes the cavity and its joined facets one group.  After
each converged attempt contacts switch and facets break
(:mod:`~hfcdem.coupling.events`), the operator is rebuilt and the step repeated
until nothing changes; :mod:`~hfcdem.coupling.stepping` sizes the steps.  The
fluid per facet lives in :class:`~hfcdem.coupling.fluidstate.FluidState`; every
step records mass balance: injected = fluid in cavity + fractures + leaked.

Size: about 760 lines, over the package's 600.  What is left is the step loop
and the network-order fluid bookkeeping (fill, guess, solve, leak, accept); the
seepage issue replaces that bookkeeping with a sparse flow system on every
joint, so it is not split further before then.
"""

from __future__ import annotations

import collections
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from mpi4py import MPI

from hfcdem.config.materials import Fluid, Injection
from hfcdem.coupling import fields
from hfcdem.coupling.checkpoint import SCALARS, checkpoint_data, read_checkpoint
from hfcdem.coupling.condense import (
    CondensedSolid,
    KeptCondensations,
    cavity_load_form,
    cavity_vertices,
    mean_point,
    mesh_cavity_volume,
)
from hfcdem.coupling.events import (
    check_small_displacement,
    facets_to_break,
    most_overstressed,
    release_debris,
    switch_contacts,
)
from hfcdem.coupling.fluidstate import FluidState
from hfcdem.coupling.groups import (
    condense_network,
    group_count,
    local_network,
    near_fluid,
    network_volumes,
    pressure_groups,
    wall_joints,
)
from hfcdem.coupling.records import SimulationStopped, StepRecord
from hfcdem.coupling.settings import FlowSettings
from hfcdem.coupling.stepping import StepController
from hfcdem.flow.balance import GroupBalance, VoidVolumes, gravity_drive, relative_permeability
from hfcdem.flow.newton import solve_groups
from hfcdem.io.files import write_csv
from hfcdem.io.progress import TimeLeft
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads
from hfcdem.solid.fragments import Fragments
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import InterfaceStates
from hfcdem.solvers import ValidityLimit

# rounds of contact switches in one step's state loop that may open faces (see _switch_contacts)
_CONTACT_ROUNDS = 1
# condensations of at most this many pressure groups are kept for states met again (each
# group a displacement field: at No. 2's default mesh 3.2 MB)
_KEPT_GROUPS = 8


@dataclass(frozen=True, eq=False)
class _Attempt:
    """What a rejected step attempt must leave as it found it."""

    states: InterfaceStates
    events: int
    fluid: FluidState
    first_break_time: float | None
    first_break_pressure: float | None
    rebuilds: int


@dataclass
class HydraulicFracture:
    """Inject into a :class:`CDEMSolid` and follow breakdown and fracture growth.

    It composes the condensed solid (:mod:`~hfcdem.coupling.condense`), the mass
    balance of the pressure groups (:mod:`~hfcdem.flow.balance`, solved by
    :mod:`~hfcdem.flow.newton`) and the step controller
    (:mod:`~hfcdem.coupling.stepping`); it owns the network, the fluid state per
    facet and the loop over interface states within a step.
    """

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
        self.stepper = StepController(
            dt=s.dt_initial,
            dt_min=s.dt_min,
            dt_max=s.dt_max,
            growth=s.dt_growth,
            break_tolerance=s.break_tolerance,
            max_pressure_change=s.max_pressure_change,
        )
        self.injected = 0.0
        self.leaked = 0.0
        self.rebuilds = 0
        self.rebuild_seconds = 0.0
        # what caused each rebuild (start, contact, break, band, fill, retry, resume)
        self.rebuild_causes: collections.Counter[str] = collections.Counter()
        self.first_break_time: float | None = None
        # the cavity pressure of the state in which the first facet broke: the first
        # crack came above the last accepted step's and at most at this one
        self.first_break_pressure: float | None = None
        # when the first facet reached its strength (the state a step landed on, else
        # the break's): each local facet's failure ratio (how near the others came),
        # the mode and midpoint of the one that reached it; not kept by a checkpoint
        self.first_break_ratio: np.ndarray | None = None
        self.first_break_point: np.ndarray | None = None
        self.first_break_mode = 0
        self._landed: tuple[float, np.ndarray, np.ndarray] | None = None
        self.initial_failures = 0
        self._worst = math.inf  # worst failure ratio of the last state the step loop checked
        self.wall_start = time.perf_counter()
        for name in (*s.cavity, *s.supports):
            solid.tmesh.facet_tag(name)  # clear error for unknown groups
        self._cavity_vertices = cavity_vertices(solid, s.cavity, s.injection_point)
        self._cavity_point = mean_point(solid.mesh, self._cavity_vertices)
        self.cavity_volume = (
            s.cavity_volume if s.cavity_volume is not None else mesh_cavity_volume(solid, s.cavity)
        ) + s.extra_volume
        # the fluid of every facet, by key (survives network rebuilds); the network's
        # arrays content, wet_since, pressure are its working copy between rebuilds
        self.facet_fluid = FluidState()
        self.p_cavity = s.initial_pressure
        self._wall_joints = wall_joints(solid, s, self._cavity_vertices)
        self._cav_form = cavity_load_form(solid, s.cavity, self._intact_wall_joints())
        self._cavity_reference: float | None = None
        self._condensations = KeptCondensations(self.comm)
        # reduced solid: the springs at the cavity walls, where stress concentrates, are
        # free from the start (recovered cell tractions underrate the wall's spring peaks)
        at_walls = np.isin(solid.vertex_ids, self._cavity_vertices).any(axis=1)
        solid.free_interfaces(np.asarray(at_walls, dtype=bool), rings=1)
        # blocks cut loose from the walls become debris in the cavity's fluid
        released = s.cavity and s.debris == "released"
        self.fragments = Fragments(solid, s.cavity) if released else None
        self.debris_cells = 0
        self._release_debris(0.0)
        self.rebuild()
        self._initialise_fluid()

    @property
    def dt(self) -> float:
        """The next time step to attempt (s)."""
        return self.stepper.dt

    @dt.setter
    def dt(self, value: float) -> None:
        self.stepper.dt = value

    @property
    def _last_ratio(self) -> float:
        # worst failure ratio of eligible facets, last accepted step (checkpointed)
        return self.stepper.last_ratio

    @_last_ratio.setter
    def _last_ratio(self, value: float) -> None:
        self.stepper.last_ratio = value

    # ------------------------------------------------------------ geometry

    @property
    def cavity_vertices(self) -> np.ndarray:
        """Global ids of the mesh vertices on the cavity walls."""
        return self._cavity_vertices

    @property
    def wall_joints(self) -> np.ndarray:
        """Per interface facet: True where it holds the cavity's fluid (a wet wall joint)."""
        return self._wall_joints

    def _intact_wall_joints(self) -> np.ndarray:
        return self._wall_joints & (self.solid.state == FacetState.INTACT)

    # ------------------------------------------------------------- network

    @property
    def reused_condensations(self) -> int:
        """Rebuilds since the start or resume that met states condensed a moment before."""
        return self._condensations.reused

    def _rebuild_network(self) -> None:
        self.network = network = local_network(self.solid, self._cavity_vertices)
        self.net, self.view = network.net, network.view
        self.is_open, self.joined = network.is_open, network.joined
        self.content, self.wet_since, self.pressure = self.facet_fluid.on(network.keys)
        # pre-existing cracks joined to the cavity start full (seed 000 pre-opens them)
        at_start = getattr(self, "op", None) is None
        if self.settings.filling == "no_lag" or self.settings.fidelity == "uniform" or at_start:
            newly = self.joined & ~np.isfinite(self.wet_since)
            self.wet_since[newly] = self.t
            self.pressure[newly] = self.p_cavity
        self.wet = np.isfinite(self.wet_since)

    def _store_state(self) -> None:
        self.facet_fluid.store(self.network.keys, self.content, self.wet_since, self.pressure)

    def _recondense(self, cause: str) -> None:
        """Record the fluid of the network and rebuild it for changed states."""
        self._store_state()
        self.rebuild(cause)

    # ------------------------------------------------------------ operator

    def rebuild(self, cause: str = "start") -> None:
        """Refactorise the solid and recondense for the current interface states.

        Runs of :meth:`step` call it at every interface event (``cause`` names it
        in :attr:`rebuild_causes`); a benchmark calls it to time one event.
        """
        t0 = time.perf_counter()
        self._rebuild_network()
        s, solid, net = self.settings, self.solid, self.net
        self.group = pressure_groups(self.wet, s.fidelity == "uniform")
        if s.permeate_joints:
            self._wall_joints = wall_joints(
                solid, s, self._cavity_vertices, self.network, self.group
            )
        self.m = group_count(self.group)
        wet_joints = self._intact_wall_joints()
        solid.free_interfaces(wet_joints)  # reduced mode: pressure on glued faces does no work
        st = solid.states
        key = self._condensations.key(
            (st.state, st.contact, st.friction_traction, st.released, wet_joints),
            (solid.band.version, solid.held_version, self.net.keys, self.group, self.is_open),
        )
        kept = self._condensations.get(key)
        if kept is None:
            base, columns = condense_network(solid, s.cavity, self.network, self.group, wet_joints)
            if s.cavity:  # the intact joints change with breaks
                self._cav_form = cavity_load_form(solid, s.cavity, wet_joints)
            track = self._cav_form is not None and not s.rigid_cavity
            volumes = network_volumes(
                solid,
                self.network,
                (base, columns),
                self.fluid.residual_aperture,
                self._cav_form if track else None,
                self.group,
            )
            kept = (base, columns, self._cav_form, volumes)
            if len(columns) <= _KEPT_GROUPS:  # many groups (viscous): too large to keep
                self._condensations.put(key, kept)
        base, columns, self._cav_form, volumes = kept
        v0, h, hc, wall, self.closure_stress = volumes
        if self._cavity_reference is None:
            # the mesh (and cavity_volume) is the cavity as it stands at the start, after
            # excavation and at the initial pressure: measure wall motion from that state
            self._cavity_reference = wall + float(hc.sum()) * s.initial_pressure
        vc0 = self.cavity_volume + wall - self._cavity_reference
        self.op = CondensedSolid(base, columns, VoidVolumes(v0, h, vc0, hc))
        drive = gravity_drive(net, self.fluid, self._cavity_point)
        self.balance = GroupBalance(
            net,
            self.fluid,
            self.op.volumes,
            self.group,
            drive,
            self.cavity_volume,
            self.injection.rate_controlled,
            # no suction where the fluid may lag (zero-lag KGD keeps its tip suction)
            lag=s.fidelity == "uniform" or s.filling == "saturation",
        )
        self.rebuilds += 1
        self.rebuild_causes[cause] += 1
        self.rebuild_seconds += time.perf_counter() - t0

    # ---------------------------------------------------------------- flow

    def _newton(
        self, dt: float, source: float, leak: np.ndarray, guess: np.ndarray
    ) -> tuple[np.ndarray, int, bool]:
        """Solve the group equations; returns pressures, iterations, converged."""
        s = self.settings
        atol = self.balance.tolerance(
            self.content, self.cavity_content, source, s.newton_tolerance, guess
        )

        def residual(p: np.ndarray, frozen: np.ndarray | None) -> np.ndarray:
            return self.balance.residual(
                p, dt, source, leak, self.content, self.cavity_content, frozen=frozen
            )

        solution = solve_groups(residual, guess, atol, s.max_newton_iterations)
        if solution.failure:
            self._newton_failure = solution.failure
        return solution.pressure, solution.iterations, solution.converged

    # ------------------------------------------------------------ stepping

    def _initialise_fluid(self) -> None:
        """Cavity (and no-lag fractures) full at the initial pressure."""
        p = np.full(self.m, self.settings.initial_pressure)
        vf, vc = self.op.volumes.at(p)
        kw = self.fluid.bulk_modulus
        self.cavity_content = float(max(float(vc), 0.0) * (1.0 + p[0] / kw))
        wet = self.group >= 0
        # a pre-existing crack the in-situ stress presses shut (its faces overlap in the
        # linear model: no contact on pre-existing cracks) holds no fluid; the fluid opens
        # it once its pressure exceeds the stress across it
        self.content[wet] = np.maximum(vf[wet], 0.0) * (1.0 + p[0] / kw)
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
        held = self.cavity_content + float(self.content[wet].sum()) + added
        p = self.op.volumes.filling_pressure(wet, held)
        return np.full(self.m, self.p_cavity if p is None else max(p, self.p_cavity))

    def _set_displacement(self, q: np.ndarray) -> Loads:
        p = self.balance.load(q)  # a lagging group (q < 0) loads its faces with nothing
        self.op.displacement(self.solid.u, p)
        pf = self.balance.facet_pressure(p)
        local = np.zeros(self.solid.num_facets)
        local[self.view.facets] = pf[self.view.positions]
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
        return near_fluid(solid, self.net, pressurised, self._cavity_vertices)

    def step(self) -> StepRecord:
        """Advance one accepted time step (cutting the step on failure)."""
        while True:
            dt = self.dt
            saved = self._save_states()
            record = self._try_step(dt)
            if isinstance(record, StepRecord):
                return record
            # a failed or shortened attempt leaves no breaks, fills or contacts behind
            self._restore_states(saved)
            if isinstance(record, float):  # land closer to the first break
                self.stepper.retry_with(record)
                continue
            if not self.stepper.halve(dt):
                self._stop_at_loose_blocks()
                raise SimulationStopped(
                    f"the coupled step failed down to dt = {dt:.3g} s "
                    f"(dt_min {self.settings.dt_min:g} s) "
                    f"at t = {self.t:.6g} s: the flow equations did not converge; "
                    "try max_breaks_per_iteration=1, a residual aperture, a smaller "
                    "dt_initial, or fidelity='uniform' "
                    f"({getattr(self, '_newton_failure', '')})"
                )

    def _stop_at_loose_blocks(self) -> None:
        """Raise :class:`ValidityLimit` if broken interfaces cut a block loose (collective).

        Called when a step fails down to ``dt_min``.  A loose block held by residual
        springs only has no static equilibrium: its faces' openings change by
        metres per pascal of pressure difference across it, so the balance of
        pressure groups that meet it has no solution the flow Newton can reach
        (condition numbers of 1e21 seen).  With uniform pressure the same state
        ends at :func:`check_small_displacement`.
        """
        fragments = self.fragments or Fragments(self.solid, self.settings.cavity)
        loose = fragments.loose_cells()
        if loose.size == 0:
            return
        _, at_walls = fragments.debris(loose)  # cells in loose blocks at the walls (global)
        hint = (
            '; solver.debris = "released" lets blocks cut loose at the cavity walls join '
            "the cavity's fluid"
            if at_walls and self.fragments is None
            else ""
        )
        raise ValidityLimit(
            f"at t = {self.t:.6g} s broken interfaces cut {loose.size} cell(s) loose from the "
            "rock: once their faces open, residual springs alone hold them, with no static "
            "equilibrium, so the fluid balance around them has no solution (the step failed "
            f"down to dt = {self.settings.dt_min:g} s){hint}; the history up to "
            f"t = {self.t:.6g} s stands"
        )

    def _save_states(self) -> _Attempt:
        solid = self.solid
        return _Attempt(
            states=solid.states.copy(),
            events=len(solid.events),
            fluid=self.facet_fluid.copy(),
            first_break_time=self.first_break_time,
            first_break_pressure=self.first_break_pressure,
            rebuilds=self.rebuilds,
        )

    def _restore_states(self, saved: _Attempt) -> None:
        solid = self.solid
        changed = self.rebuilds != saved.rebuilds
        solid.states.restore(saved.states)
        del solid.events[saved.events :]
        self.facet_fluid.restore(saved.fluid)
        self.first_break_time = saved.first_break_time
        self.first_break_pressure = saved.first_break_pressure
        if changed:
            self.rebuild("retry")

    def _try_step(self, dt: float) -> StepRecord | float | None:
        """Attempt a step of ``dt``, repeating it until the interface states settle.

        Returns the record, a shorter step to try instead, or None (failed).
        """
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
            self._report(t1, iteration)
            leak = self._leak(t1)
            p, its, ok = self._newton(dt, source, leak, self._guess(source))
            its_total += its
            last_its = its
            if not ok:
                return None
            # accuracy control: the cavity pressure may move by at most max_pressure_change
            # (relative, at least 1 MPa wide) per step, or the step is retried shorter
            if iteration == 0 and self.history:
                p_new = float(self.balance.load(p)[0])
                shorter = self.stepper.pressure_cut(dt, self.p_cavity, p_new)
                if shorter is not None:
                    return shorter
            if self._drain_and_fill(p, dt, t1):
                changed_states = True
                continue
            loads = self._set_displacement(p)
            switched = self._switch_contacts(loads, contact_iterations)
            contact_iterations += 1 if switched else 0
            if switched:
                continue
            grown = solid.grow_band(loads)
            if grown:  # reduced mode: facets near their strength get their own springs
                self._last_change = f"band grew by {grown}"
                changed_states = True
                self._recondense("band")
                continue
            load = self.balance.load(p)
            self._trial_pressure = self.balance.facet_pressure(load)
            ratio, mode = solid.overstress(loads)
            ratio = np.where(self._eligible(), ratio, 0.0)
            worst = float(self.comm.allreduce(float(ratio.max(initial=0.0)), op=MPI.MAX))
            self._worst = worst  # the last state's: the accepted one's once the loop ends
            if iteration == 0 or (self.first_break_time is None and not changed_states):
                # event location: a step that overshoots the next break is shortened; before
                # the first crack also when contacts it switched made the ratio jump past
                # it (where the first crack is; later it cost No. 2 67 % more steps for the
                # same peak to 0.1 %), not when fluid arrived or the band grew
                shorter = self.stepper.overshoot(dt, worst, switched=iteration > 0)
                if shorter is not None:
                    return shorter
                if iteration == 0 and self.stepper.landed(worst):
                    # landed on the next break: record this state (the peak before it
                    # breaks) and let the next step break it
                    if self.first_break_time is None:
                        self._landed = (t1, ratio.copy(), mode.copy())
                    break
            if self._break(ratio, mode, t1, float(load[0])):
                changed_states = True
                continue
            if self._release_debris(t1):
                changed_states = True
                self._recondense("debris")
                continue
            break
        else:
            raise SimulationStopped(
                f"interface states did not settle in {s.max_state_iterations} iterations at "
                f"t = {t1:.6g} s; use a smaller time step"
            )
        check_small_displacement(solid, t1)
        return self._accept(p, dt, t1, source, leak, (its_total, last_its), changed_states)

    def _report(self, t1: float, iteration: int) -> None:
        if self.progress is not None and iteration and iteration % 10 == 0:
            counts = self.solid.broken_counts()
            self.progress(
                f"  t {t1:.6g} s, iteration {iteration}: {counts['tensile']} tensile, "
                f"{counts['shear']} shear, {int(self.wet.sum())} wet, "
                f"{self.rebuilds} rebuilds, "
                f"last change: {getattr(self, '_last_change', '')}"
            )

    def _drain_and_fill(self, p: np.ndarray, dt: float, t1: float) -> bool:
        """Saturation filling: wet facets below zero pressure drain, full dry ones turn wet.

        Returns whether the wet set changed (the solid is then recondensed).
        """
        s = self.settings
        if not (s.filling == "saturation" and s.fidelity == "viscous"):
            return False
        drained, full = self.balance.wet_changes(p, dt, self.content, self.wet_since < t1)
        if not (drained.any() or full.any()):
            return False
        self._last_change = f"{int(drained.sum())} drained, {int(full.sum())} filled"
        self.wet_since[drained] = math.inf
        self.wet_since[full] = t1
        self.wet = np.isfinite(self.wet_since)
        self._recondense("fill")
        return True

    def _switch_contacts(self, loads: Loads, rounds: int) -> int:
        """Switch contacts (only closings after the first round); return how many switched."""
        # viscous flow without it: on a viscous borehole (mu = 0.1 Pa s) it made three
        # wall cells cut loose likelier (3 of 41 round-off paths against 0; a validity
        # limit with debris = "stay", see _stop_at_loose_blocks), and it is not measured
        # to save anything there
        s = self.settings
        hysteresis = s.contact_hysteresis and s.fidelity == "uniform"
        switched = switch_contacts(self.solid, loads, rounds >= _CONTACT_ROUNDS, hysteresis)
        if switched:
            self._last_change = f"{switched} contacts switched"
            self._recondense("contact")
        return switched

    def _release_debris(self, t1: float) -> bool:
        """Hold open the faces of blocks cut loose from the walls; return whether any were.

        Without it such a block slides out of the wall on its broken faces and
        ends the run at the validity limit (:func:`check_small_displacement`).
        """
        if self.fragments is None:
            return False
        count, cells, held = release_debris(self.solid, self.fragments, self.settings.supports)
        self.debris_cells = cells  # all of it, released before or now (a resume recounts)
        if not (count or held):
            return False
        self._last_change = f"{count} faces around debris released, {held} cells held"
        if self.progress is not None:
            self.progress(
                f"  t {t1:.4g} s: blocks cut loose from the wall are debris ({cells} cells "
                f"in all): {count} broken faces around them take the cavity pressure; "
                f"{held} cells against a supporting wall held by it"
            )
        self.debris_cells = cells
        return True

    def _break(self, ratio: np.ndarray, mode: np.ndarray, t1: float, cavity: float) -> bool:
        """Break the facets the rule picks from ``ratio``; return whether any broke.

        ``cavity``: the cavity pressure of the state ``ratio`` comes from.
        """
        chosen = facets_to_break(self.solid, ratio, self.settings.max_breaks_per_iteration)
        nbreak = self.comm.allreduce(len(chosen), op=MPI.SUM)
        if not nbreak:
            return False
        self.stepper.broke()
        self._last_change = f"{nbreak} broke"
        self.solid.break_facets(chosen, mode[chosen], t1)
        if self.first_break_time is None:
            self.first_break_time = t1
            self.first_break_pressure = cavity
            at, how = ratio, mode
            if self._landed is not None and self._landed[0] == self.t:  # the step before
                _, at, how = self._landed
                self.first_break_pressure = self.p_cavity  # it reached its strength there
            self.first_break_ratio = at.copy()
            self.first_break_mode, self.first_break_point = most_overstressed(self.solid, at, how)
        self._recondense("break")
        return True

    def _leak(self, t1: float) -> np.ndarray:
        lo = self.settings.leak_off
        if lo is None or self.net.size == 0:
            return np.zeros(self.net.size)
        vol = lo.volume(self.net.area, self.wet_since, self.t, t1)
        # a facet loses at most the fluid it holds at the start of the step: leaking more
        # (a facet just broken, or closed with no residual aperture, holds none) drives
        # its pressure to a suction that pulls its faces shut and the rock ahead apart
        return np.where(self.wet, np.minimum(vol, np.maximum(self.content, 0.0)), 0.0)

    def _accept(
        self,
        p: np.ndarray,
        dt: float,
        t1: float,
        source: float,
        leak: np.ndarray,
        iterations: tuple[int, int],
        changed: bool,
    ) -> StepRecord:
        """Take the step solved to ``p``: fluid bookkeeping, fills, the record, next dt.

        ``iterations``: Newton iterations of the whole step and of its last solve.
        """
        wet = self.group >= 0
        after = self.balance.advance(p, dt, source, leak, self.content, self.cavity_content)
        if after.cavity_content < 0.0:
            # the walls moved in by more than the cavity holds: blocks come loose from the
            # wall and travel into the tunnel, where nothing holds them (residual springs
            # only); the small-displacement solid has no answer past this state
            raise ValidityLimit(
                f"at t = {t1:.6g} s the cavity walls moved inward by more than the cavity's "
                f"volume ({after.cavity_content:.3g} m^3 left): blocks that came loose from "
                "the wall move into the cavity, beyond what the small-displacement solid "
                f"represents; the history up to t = {self.t:.6g} s stands"
            )
        vf = after.facet_volumes
        self.volume_mismatch = after.mismatch
        self.content = after.content
        self.cavity_content = after.cavity_content
        self.pressure = after.pressure
        self.p_cavity = float(self.balance.load(p)[0])
        self.injected += after.injected
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
            self.rebuild("fill")
        rec = self._record(t1, dt, vf, iterations[0])
        if not (math.isfinite(rec.injection_pressure) and np.all(np.isfinite(self.pressure))):
            raise SimulationStopped(f"non-finite pressure at t = {t1:.6g} s")
        self.history.append(rec)
        self.stepper.accepted(dt, changed, iterations[1])
        return rec

    def _record(self, t1: float, dt: float, vf: np.ndarray, its: int) -> StepRecord:
        stored_total = self.cavity_content + float(self.content.sum()) - self.initial_fluid
        # relative to the fluid in play: before a delayed pump starts, the initial fluid
        scale = max(abs(self.injected), abs(self.initial_fluid), 1e-300)
        err = abs(self.injected - stored_total - self.leaked) / scale
        counts = self.solid.broken_counts()
        return StepRecord(
            time=t1,
            dt=dt,
            injection_pressure=self.p_cavity,
            injected_volume=self.injected,
            cavity_fluid=self.cavity_content,
            fracture_fluid=float(self.content.sum()),
            fracture_volume=float(np.maximum(vf, 0.0).sum()),
            leaked_volume=self.leaked,
            mass_error=err,
            volume_mismatch=self.volume_mismatch / scale,
            wet_facets=int(self.wet.sum()),
            tensile=counts["tensile"],
            shear=counts["shear"],
            fracture_degree=self.solid.fracture_degree(),
            newton_iterations=its,
            rebuilds=self.rebuilds,
            wall_time=self.wall_time(),
            held_shut=self.solid.held_shut.count,
        )

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
        # the settled state's worst failure ratio, not 1 for a step that broke: so the
        # first step can be shortened onto the first crack (lab at 45 deg, coarse: once it
        # broke in the first step, somewhere between 0 and 2.29 MPa)
        self._last_ratio = self._worst
        self.first_break_time = self.first_break_pressure = None
        self.first_break_ratio = self.first_break_point = self._landed = None
        self.initial_failures = sum(self.solid.broken_counts().values()) - before
        return self.initial_failures

    def wall_time(self) -> float:
        """Return the wall time since the fracture was built (s): the clock of its records."""
        return time.perf_counter() - self.wall_start

    def run(self, t_end: float, max_steps: int = 100_000) -> list[StepRecord]:
        """Step to ``t_end`` (s); progress lines go to ``progress`` if set."""
        if not (math.isfinite(t_end) and t_end > self.t):
            raise ValueError(
                f"t_end must be a time in s after the current {self.t} s, got {t_end!r}"
            )
        pace = TimeLeft(t_end, self.t)
        begun = self.wall_time()  # a run goes on from a settled state
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
            pace.add(self.t, rec.wall_time - begun)
            if self.progress is not None:
                self.progress(rec.progress_line(pace.seconds()))
        return self.history

    # ------------------------------------------------------------- results

    def _last_volumes(self) -> np.ndarray:
        vf, _ = self.op.volumes.at(self._guess())
        return vf

    def _saturation(self) -> np.ndarray:
        lag = self.balance.lag
        return fields.saturation(self.wet, self.content, self._last_volumes(), lag)

    def wet_extent(self, origin: Sequence[float], direction: Sequence[float]) -> float:
        """Return the fluid front along ``direction`` from ``origin`` (m)."""
        return fields.wet_extent(self.net, self.wet, self._saturation(), origin, direction)

    def apertures(self) -> np.ndarray:
        """Hydraulic aperture of every network facet (m): never negative."""
        return fields.apertures(self._last_volumes(), self.net.area, self.fluid.residual_aperture)

    def opening_at_cavity(self) -> float:
        """Mean opening of the facets that touch the cavity or injection point (m)."""
        return fields.opening_at_cavity(self._last_volumes(), self.net)

    def facet_fields(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Return the fluid data of this rank's network facets (see ``fields.facet_fields``)."""
        sat, aperture = self._saturation(), self.apertures()
        return fields.facet_fields(
            self.solid, self.view, self.pressure, aperture, sat, self.is_open
        )

    def interface_fields(self, loads: Loads) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Return the data of every owned interface at :meth:`current_loads` (see ``fields``)."""
        sat, aperture = self._saturation(), self.apertures()
        return fields.interface_fields(self.solid, loads, self.view, self.pressure, aperture, sat)

    def current_loads(self) -> Loads:
        """Set the solid's displacement to the last accepted state; return its loads."""
        return self._set_displacement(self._guess())

    # ------------------------------------------------------------ checkpoints

    def checkpoint(self) -> dict:
        """Return the state to continue from (the same on every rank, JSON-ready).

        Interfaces and fluid are keyed by global vertex ids, so a run may resume
        on another number of ranks (:mod:`~hfcdem.coupling.checkpoint`).
        """
        scalars = {k: getattr(self, k) for k in SCALARS}
        scalars["rebuild_causes"] = dict(self.rebuild_causes)
        return checkpoint_data(scalars, self.solid, self.facet_fluid)

    def restore(self, data: dict, history: list[StepRecord] | None = None) -> None:
        """Continue from a :meth:`checkpoint` (collective), with the ``history`` so far.

        The checkpoint holds the state only; the step records come from
        ``history.csv`` (or an older checkpoint's ``history``).
        """
        scalars, self.facet_fluid = read_checkpoint(data, self.solid)
        causes = scalars.pop("rebuild_causes", {})  # older checkpoints have none
        for k, v in scalars.items():
            setattr(self, k, v)
        self.rebuild_causes = collections.Counter(causes)
        if history is None:
            history = [StepRecord.from_row(row) for row in data.get("history", [])]
        self.history = list(history)
        self._release_debris(self.t)  # the held cells are not in the checkpoint: found again
        self.rebuild("resume")

    def write_history(self, path: str | os.PathLike[str]) -> None:
        """Write the step records as CSV (rank 0, atomically: a stopped run keeps it)."""
        names = list(StepRecord.__dataclass_fields__)
        rows = [[float(getattr(r, k)) for k in names] for r in self.history]
        write_csv(path, names, rows, self.comm)


__all__ = [
    "FlowSettings",
    "HydraulicFracture",
    "SimulationStopped",
    "StepRecord",
    "relative_permeability",
]
