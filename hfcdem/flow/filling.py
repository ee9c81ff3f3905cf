"""Saturation filling of a joint network: residual and Newton linearisation (plain NumPy).

One unknown ``q`` (Pa) per facet: content ``M = V (1 + q / Kw)`` for every
``q >= -Kw``, pressure ``p = max(q, 0)`` and saturation ``S = min(1, 1 + q / Kw)``
(a full joint at ``q >= 0``, a dry one at ``q = -Kw``).  Storage is ``V / Kw``
per Pa on both branches, so compressible seepage is the case ``q >= 0``.  A
connection passes ``T ks (p_i - p_j)`` with ``ks = S^2 (3 - 2S)`` of the mean
saturation of its two ends (the cavity end counts ``S = 1``).  Implicit Euler::

    V / (Kw dt) (q - q^n) + sum_pairs T ks (p_i - p_j) + sum_cavity T_c ks_c (p_i - p_c) = 0

:class:`Linearisation` holds the Newton matrix entries at an iterate (the
active set ``H = [q > 0]`` of ``max`` and the derivative of ``ks``), laid out
like the transmissibility matrix of :mod:`hfcdem.flow.seepage`, so the solve
sums them into the same sparse pattern.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hfcdem.flow.balance import relative_permeability


@dataclass(frozen=True, eq=False)
class Pairs:
    """The connections of a network split into inner pairs and cavity connections."""

    a: np.ndarray  # (P_in,) first facet of each inner pair
    b: np.ndarray  # (P_in,) second facet
    t: np.ndarray  # (P_in,) transmissibility, m^3/(Pa s)
    c: np.ndarray  # (P_c,) facet of each cavity connection
    tc: np.ndarray  # (P_c,) transmissibility of each cavity connection
    size: int  # number of facets


@dataclass(frozen=True, eq=False)
class Linearisation:
    """Newton system of the filling step at an iterate ``q`` (fluxes without storage).

    ``values`` are the matrix entries in the order inner (a, a), (b, b), (a, b),
    (b, a), cavity (c, c), then a zero per diagonal; ``load`` the right-hand
    side besides storage: ``sum_c T_c ks_c p_c + C q`` with ``C`` the
    ``ks``-derivative part of the matrix.
    """

    q: np.ndarray  # the iterate
    values: np.ndarray
    load: np.ndarray
    cavity_facets: np.ndarray
    cavity_tk: np.ndarray  # T_c ks_c at q
    cavity_active: np.ndarray  # H of each cavity connection's facet
    cavity_g: np.ndarray  # d(T_c ks_c)/dq (p - p_c): the ks part of d flux / dq
    cavity_pressure: np.ndarray

    def cavity_outflow(self, new: np.ndarray) -> np.ndarray:
        """Linearised rate out of the network through every cavity connection at ``new``.

        With these rates the linear system conserves mass exactly: summing its
        rows cancels every inner pair.
        """
        idx = self.cavity_facets
        return self.cavity_tk * (self.cavity_active * new[idx] - self.cavity_pressure) + (
            self.cavity_g * (new[idx] - self.q[idx])
        )


def saturation(q: np.ndarray, kw: float) -> np.ndarray:
    """Saturation ``min(1, 1 + q / Kw)``, clipped at 0."""
    return np.clip(1.0 + q / kw, 0.0, 1.0)


def _ks_and_slope(mean: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    s = np.clip(mean, 0.0, 1.0)
    return relative_permeability(s), 6.0 * s * (1.0 - s)


def linearise(
    pairs: Pairs, q: np.ndarray, kw: float, cavity_pressure: np.ndarray, newton: bool = True
) -> Linearisation:
    """Newton matrix entries and load at ``q`` (``ks`` and the active set at ``q``).

    ``newton=False`` drops the derivative of ``ks`` (a Picard step on ``ks``).
    """
    a, b, c = pairs.a, pairs.b, pairs.c
    active = (q > 0.0).astype(float)
    p = np.maximum(q, 0.0)
    s = saturation(q, kw)
    # dS/dq, zero where S is clipped
    ds = np.where((q < 0.0) & (q > -kw), 1.0 / kw, 0.0) if newton else np.zeros_like(q)
    ks, dks = _ks_and_slope(0.5 * (s[a] + s[b]))
    tk = pairs.t * ks
    drop = p[a] - p[b]
    ga = pairs.t * dks * 0.5 * ds[a] * drop
    gb = pairs.t * dks * 0.5 * ds[b] * drop
    kc, dkc = _ks_and_slope(0.5 * (s[c] + 1.0))
    tkc = pairs.tc * kc
    gc = pairs.tc * dkc * 0.5 * ds[c] * (p[c] - cavity_pressure)
    values = np.concatenate(
        [
            tk * active[a] + ga,
            tk * active[b] - gb,
            -(tk * active[b]) + gb,
            -(tk * active[a]) - ga,
            tkc * active[c] + gc,
            np.zeros(pairs.size),
        ]
    )
    load = np.zeros(pairs.size)
    np.add.at(load, c, tkc * cavity_pressure)
    cq = ga * q[a] + gb * q[b]
    np.add.at(load, a, cq)
    np.add.at(load, b, -cq)
    np.add.at(load, c, gc * q[c])
    return Linearisation(q.copy(), values, load, c, tkc, active[c], gc, cavity_pressure)


def residual(
    pairs: Pairs,
    q: np.ndarray,
    old: np.ndarray,
    storage_rate: np.ndarray,
    kw: float,
    cavity_pressure: np.ndarray,
) -> np.ndarray:
    """Residual of the filling step at ``q`` (m^3/s per facet); ``storage_rate = V / (Kw dt)``."""
    a, b, c = pairs.a, pairs.b, pairs.c
    p = np.maximum(q, 0.0)
    s = saturation(q, kw)
    out = storage_rate * (q - old)
    flux = pairs.t * relative_permeability(0.5 * (s[a] + s[b])) * (p[a] - p[b])
    np.add.at(out, a, flux)
    np.add.at(out, b, -flux)
    kc = relative_permeability(0.5 * (s[c] + 1.0))
    np.add.at(out, c, pairs.tc * kc * (p[c] - cavity_pressure))
    return out


__all__ = ["Linearisation", "Pairs", "linearise", "residual", "saturation"]
