"""Breakable interfaces between blocks: geometry, strengths, states and failure.

Every facet of the fracturable zone carries a normal and a tangential spring.
Its state is one of

- ``INTACT`` (0): springs carry the in-situ traction plus ``K [u]``;
- ``TENSILE`` (1) or ``SHEAR`` (2): broken; open faces carry the fluid pressure,
  closed faces resist interpenetration and slide with Coulomb friction.

These numbers are what the output writes (the paper's Fig. 17 uses 0/1/2).
This module is plain NumPy: the DOLFINx side lives in :mod:`hfcdem.solid.cdem`.
Tractions are *tension positive*; strengths are positive numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import numpy.typing as npt


class FacetState(IntEnum):
    """Failure state of an interface."""

    INTACT = 0
    TENSILE = 1
    SHEAR = 2


def stable_facet_hash(vertex_ids: npt.NDArray[np.int64], seed: int) -> npt.NDArray[np.float64]:
    """Uniform numbers in (0, 1) from sorted global vertex ids of each facet (rows).

    SplitMix64 over the ids: the same facet gets the same number on any number of
    ranks and in any ordering.
    """
    ids = np.sort(np.asarray(vertex_ids, dtype=np.int64), axis=1).astype(np.uint64)
    mask = np.uint64(0xFFFFFFFFFFFFFFFF)
    with np.errstate(over="ignore"):
        h: np.ndarray = np.full(
            ids.shape[0], np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) & mask
        )
        for col in range(ids.shape[1]):
            h = h ^ ids[:, col]
            h = h + np.uint64(0x9E3779B97F4A7C15)
            z: np.ndarray = h
            z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
            z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
            h = z ^ (z >> np.uint64(31))
    return (h >> np.uint64(11)).astype(np.float64) / float(1 << 53) * (1.0 - 2e-16) + 1e-16


def weibull_scatter(mean: float, modulus: float, uniform: npt.NDArray[np.float64]) -> np.ndarray:
    """Weibull-distributed values of the given ``mean`` and shape ``modulus``."""
    if not math.isfinite(mean):
        return np.full(uniform.shape, mean)
    scale = mean / math.gamma(1.0 + 1.0 / modulus)
    return scale * (-np.log1p(-uniform)) ** (1.0 / modulus)


@dataclass(frozen=True)
class Overstress:
    """Per-facet failure check: which criterion is exceeded and by how much."""

    ratio: np.ndarray  # max over criteria of demand / strength; >= 1 means failure
    mode: np.ndarray  # FacetState the facet would break into


def check_failure(
    normal_traction: np.ndarray,
    shear_traction: np.ndarray,
    tensile_strength: np.ndarray,
    cohesion: np.ndarray,
    friction: float,
) -> Overstress:
    """Tension cut-off and Mohr-Coulomb checks (tension-positive normal traction)."""
    tn = np.asarray(normal_traction, dtype=float)
    tau = np.abs(np.asarray(shear_traction, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        tensile = np.where(tn > 0.0, tn / tensile_strength, 0.0)
        tensile = np.where((tn > 0.0) & (tensile_strength == 0.0), np.inf, tensile)
        shear_strength = cohesion - tn * friction  # sigma_n = -t_n (compression positive)
        shear = np.where(
            shear_strength > 0.0, tau / shear_strength, np.where(tau > 0.0, np.inf, 0.0)
        )
        shear = np.nan_to_num(shear, nan=0.0)
    ratio = np.maximum(tensile, shear)
    # the tension cut-off wins whenever it is reached
    mode = np.where((tensile >= 1.0) | (tensile >= shear), FacetState.TENSILE, FacetState.SHEAR)
    return Overstress(ratio=ratio, mode=mode.astype(np.int8))


def select_breaking(
    ratio: np.ndarray, keys: np.ndarray, rule: str, max_breaks: int, comm
) -> np.ndarray:
    """Local indices of facets to break this iteration (collective).

    ``ratio`` >= 1 marks overstressed facets; ``keys`` (rows of floats, e.g.
    midpoint coordinates) break ties the same way on any number of ranks.
    """
    over = np.flatnonzero(ratio >= 1.0)
    if rule == "all":
        return over
    count = 1 if rule == "most_overstressed" else max_breaks
    # candidates from every rank, ordered by ratio then by position
    local = [(-float(ratio[i]), *map(float, keys[i]), comm.rank, int(i)) for i in over]
    local.sort()
    gathered = comm.allgather(local[:count])
    chosen = sorted(c for part in gathered for c in part)[:count]
    return np.array([c[-1] for c in chosen if c[-2] == comm.rank], dtype=np.int64)


def critical_factors(
    base_jumps: list[np.ndarray],
    unit_jumps: list[np.ndarray],
    normals: np.ndarray,
    in_situ_traction: np.ndarray,
    in_situ_factors: tuple[float, float],
    stiffness: tuple[np.ndarray, np.ndarray],
    strength: tuple[np.ndarray, np.ndarray, float],
    bracket: tuple[float, float, int],
) -> np.ndarray:
    """Smallest load factor in ``(lam0, lam1]`` at which each facet fails (inf: none).

    The jump at every strength point is ``base + lam unit`` (one array per point),
    the in-situ traction ``sigma0 n`` scales by ``fb + lam fu``, so every facet's
    failure ratio is a cheap function of ``lam``: sample ``samples`` levels, then
    bisect each bracket (all facets at once).  ``stiffness`` is (kn, ks),
    ``strength`` (T0, C0, friction), ``bracket`` (lam0, lam1, samples).
    """
    n, s0n = normals, in_situ_traction
    fb, fu = in_situ_factors
    kn, ks = stiffness
    t0s, c0s, mu = strength
    lam0, lam1, samples = bracket

    def ratio(lam: np.ndarray, sel: np.ndarray) -> np.ndarray:
        """Failure ratio of the facets ``sel``, each at its own factor ``lam``."""
        ns = n[sel]
        t0 = s0n[sel] * (fb + lam * fu)[:, None]
        t0n = np.einsum("fi,fi->f", t0, ns)
        worst = np.zeros(len(lam))
        for jb, ju in zip(base_jumps, unit_jumps, strict=True):
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


__all__ = [
    "FacetState",
    "Overstress",
    "check_failure",
    "critical_factors",
    "select_breaking",
    "stable_facet_hash",
    "weibull_scatter",
]
