"""Breakdown: the peak injection pressure before a sustained drop.

Criterion (causal, so it can run while the simulation steps): follow the running
maximum of the injection pressure; breakdown is declared the first time the
pressure has fallen below that maximum by ``drop_fraction`` of the rise
``max - p_start``.  The breakdown pressure is the running maximum at that moment
and its time the time of the peak.  A history that never drops that far has no
breakdown (the pressure is still rising, or only wobbles).
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
    times: Sequence[float], pressures: Sequence[float], drop_fraction: float = 0.05
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
    start = p[0]
    peak, peak_time = p[0], t[0]
    for ti, pi in zip(t[1:], p[1:], strict=True):
        if pi > peak:
            peak, peak_time = pi, ti
            continue
        rise = peak - start
        if rise > 0.0 and peak - pi >= drop_fraction * rise:
            return Breakdown(pressure=float(peak), time=float(peak_time), confirmed_at=float(ti))
    return None
