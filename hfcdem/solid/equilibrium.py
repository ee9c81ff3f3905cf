"""A solid's interface states at a fixed load, and a load ramped exactly between breaks.

:func:`equilibrate` breaks overstressed facets and switches contacts until nothing
changes (growing the reduced band first when it must); :func:`ramp` exploits the
linearity between events to land on each critical load.  Both drive a
:class:`~hfcdem.solid.cdem.CDEMSolid` through its public methods.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

import numpy as np
from mpi4py import MPI

from hfcdem.solid.forms import Loads, combine
from hfcdem.solid.interfaces import FacetState, critical_factors, select_breaking
from hfcdem.solid.states import CascadeStopped

if TYPE_CHECKING:
    from hfcdem.solid.cdem import CDEMSolid


def equilibrate(
    solid: CDEMSolid, loads: Loads, max_iterations: int = 200, load_factor: float = 0.0
) -> int:
    """Solve, then break overstressed facets and switch contacts until nothing changes.

    Returns the number of facets broken (global).  Raises
    :class:`~hfcdem.solid.states.CascadeStopped` (on every rank) when the
    active set does not settle in ``max_iterations``; the breaks made so far
    stay in the states and in ``solid.events``.
    """
    broken_total = 0
    t0 = time.perf_counter()
    for iteration in range(max_iterations):
        if solid.progress is not None and iteration and iteration % 10 == 0:
            counts = solid.broken_counts()
            solid.progress(
                f"  iteration {iteration}: {counts['tensile']} tensile, "
                f"{counts['shear']} shear, "
                f"{solid.solves} solves, {time.perf_counter() - t0:.1f} s"
            )
        solid.solve(loads)
        if solid.grow_band(loads):
            continue
        ratio, mode = solid.overstress(loads)
        keys = solid.midpoints
        chosen = select_breaking(
            ratio, keys, solid.model.break_rule, solid.model.max_breaks, solid.comm
        )
        n_break = int(solid.comm.allreduce(len(chosen), op=MPI.SUM))
        if n_break:
            solid.break_facets(chosen, mode[chosen], load_factor)
            broken_total += n_break
            continue
        if solid.update_contact(loads) == 0:
            return broken_total
        solid.sync_ghost_states()
    raise CascadeStopped(load_factor, broken_total, max_iterations)


def ramp(
    solid: CDEMSolid,
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
    states are equilibrated (:func:`equilibrate`).  With ``stop_after_first``
    the ramp ends at the first break.  Returns the load factor of the first
    break, or None if nothing breaks up to ``max_factor``.  A cascade that
    does not settle raises :class:`~hfcdem.solid.states.CascadeStopped`
    carrying that first break; the events so far stay in :attr:`events`.
    """
    if solid.mode == "reduced":
        raise ValueError(
            "ramp() needs mode='full': the reduced band is grown by equilibrate() "
            "and the coupled runs, not by the linear ramp"
        )
    lam = 0.0
    first: float | None = None
    while lam < max_factor:
        solid.solve(base, unit)
        crit = critical_factor(solid, base, unit, lam, max_factor, samples)
        local_min = float(crit.min()) if crit.size else math.inf
        lam_star = solid.comm.allreduce(local_min, op=MPI.MIN)
        if not math.isfinite(lam_star):
            break
        first = lam_star if first is None else first
        lam = lam_star * (1.0 + 1e-9)
        loads = combine(base, unit, lam)
        solid.u.x.array[:] += lam * solid.u_unit.x.array
        try:
            equilibrate(solid, loads, max_iterations=max_iterations, load_factor=lam)
        except CascadeStopped as stop:
            raise CascadeStopped(
                stop.load_factor, stop.broken, stop.iterations, first_break=first
            ) from None
        if solid.progress is not None:
            counts = solid.broken_counts()
            solid.progress(
                f"  load factor {lam:.6g}: {counts['tensile']} tensile, {counts['shear']} shear"
            )
        if stop_after_first:
            break
    return first


def critical_factor(
    solid: CDEMSolid, base: Loads, unit: Loads, lam0: float, lam1: float, samples: int
) -> np.ndarray:
    """Smallest factor in (lam0, lam1] at which each intact owned facet fails."""
    intact = (solid.state == FacetState.INTACT) & solid.owned
    n = solid.normals[intact]
    return critical_factors(
        [solid.jumps(solid.u, pts)[intact] for pts in solid.strength_points],
        [solid.jumps(solid.u_unit, pts)[intact] for pts in solid.strength_points],
        n,
        np.einsum("ij,fj->fi", solid.sigma0, n),
        (base.in_situ_factor, unit.in_situ_factor),
        (solid.kn[intact], solid.ks[intact]),
        (solid.t0[intact], solid.c0[intact], solid.model.friction),
        (lam0, lam1, samples),
    )


__all__ = ["critical_factor", "equilibrate", "ramp"]
