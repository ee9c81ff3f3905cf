"""Breakdown: the peak injection pressure before a sustained drop.

Criterion (causal, so it can run while the simulation steps): follow the running
maximum of the injection pressure; breakdown is declared once the pressure has
stayed below that maximum by at least ``drop_fraction`` of the rise
``max - p_start`` for ``hold`` consecutive records (a sustained drop).  The
breakdown pressure is that running maximum and its time the time of the peak.
A history that never drops that far for that long has no breakdown (the
pressure is still rising, or only wobbles).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Breakdown:
    """Peak pressure (Pa) and its time (s), and when the drop confirmed it."""

    pressure: float
    time: float
    confirmed_at: float


def detect_breakdown(
    times: Sequence[float],
    pressures: Sequence[float],
    drop_fraction: float = 0.05,
    hold: int = 3,
) -> Breakdown | None:
    """Return the breakdown of a pressure history, or None (see the module docstring)."""
    if not 0.0 < drop_fraction < 1.0:
        raise ValueError(f"drop_fraction must be in (0, 1), got {drop_fraction!r}")
    t = np.asarray(times, dtype=float)
    p = np.asarray(pressures, dtype=float)
    if t.shape != p.shape:
        raise ValueError("times and pressures must have the same length")
    if len(p) < 2:
        return None
    if hold < 1:
        raise ValueError(f"hold must be >= 1 record, got {hold!r}")
    start = p[0]
    peak, peak_time = p[0], t[0]
    below = 0
    for ti, pi in zip(t[1:], p[1:], strict=True):
        if pi > peak:
            peak, peak_time, below = pi, ti, 0
            continue
        rise = peak - start
        below = below + 1 if rise > 0.0 and peak - pi >= drop_fraction * rise else 0
        if below >= hold:
            return Breakdown(pressure=float(peak), time=float(peak_time), confirmed_at=float(ti))
    return None


__all__ = [
    "Breakdown",
    "detect_breakdown",
]
