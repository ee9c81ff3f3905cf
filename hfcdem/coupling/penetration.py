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

import numpy as np
from mpi4py import MPI

from hfcdem.config.materials import Fluid
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.seepage import JointSeepage, joint_network
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.equilibrium import critical_factor
from hfcdem.solid.forms import Loads, combine
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import CascadeStopped


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
class RampBreakdown:
    """First break of a :class:`PressureRamp` (``pressure`` None: nothing broke).

    ``wet_fraction``: share of the zone's joints holding pressure at the break;
    ``wall_joint_pressure``: mean joint pressure of the joints on the cavity
    wall over the cavity pressure, at the break;
    ``joint_pressure``, ``saturation``: per local facet of the solid (0 off the
    joints) at the break, or at the end of the ramp;
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


def ramp_breakdown(
    solid: CDEMSolid,
    cavity: Sequence[str],
    fluid: Fluid,
    aperture: float | np.ndarray,
    ramp: PressureRamp,
    progress: Callable[[str], None] | None = None,
) -> RampBreakdown:
    """Raise the pressure of the ``cavity`` facet groups until the first joint breaks (collective).

    ``solid`` must be in the full mode with every interface intact or a
    pre-existing crack; ``aperture``: hydraulic aperture of the joints (m), one
    value or one per network facet.
    """
    if solid.mode != "full":
        raise ValueError("ramp_breakdown needs CDEMSolid(mode='full') (pressure on glued faces)")
    for name in cavity:
        solid.tmesh.facet_tag(name)  # clear error for unknown groups
    joints = np.flatnonzero((solid.state == FacetState.INTACT) & ~solid.is_crack)
    # the state the ramp starts from (excavated, cavity at P0): what fails there, e.g. on
    # stress noise where the wall mesh changes, breaks first and is not the breakdown
    p0 = ramp.initial_pressure if ramp.filling == "compressible" else 0.0
    start = Loads(
        cavity={name: ramp.initial_pressure for name in cavity},
        joint_pressure=np.where(np.isin(np.arange(solid.num_facets), joints), p0, 0.0),
    )
    try:
        initial_failures = solid.equilibrate(start)
    except CascadeStopped as stop:  # the excavated rock does not stand: no ramp to run
        return RampBreakdown(
            None,
            None,
            None,
            None,
            0.0,
            0.0,
            0,
            stop.broken,
            stopped=f"the excavated rock fails before the ramp: {stop}",
        )
    joints = np.flatnonzero((solid.state == FacetState.INTACT) & ~solid.is_crack)
    net = joint_network(solid, cavity_vertices(solid, cavity, None), joints)
    local = _network_positions(solid, net.index(), joints)
    if ramp.filling == "saturation":  # dry joints hold no pressure
        seep = JointSeepage(net, aperture, fluid, filling="saturation", saturation=0.0)
    else:
        seep = JointSeepage(net, aperture, fluid, pressure=ramp.initial_pressure)
    wall = np.unique(seep.cavity_facets)

    def per_facet(values: np.ndarray) -> np.ndarray:
        out = np.zeros(solid.num_facets)
        out[joints] = values[local]
        return out

    def loads_at(pw: float, pj: np.ndarray, in_situ: float = 1.0) -> Loads:
        cav = {name: pw for name in cavity}
        return Loads(cavity=cav, joint_pressure=per_facet(pj), in_situ_factor=in_situ)

    dt = ramp.dt
    t, pw = 0.0, ramp.initial_pressure
    pj = seep.pressure
    history: list[tuple[float, float, float, float]] = []
    try:
        for n in range(1, ramp.steps + 1):
            pw_new = ramp.initial_pressure + ramp.rate * n * dt
            pj_new = seep.step(dt, pw_new)
            base = loads_at(pw, pj)
            unit = loads_at(pw_new - pw, pj_new - pj, in_situ=0.0)
            solid.solve(base, unit)
            crit = critical_factor(solid, base, unit, 0.0, 1.0, 8)
            s = solid.comm.allreduce(float(crit.min()) if crit.size else math.inf, op=MPI.MIN)
            history.append((t + dt, pw_new, float(seep.content.sum()), s))
            if progress is not None and (n % max(1, ramp.steps // 10) == 0 or math.isfinite(s)):
                progress(
                    f"  t {t + dt:.4g} s, cavity {pw_new / 1e6:.4g} MPa, "
                    f"joints holding pressure {np.mean(pj_new > 0):.1%}"
                )
            if math.isfinite(s):
                p_break = pw + s * (pw_new - pw)
                pj_break = pj + s * (pj_new - pj)
                mode, where = _first_facet(solid, base, unit, s, crit)
                return RampBreakdown(
                    pressure=p_break,
                    time=t + s * dt,
                    mode=mode,
                    location=where,
                    wet_fraction=float(np.mean(pj_break > 0.0)) if net.size else 0.0,
                    wall_joint_pressure=float(np.mean(pj_break[wall]) / p_break)
                    if wall.size
                    else 0.0,
                    steps=n,
                    initial_failures=initial_failures,
                    history=history,
                    joint_pressure=per_facet(pj_break),
                    saturation=per_facet(seep.saturation),
                )
            t, pw, pj = t + dt, pw_new, pj_new
    finally:
        seep.destroy()
    return RampBreakdown(
        None,
        None,
        None,
        None,
        float(np.mean(pj > 0.0)) if net.size else 0.0,
        0.0,
        ramp.steps,
        initial_failures,
        history,
        per_facet(pj),
        per_facet(seep.saturation),
    )


def _network_positions(
    solid: CDEMSolid, index: dict[tuple[int, ...], int], facets: np.ndarray
) -> np.ndarray:
    """Network position of every local facet in ``facets`` (owned or ghost)."""
    keys = np.sort(solid.vertex_ids[facets], axis=1)
    return np.asarray([index[tuple(int(v) for v in k)] for k in keys], dtype=np.int64)


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


__all__ = ["PressureRamp", "RampBreakdown", "ramp_breakdown"]
