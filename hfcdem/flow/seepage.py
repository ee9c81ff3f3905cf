"""Seepage through intact joints: transient cubic-law flow on a joint network.

Every interface facet of a set (the fracturable zone) is a joint of hydraulic
aperture ``a``: a cell of the :class:`~hfcdem.flow.network.Network` holding
``V = a A`` of fluid at zero pressure and ``V p / Kw`` more at pressure ``p``.
Cells exchange fluid through the network's pair transmissibilities (cubic law
``k = a^3 / 12 mu``, two-point ``t = k c / d`` per star entry, junctions
eliminated as zero-volume nodes).  Implicit Euler in time::

    (S / dt + T) p^{n+1} = S / dt p^n + sum_c t_c p_cavity

with ``S = diag(a A / Kw)`` and ``T`` the sparse transmissibility matrix (the
cavity connections on its diagonal).  The network is replicated on every rank
in a rank-independent order and solved there with a sparse LU (PETSc,
``COMM_SELF``), so every rank holds the same pressures whatever their number.
The solid does not enter yet: apertures are given, not computed.

``filling="saturation"`` lets joints start dry and fill from the cavity
(perforation paper, eqs. 14-19): one unknown ``q`` per facet with content
``V (1 + q / Kw)``, pressure ``max(q, 0)`` and saturation ``min(1, 1 + q / Kw)``,
fluxes scaled by ``ks = S^2 (3 - 2S)``; each step is a semismooth Newton solve
(:mod:`hfcdem.flow.filling`).  With every joint full it is the compressible model.

:meth:`JointSeepage.step_pumped` makes the cavity pressure an unknown too: the
cavity (a :class:`CavityStorage`) and the joints together must hold a given
volume at the end of the step.  Each Newton iterate is the joints' system
bordered by that one balance, solved by two back-substitutions with the same
factorisation, so a pumped step costs one Newton, not one per trial pressure.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.materials import JOINT_HYDRAULIC_APERTURE, PERMEABILITY_COEFFICIENT, Fluid
from hfcdem.flow.balance import relative_permeability
from hfcdem.flow.filling import Linearisation, Pairs, linearise, residual, saturation
from hfcdem.flow.network import Network, build_network
from hfcdem.solid.cdem import CDEMSolid

#: initial hydraulic aperture of the intact joints (perforation paper, Table 1), m
INITIAL_JOINT_APERTURE = 5e-6

#: PETSc options prefix of the seepage solve (the command line may override it)
PREFIX = "hfcdem_seepage_"

#: pivots below this are zero in the LU (PETSc's default, 2.2e-14, is absolute)
ZERO_PIVOT = 1e-300

#: filling modes: full joints with compressibility storage, or dry joints filling
FILLING_MODES = ("compressible", "saturation")

#: Newton stops when every facet's residual over the step is below this fraction
#: of its void volume: ``|R_i| dt <= tol V_i`` (a pressure error ``tol Kw``, 2.2e-3 Pa for water)
FILLING_TOLERANCE = 1e-12

#: Newton iterations (linear solves) allowed per step before a RuntimeError
MAX_NEWTON_ITERATIONS = 60

#: relative round-off allowed in a facet's sum of fluxes (1000 machine epsilons)
_ROUNDOFF = 1e3 * float(np.finfo(float).eps)

#: the derivative of ks enters once the residual is below this fraction of the void
NEWTON_SWITCH = 1e-2


def joint_network(
    solid: CDEMSolid, cavity_vertices: np.ndarray, facets: Sequence[int] | np.ndarray | None = None
) -> Network:
    """Build the network of the joints ``facets`` of ``solid`` (collective).

    ``facets``: local interface indices (owned or ghost; default every
    interface of the zone); ``cavity_vertices``: global vertex ids of the cavity
    wall (e.g. :func:`hfcdem.coupling.condense.cavity_vertices`).  Only the
    owned ones are gathered, so each joint appears once.
    """
    n = solid.num_facets
    local = np.arange(n) if facets is None else np.unique(np.asarray(facets, dtype=np.int64))
    if local.size and (local[0] < 0 or local[-1] >= n):
        raise ValueError(f"facets must be local interface indices in [0, {n}), got out of range")
    owned = local[solid.owned[local]]
    net, _ = build_network(
        solid.comm,
        solid.vertex_ids[owned],  # unsorted: build_network orders ids and coordinates
        solid.areas[owned],
        solid.vertex_coords[owned],
        np.asarray(cavity_vertices, dtype=np.int64),
    )
    return net


def network_positions(solid: CDEMSolid, net: Network, facets: np.ndarray) -> np.ndarray:
    """Position in ``net`` of every local interface in ``facets`` (owned or ghost)."""
    positions = net.positions(solid.vertex_ids[np.asarray(facets, dtype=np.int64)])
    if np.any(positions < 0):
        raise ValueError("network_positions: a facet is not in the network")
    return positions


def network_values(
    solid: CDEMSolid, net: Network, facets: np.ndarray, positions: np.ndarray, values: np.ndarray
) -> np.ndarray:
    """Per facet of ``net``, the ``values`` (one per local interface) of its owning rank.

    ``facets``: local interfaces in ``net``, ``positions`` their
    :func:`network_positions`.  Each joint is owned by one rank, so the sum over
    ranks is its value exactly: the same array on every rank (collective).
    """
    facets = np.asarray(facets, dtype=np.int64)
    owned = solid.owned[facets]
    local = np.zeros(net.size)
    local[positions[owned]] = np.asarray(values)[facets[owned]]
    out = np.zeros_like(local)
    solid.comm.Allreduce(local, out, op=MPI.SUM)
    return out


def _apertures(name: str, value: float | np.ndarray, n: int) -> np.ndarray:
    """``value`` as ``n`` apertures (m), each finite and > 0."""
    ap = np.asarray(value, dtype=float)
    if ap.ndim not in (0, 1) or (ap.ndim == 1 and ap.shape != (n,)):
        raise ValueError(f"{name} must be one value or {n} values (m)")
    ap = np.broadcast_to(ap, (n,)).copy()
    if n and not (np.all(np.isfinite(ap)) and ap.min() > 0.0):
        raise ValueError(f"{name} must be finite and > 0 m on every facet, min {ap.min()!r}")
    return ap


def _finite(name: str, value: float, unit: str) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite ({unit}), got {value!r}")
    return v


@dataclass(frozen=True)
class CavityStorage:
    """Fluid a cavity holds at pressure ``P``: ``(volume + slope (P - pressure)) (1 + P / Kw)``.

    ``volume`` (m^3; per metre in 2D) at ``pressure`` (Pa), its walls'
    ``slope`` dV/dP (m^3/Pa) at fixed interface states, the fluid's
    ``bulk_modulus`` Kw (Pa).  ``joint_coupling`` (m^3/Pa per network facet,
    optional): how the volume moves with the joints' pressures, measured at
    ``joint_pressure`` (Pa per network facet).  The volume then is
    ``volume + slope (P - pressure) + joint_coupling . (p_joints - joint_pressure)``.
    """

    volume: float
    slope: float
    pressure: float
    bulk_modulus: float
    joint_coupling: np.ndarray | None = field(default=None, compare=False)
    joint_pressure: np.ndarray | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        for name, unit in (("volume", "m^3"), ("slope", "m^3/Pa"), ("pressure", "Pa")):
            _finite(name, getattr(self, name), unit)
        if not (math.isfinite(self.bulk_modulus) and self.bulk_modulus > 0.0):
            raise ValueError(f"bulk_modulus must be > 0 Pa, got {self.bulk_modulus!r}")
        if (self.joint_coupling is None) != (self.joint_pressure is None):
            raise ValueError("joint_coupling and joint_pressure come together (or neither)")
        if self.joint_coupling is not None:
            g, pj = np.asarray(self.joint_coupling), np.asarray(self.joint_pressure)
            if g.ndim != 1 or g.shape != pj.shape:
                raise ValueError(
                    f"joint_coupling and joint_pressure must be two vectors of one length, "
                    f"got {g.shape} and {pj.shape}"
                )
            if not (np.all(np.isfinite(g)) and np.all(np.isfinite(pj))):
                raise ValueError("joint_coupling (m^3/Pa) and joint_pressure (Pa) must be finite")

    def held(self, p: float, joints: np.ndarray | None = None) -> float:
        """Fluid held at ``p`` (m^3 at zero pressure), the joints at ``joints`` (Pa)."""
        volume = self.volume + self.slope * (p - self.pressure)
        if self.joint_coupling is not None and joints is not None:
            volume += float(self.joint_coupling @ (joints - self.joint_pressure))
        return volume * (1.0 + p / self.bulk_modulus)

    def coefficients(self, shift: float = 0.0, tilt: float = 0.0) -> tuple[float, float, float]:
        """``(a2, a1, a0)`` with ``held(P) = a2 P^2 + a1 P + a0``.

        ``shift + tilt P`` is added to the volume (the joints' part, linearised).
        """
        slope = self.slope + tilt
        base = self.volume - self.slope * self.pressure + shift
        kw = self.bulk_modulus
        return slope / kw, slope + base / kw, base


class CavityDry(RuntimeError):
    """The cavity holds more than the target even at zero pressure: it runs dry."""


class JointSeepage:
    """Transient seepage on a joint network with the cavity pressure as Dirichlet value.

    Parameters
    ----------
    net
        The joint network (the same on every rank).
    aperture
        Hydraulic aperture per facet (m), ``(n,)`` or one value for all.
    fluid
        Viscosity (Pa s) and bulk modulus ``Kw`` (Pa) of the fluid.
    pressure
        Initial facet pressure (Pa), ``(n,)`` or one value.
    filling
        ``"compressible"`` (full joints, storage ``V / Kw``) or ``"saturation"``
        (joints fill from dry; pressure rises once full).
    saturation
        Initial saturation in [0, 1], ``(n,)`` or one value (1: full).  Below 1
        only with ``filling="saturation"``, and only where the pressure is 0.
    void_aperture
        Aperture of each facet's void (m), ``(n,)`` or one value: its fluid
        volume is ``void_aperture * area``.  Default: ``aperture`` (one aperture
        for flow and storage); :mod:`hfcdem.flow.apertures` gives the two apart
        when the apertures follow the mesh size.

    """

    def __init__(
        self,
        net: Network,
        aperture: float | np.ndarray,
        fluid: Fluid,
        pressure: float | np.ndarray = 0.0,
        filling: str = "compressible",
        saturation: float | np.ndarray = 1.0,
        void_aperture: float | np.ndarray | None = None,
    ) -> None:
        if filling not in FILLING_MODES:
            raise ValueError(f"filling must be one of {FILLING_MODES}, got {filling!r}")
        n = net.size
        ap = _apertures("aperture", aperture, n)
        void = ap.copy() if void_aperture is None else _apertures("void_aperture", void_aperture, n)
        self.net = net
        self.fluid = fluid
        self.aperture = ap
        self.void_aperture = void
        self.void = void * net.area  # m^3 per facet at zero pressure
        self.storage = self.void / fluid.bulk_modulus  # m^3/Pa per facet
        self.transmissibility = net.transmissibility(ap, fluid.conductivity)  # m^3/(Pa s)
        for arr in (self.aperture, self.void_aperture, self.void, self.storage):
            arr.flags.writeable = False
        self.transmissibility.flags.writeable = False
        self.filling = filling
        # q: the pressure of a full joint, Kw (S - 1) below it (see hfcdem.flow.filling)
        initial = self._facet_values("pressure", pressure)
        self._q = _initial_state(initial, saturation, filling, fluid)
        fa, fb, inner = net.pair_facets
        self._cavity = np.flatnonzero(~inner)  # connections to the cavity
        self._pattern = _pattern(n, fa, fb, inner)
        self._csr, self._diag = _csr(self._pattern, fa, inner, self.transmissibility)
        t = self.transmissibility
        self._pairs = Pairs(fa[inner], fb[inner], t[inner], fa[~inner], t[~inner], n)
        # sum of each facet's transmissibilities: the scale of its flux round-off
        self._reach = np.zeros(n)
        for facets, trans in (
            (fa[inner], t[inner]),
            (fb[inner], t[inner]),
            (fa[~inner], t[~inner]),
        ):
            np.add.at(self._reach, facets, trans)
        self._solver: tuple[float, PETSc.KSP] | None = None
        self._fill_solver: PETSc.KSP | None = None  # saturation filling's Newton matrix
        self._injected = 0.0
        self._iterations = 0

    @property
    def pressure(self) -> np.ndarray:
        """Facet pressures (Pa) after the last step."""
        if self.filling == "compressible":
            return self._q.copy()
        return np.maximum(self._q, 0.0)

    @property
    def saturation(self) -> np.ndarray:
        """Facet saturations in [0, 1] (1 everywhere in the compressible mode)."""
        if self.filling == "compressible":
            return np.ones(self.net.size)
        return saturation(self._q, self.fluid.bulk_modulus)

    @property
    def content(self) -> np.ndarray:
        """Fluid content of every facet, ``V (1 + q / Kw)`` (m^3 at zero pressure)."""
        return self.void + self.storage * self._q

    @property
    def newton_iterations(self) -> int:
        """Linear solves of the last step (1 in the compressible mode)."""
        return self._iterations

    @property
    def cavity_facets(self) -> np.ndarray:
        """Facet of every cavity connection, in connection order."""
        return np.asarray(self.net.pair_facets[0][self._cavity])

    def save(self) -> np.ndarray:
        """Return the state of every facet (a copy) for :meth:`restore` (trial steps)."""
        return self._q.copy()

    def restore(self, saved: np.ndarray) -> None:
        """Return to a state from :meth:`save` (e.g. to repeat a step at another pressure)."""
        arr = np.asarray(saved, dtype=float)
        if arr.shape != self._q.shape:
            raise ValueError(f"saved state must hold {self._q.shape[0]} values, got {arr.shape}")
        self._q = arr.copy()

    def stored(self) -> float:
        """Content above full joints at zero pressure: ``sum V q / Kw`` (m^3).

        ``sum V p / Kw`` when every joint is full; negative while some are not.
        """
        return float(self.storage @ self._q)

    def inflow(
        self,
        cavity_pressure: float | np.ndarray,
        pressure: np.ndarray,
        saturation: np.ndarray | None = None,
    ) -> np.ndarray:
        """Rate into the network through every cavity connection (m^3/s) at facet ``pressure``.

        ``saturation`` (per facet; default full) scales each connection by
        ``ks`` of the mean of the facet's and the cavity's (1) saturation.
        """
        pc = self._cavity_values(cavity_pressure)
        fa = self.cavity_facets
        t = self.transmissibility[self._cavity]
        if saturation is not None:
            t = t * relative_permeability(0.5 * (np.asarray(saturation)[fa] + 1.0))
        return t * (pc - pressure[fa])

    def flux_into_network(self) -> float:
        """Volume that entered from the cavity during the last step (m^3)."""
        return self._injected

    def step(self, dt: float, cavity_pressure: float | np.ndarray) -> np.ndarray:
        """Advance by ``dt`` (s) with the cavity at ``cavity_pressure`` (Pa); return pressures.

        ``cavity_pressure``: one value, or one per cavity connection
        (:attr:`cavity_facets` order).
        """
        dt = _finite("dt", dt, "s")
        if dt <= 0.0:
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        pc = self._cavity_values(cavity_pressure)
        if self.net.size == 0:
            self._injected = 0.0
            return np.zeros(0)
        if self.filling == "saturation":
            if pc.size and pc.min() < 0.0:
                msg = f"cavity_pressure must be >= 0 Pa with saturation filling, got {pc.min()!r}"
                raise ValueError(msg)
            self._q, self._injected, self._iterations = self._fill(dt, pc)
            return self.pressure
        rhs = self.storage / dt * self._q + self._cavity_load(pc)
        if self._solver is None or self._solver[0] != dt:
            self.destroy()
            self._solver = (dt, _lu(self._csr, self._diag, self.storage / dt))
        new = _solve(self._solver[1], rhs)
        self._injected = dt * float(self.inflow(pc, new).sum())
        self._q = new
        self._iterations = 1
        return new.copy()

    def _fill(self, dt: float, pc: np.ndarray) -> tuple[np.ndarray, float, int]:
        """Semismooth Newton for one filling step: new ``q``, injected volume, linear solves.

        Each iterate solves the system linearised at the last one: the active set
        of ``max(q, 0)``, and ``ks`` lagged (Picard) until the active set stays
        and the residual is below :data:`NEWTON_SWITCH` and falling, then with its
        derivative (Newton; early on it can point the wrong way where ``ks``
        grows fast with S).  The accepted iterate is a plain linear solve and
        the injected volume is that system's cavity flux, so its rows sum to
        exact mass conservation whatever the residual.  Iterates are projected
        on bounds the solution obeys: a joint that fills within an iteration,
        with no outflow yet, overshoots by orders of magnitude.
        """
        old = self._q
        kw = self.fluid.bulk_modulus
        rate = self.storage / dt
        pmax = max(float(np.abs(old).max()), float(pc.max(initial=0.0)))
        scale = self._residual_scale(dt, pmax)
        # a joint below full at the end only gained (p = 0: nothing flows out), and no
        # pressure exceeds the largest old or cavity one (a monotone scheme)
        low, high = np.minimum(old, 0.0), max(float(old.max()), float(pc.max(initial=0.0)))
        q, newton, worst = old, False, math.inf
        for solves in range(1, MAX_NEWTON_ITERATIONS + 1):
            lin = linearise(self._pairs, q, kw, pc, newton)
            new = self._linear_solve(lin, rate, rate * old + lin.load)
            res = float(np.abs(residual(self._pairs, new, old, rate, kw, pc) * scale).max())
            if res <= FILLING_TOLERANCE:
                return new, -dt * float(lin.cavity_outflow(new).sum()), solves
            same = np.array_equal(new > 0.0, q > 0.0)
            newton = same and res < NEWTON_SWITCH and res < worst
            q, worst = np.clip(new, low, high), res
        raise RuntimeError(
            f"saturation filling: Newton did not converge in {MAX_NEWTON_ITERATIONS} iterations "
            f"(dt = {dt!r} s; residual {worst:.3g} of the void or flux round-off); try a smaller dt"
        )

    def step_pumped(
        self, dt: float, cavity: CavityStorage, target: float, guess: np.ndarray | None = None
    ) -> float:
        """Advance by ``dt`` (s) with the cavity pressure unknown; return it (Pa).

        At the end of the step the cavity (``cavity.held``) and the joints
        (:attr:`content`) hold ``target`` (m^3) together.  Saturation filling
        only.  A semismooth Newton on the joints and the cavity pressure
        together: each iterate solves the joints' system linearised as in
        :meth:`step` for the load and for a unit cavity pressure (one
        factorisation, two back-substitutions), so the joints respond linearly
        to the cavity pressure, and the balance, quadratic in it, is solved in
        closed form.  The accepted iterate conserves mass exactly, as a step's.
        ``guess``: the joints' state to start Newton from (e.g. the last
        balance of the same step; default the state before the step).
        Raises :class:`CavityDry` when the joints and the cavity hold more than
        ``target`` at zero pressure, RuntimeError when Newton does not converge.
        """
        dt = _finite("dt", dt, "s")
        if dt <= 0.0:
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        target = _finite("target", target, "m^3")
        if self.filling != "saturation":
            raise ValueError("step_pumped needs filling='saturation'")
        old = self._q
        kw = self.fluid.bulk_modulus
        void = self.void
        a2, a1, a0 = cavity.coefficients()
        base = float(void.sum()) - target
        if self.net.size == 0:
            p = _balance_root(a2, a1, a0 + base)
            if p < 0.0:
                excess = a0 + base
                raise CavityDry(f"the cavity runs dry (holds {excess:.3g} m^3 more at 0 Pa)")
            self._injected, self._iterations = 0.0, 0
            return p
        rate = self.storage / dt
        low, old_max = np.minimum(old, 0.0), float(np.abs(old).max())
        count = len(self._cavity)
        q, p, newton, worst = old, max(cavity.pressure, 0.0), False, math.inf
        if guess is not None:
            q = np.asarray(guess, dtype=float)
            if q.shape != old.shape:
                raise ValueError(f"guess must hold {old.shape[0]} values, got {q.shape}")
            q = np.clip(q, low, max(float(old.max()), p))
        for solves in range(1, MAX_NEWTON_ITERATIONS + 1):
            lin = linearise(self._pairs, q, kw, np.full(count, p), newton)
            ksp = self._factorise(lin, rate)
            x0 = _solve(ksp, rate * old + lin.load)
            unit = np.zeros(self.net.size)
            np.add.at(unit, lin.cavity_facets, lin.cavity_tk)
            x1 = _solve(ksp, unit)  # d q / d P at this linearisation
            # the joints hold void + S (x0 + (P' - p) x1): the balance's terms in P'
            c1 = float(self.storage @ x1)
            c0 = base + float(self.storage @ x0) - p * c1
            p_new = _balance_root(a2, a1 + c1, a0 + c0)
            if cavity.joint_coupling is not None:
                p_new = _coupled_root(cavity, x0, x1, p, p_new, (c1, c0))
            dry = p_new < 0.0
            p_new = max(p_new, 0.0)
            new = x0 + (p_new - p) * x1
            pc = np.full(count, p_new)
            scale = self._residual_scale(dt, max(old_max, p_new))
            res = float(np.abs(residual(self._pairs, new, old, rate, kw, pc) * scale).max())
            if res <= FILLING_TOLERANCE:
                if dry:
                    joints = np.maximum(new, 0.0)
                    excess = cavity.held(0.0, joints) + float(void @ (1.0 + new / kw)) - target
                    msg = f"the cavity runs dry (holds {excess:.3g} m^3 more than pumped at 0 Pa)"
                    raise CavityDry(msg)
                outflow = float(lin.cavity_outflow(new).sum()) - (p_new - p) * float(
                    lin.cavity_tk.sum()
                )
                self._q, self._injected, self._iterations = new, -dt * outflow, solves
                return p_new
            same = np.array_equal(new > 0.0, q > 0.0)
            newton = same and res < NEWTON_SWITCH and res < worst
            high = max(float(old.max()), p_new)
            q, p, worst = np.clip(new, low, high), p_new, res
        raise RuntimeError(
            f"pumped seepage: Newton did not converge in {MAX_NEWTON_ITERATIONS} iterations "
            f"(dt = {dt!r} s; residual {worst:.3g} of the void or flux round-off); try a smaller dt"
        )

    def _residual_scale(self, dt: float, pmax: float) -> np.ndarray:
        """Per facet, ``dt`` over the volume a step's residual is measured against.

        A fraction of the void, or the round-off of the facet's flux sum when that
        is larger (a long step on full joints: fluxes far above the void).
        """
        void = self.void
        return dt / np.maximum(void, _ROUNDOFF * dt * self._reach * pmax / FILLING_TOLERANCE)

    def _linear_solve(self, lin: Linearisation, shift: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        return _solve(self._factorise(lin, shift), rhs)

    def _factorise(self, lin: Linearisation, shift: np.ndarray) -> PETSc.KSP:
        """Set up the Newton matrix of ``lin`` plus ``diag(shift)`` for solves."""
        indptr, indices, inverse, count = self._pattern
        data = np.bincount(inverse, weights=lin.values, minlength=count)
        if self._fill_solver is None:  # one matrix and KSP for every Newton solve
            self._fill_solver = _lu((indptr, indices, data), self._diag, shift)
        else:  # the same pattern: PETSc keeps the symbolic factorisation
            values = data.copy()
            values[self._diag] += shift
            mat = self._fill_solver.getOperators()[0]
            itype = PETSc.IntType
            mat.setValuesCSR(indptr.astype(itype), indices.astype(itype), values)
            mat.assemble()
            self._fill_solver.setOperators(mat)
        return self._fill_solver

    def steady(self, cavity_pressure: float | np.ndarray) -> np.ndarray:
        """Steady facet pressures for ``cavity_pressure`` (the state is not changed).

        Every facet must be joined to the cavity (else its pressure is undefined).
        """
        if self.net.size and np.any(self.net.components() != 0):
            raise ValueError("steady seepage needs every facet joined to the cavity")
        pc = self._cavity_values(cavity_pressure)
        if self.net.size == 0:
            return np.zeros(0)
        ksp = _lu(self._csr, self._diag, np.zeros(self.net.size))
        try:
            return _solve(ksp, self._cavity_load(pc))
        finally:
            ksp.getOperators()[0].destroy()
            ksp.destroy()

    def destroy(self) -> None:
        """Free the kept factorisations (a new time step size factorises again)."""
        if self._solver is not None:
            ksp = self._solver[1]
            ksp.getOperators()[0].destroy()
            ksp.destroy()
            self._solver = None
        if self._fill_solver is not None:
            self._fill_solver.getOperators()[0].destroy()
            self._fill_solver.destroy()
            self._fill_solver = None

    def _cavity_load(self, pc: np.ndarray) -> np.ndarray:
        load = np.zeros(self.net.size)
        np.add.at(load, self.cavity_facets, self.transmissibility[self._cavity] * pc)
        return load

    def _cavity_values(self, value: float | np.ndarray) -> np.ndarray:
        count = len(self._cavity)
        arr = np.asarray(value, dtype=float)
        if arr.ndim not in (0, 1) or (arr.ndim == 1 and arr.shape != (count,)):
            raise ValueError(f"cavity_pressure must be one value or {count} values (Pa)")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"cavity_pressure must be finite (Pa), got {value!r}")
        return np.broadcast_to(arr, (count,)).copy()

    def _facet_values(self, name: str, value: float | np.ndarray) -> np.ndarray:
        arr = np.asarray(value, dtype=float)
        n = self.net.size
        if arr.ndim not in (0, 1) or (arr.ndim == 1 and arr.shape != (n,)):
            raise ValueError(f"{name} must be one value or {n} values (Pa)")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite (Pa)")
        return np.broadcast_to(arr, (n,)).copy()


def _coupled_root(
    cavity: CavityStorage,
    x0: np.ndarray,
    x1: np.ndarray,
    p: float,
    guess: float,
    joints: tuple[float, float],
) -> float:
    """:func:`_balance_root` with the cavity's volume following the joints' pressures.

    The joints' pressures of the iterate, ``max(x0 + (P - p) x1, 0)``, are
    linear in ``P`` on the facets that hold pressure at the root: that set is
    found by a few fixed-point passes from ``guess`` (the root without the
    coupling).  Returns ``guess`` when the coupled balance has no rising branch
    (the measured-volume pass of the caller then does the coupling).
    """
    g = np.asarray(cavity.joint_coupling)
    ref = float(g @ np.asarray(cavity.joint_pressure))
    c1, c0 = joints
    root, active = guess, None
    for _ in range(4):
        now = x0 + (max(root, 0.0) - p) * x1 > 0.0
        if active is not None and np.array_equal(now, active):
            break
        active = now
        tilt = float(g[active] @ x1[active])
        shift = float(g[active] @ (x0[active] - p * x1[active])) - ref
        a2, a1, a0 = cavity.coefficients(shift, tilt)
        if not a1 + c1 > 0.0:
            return guess
        root = _balance_root(a2, a1 + c1, a0 + c0)
    return root


def _balance_root(a2: float, a1: float, a0: float) -> float:
    """Return the root of ``a2 P^2 + a1 P + a0`` on its rising branch (``a1 > 0``, ``a2 >= 0``).

    Negative when the cavity holds too much at 0 Pa (``a0 > 0``); -inf when no
    real root exists there (so also dry).
    """
    if not a1 > 0.0:
        raise RuntimeError(f"the cavity and joints hold less as the pressure rises ({a1!r} m^3/Pa)")
    disc = a1 * a1 - 4.0 * a2 * a0
    if disc < 0.0:
        return -math.inf
    return -2.0 * a0 / (a1 + math.sqrt(disc))  # no cancellation whatever the sign of a0


def _initial_state(
    pressure: np.ndarray, value: float | np.ndarray, filling: str, fluid: Fluid
) -> np.ndarray:
    """Validate the initial pressure and saturation and return the unknown ``q``."""
    n = pressure.size
    sat = np.asarray(value, dtype=float)
    if sat.ndim not in (0, 1) or (sat.ndim == 1 and sat.shape != (n,)):
        raise ValueError(f"saturation must be one value or {n} values (in [0, 1])")
    sat = np.broadcast_to(sat, (n,))
    if not np.all(np.isfinite(sat)) or (n and (sat.min() < 0.0 or sat.max() > 1.0)):
        raise ValueError(f"saturation must be in [0, 1] on every facet, got {value!r}")
    if filling == "compressible":
        if n and sat.min() < 1.0:
            raise ValueError("saturation below 1 needs filling='saturation' (compressible: full)")
        return pressure
    if n and pressure.min() < 0.0:
        raise ValueError("pressure must be >= 0 Pa with saturation filling")
    if np.any((sat < 1.0) & (pressure != 0.0)):
        raise ValueError("pressure must be 0 Pa where the saturation is below 1")
    return np.where(sat < 1.0, fluid.bulk_modulus * (sat - 1.0), pressure)


def _pattern(
    n: int, fa: np.ndarray, fb: np.ndarray, inner: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """CSR pattern of the pair matrix: indptr, indices, the slot of each entry, nonzeros.

    Entries come in the order inner (a, a), (b, b), (a, b), (b, a), cavity
    (c, c), then every diagonal; an inner pair couples its two facets, a cavity
    pair adds to its facet's diagonal only (its pressure is known).
    """
    a, b = fa[inner], fb[inner]
    diag = np.arange(n, dtype=np.int64)
    rows = np.concatenate([a, b, a, b, fa[~inner], diag])
    cols = np.concatenate([a, b, b, a, fa[~inner], diag])
    key = rows * n + cols
    uniq, inverse = np.unique(key, return_inverse=True)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(uniq // n, minlength=n))])
    return indptr, uniq % n, inverse, len(uniq)


def _csr(
    pattern: tuple[np.ndarray, np.ndarray, np.ndarray, int],
    fa: np.ndarray,
    inner: np.ndarray,
    trans: np.ndarray,
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    """Transmissibility matrix in CSR (duplicates summed), and its diagonal positions."""
    indptr, indices, inverse, count = pattern
    n = len(indptr) - 1
    t = trans[inner]
    vals = np.concatenate([t, t, -t, -t, trans[~inner], np.zeros(n)])
    data = np.bincount(inverse, weights=vals, minlength=count)
    return (indptr, indices, data), inverse[len(inverse) - n :]  # the diagonals come last


def _lu(
    csr: tuple[np.ndarray, np.ndarray, np.ndarray], diag: np.ndarray, shift: np.ndarray
) -> PETSc.KSP:
    """Factorise ``T + diag(shift)`` on this rank alone (sparse LU; the same on every rank)."""
    indptr, indices, data = csr
    values = data.copy()
    values[diag] += shift
    n = len(indptr) - 1
    itype = PETSc.IntType
    mat = PETSc.Mat().createAIJ(
        (n, n), csr=(indptr.astype(itype), indices.astype(itype), values), comm=PETSc.COMM_SELF
    )
    mat.assemble()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOptionsPrefix(PREFIX)
    ksp.setOperators(mat)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    # sequential MUMPS: No. 2's 34,545 joints at the default mesh refactorise in 0.22 s
    # against 0.56 s with PETSc's own LU (benchmarks/README.md)
    ksp.getPC().setFactorSolverType("mumps")
    # PETSc's zero pivot test is absolute (2.2e-14), but a dry joint's row is only its
    # storage V / (Kw dt), 1.4e-16 m^2/(Pa s) for 6 cm of 5 um at dt = 1 s: tiny pivots
    # only (for -hfcdem_seepage_pc_factor_mat_solver_type petsc; MUMPS scales the rows)
    ksp.getPC().setFactorPivot(zeropivot=ZERO_PIVOT)
    ksp.setFromOptions()  # e.g. -hfcdem_seepage_pc_factor_mat_solver_type petsc
    ksp.setUp()
    return ksp


def _solve(ksp: PETSc.KSP, rhs: np.ndarray) -> np.ndarray:
    b = PETSc.Vec().createWithArray(rhs.copy(), comm=PETSc.COMM_SELF)
    x = b.duplicate()
    ksp.solve(b, x)
    if ksp.getConvergedReason() < 0:
        raise RuntimeError(f"seepage solve failed (KSP reason {ksp.getConvergedReason()})")
    out = x.getArray().copy()
    b.destroy()
    x.destroy()
    return out


__all__ = [
    "FILLING_MODES",
    "FILLING_TOLERANCE",
    "INITIAL_JOINT_APERTURE",
    "JOINT_HYDRAULIC_APERTURE",
    "MAX_NEWTON_ITERATIONS",
    "NEWTON_SWITCH",
    "PERMEABILITY_COEFFICIENT",
    "PREFIX",
    "CavityDry",
    "CavityStorage",
    "JointSeepage",
    "joint_network",
    "network_positions",
    "network_values",
]
