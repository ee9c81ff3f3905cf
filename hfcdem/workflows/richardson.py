"""Richardson extrapolation: the discretisation error of an answer from a sequence of meshes.

An answer computed at element sizes h is modelled as f(h) = f* + C h^p.  Three
sizes h1 < h2 < h3 (any ratios) give the observed order p from

    (f2 - f1) / (f3 - f2) = (h2^p - h1^p) / (h3^p - h2^p),

solved numerically (the right side falls monotonically from infinity to 0 as p
runs over the reals), then f* = f1 - (f2 - f1) / (exp(p ln(h2/h1)) - 1), and
the estimated error of the finest answer is |f1 - f*|.

When the three finest answers are not monotone in h (the differences change
sign), or the differences grow as h falls (p <= 0), the model does not hold and
the estimate falls back to the difference of the two finest answers, saying so
in :attr:`Extrapolation.method`.  Two answers give only that difference; one
gives no estimate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

RICHARDSON = "richardson"
TWO_FINEST = "two-finest"
SPREAD = "spread"  # cases without a measure (solver names): the range of the answers
MAX_ORDER = 20.0  # orders beyond +-20 are not fitted (the answers barely move or jump)


@dataclass(frozen=True)
class Extrapolation:
    """The estimated discretisation error of one answer.

    ``finest``: the answer at the smallest h; ``limit``: the extrapolated
    answer at h = 0 (None when no order could be fitted); ``error``: the
    estimated error of ``finest`` (>= 0; NaN without two answers); ``order``:
    the observed order p (None unless fitted); ``method``: ``"richardson"``,
    or ``"two-finest: <why>"``, ``"spread: <why>"`` (the range of answers
    without a measure), or ``"none: <why>"``.
    """

    finest: float
    limit: float | None
    error: float
    order: float | None
    method: str
    cases: int

    def __post_init__(self) -> None:
        if not (math.isnan(self.error) or self.error >= 0.0):
            raise ValueError(f"error must be >= 0 or NaN, got {self.error!r}")
        if not self.method.startswith((RICHARDSON, TWO_FINEST, SPREAD, "none")):
            raise ValueError(f"unknown method {self.method!r}")

    @property
    def relative_error(self) -> float:
        """``error`` relative to the best answer (the limit when there is one)."""
        best = self.limit if self.limit is not None else self.finest
        return self.error / abs(best) if best else math.nan

    @property
    def extrapolated(self) -> bool:
        """Whether the Richardson model was fitted (else a fallback)."""
        return self.method == RICHARDSON


def _phi(x: float) -> float:
    """(exp(x) - 1) / x, 1 at x = 0 (no cancellation near 0)."""
    return math.expm1(x) / x if x != 0.0 else 1.0


def _log_ratio(p: float, a: float, b: float) -> float:
    """Return ln((h2^p - h1^p) / (h3^p - h2^p)); a = ln(h2/h1), b = ln(h3/h2), both > 0."""
    return -p * a + math.log(a * _phi(p * a)) - math.log(b * _phi(p * b))


def observed_order(h: Sequence[float], f: Sequence[float]) -> float | None:
    """Return the order p that fits f = f* + C h^p through three points, or None.

    ``h`` increasing (distinct, positive); None when the differences of ``f``
    change sign or one is zero (no such p), or p falls outside
    [-MAX_ORDER, MAX_ORDER].
    """
    from scipy.optimize import brentq

    h1, h2, h3 = (float(v) for v in h)
    f1, f2, f3 = (float(v) for v in f)
    if not 0.0 < h1 < h2 < h3:
        raise ValueError(f"h must be positive and increasing, got {list(h)}")
    d1, d2 = f2 - f1, f3 - f2
    if d1 * d2 <= 0.0:
        return None
    a, b = math.log(h2 / h1), math.log(h3 / h2)
    target = math.log(d1 / d2)
    bound = min(MAX_ORDER, 600.0 / max(a, b))  # keep exp(p a) finite

    def residual(p: float) -> float:
        return _log_ratio(p, a, b) - target

    lo, hi = residual(-bound), residual(bound)
    if lo * hi > 0.0:
        return None
    return float(brentq(residual, -bound, bound, xtol=1e-15, rtol=4 * np.finfo(float).eps))


def extrapolate(h: Sequence[float], f: Sequence[float]) -> Extrapolation:
    """Estimate the discretisation error of the answers ``f`` at sizes ``h``.

    Entries whose answer or size is not finite are left out (a case that found
    no breakdown); the three smallest sizes left are used (module docstring).
    """
    hs = np.asarray(h, dtype=float)
    fs = np.asarray(f, dtype=float)
    if hs.shape != fs.shape:
        raise ValueError("h and f must have the same length")
    keep = np.isfinite(hs) & np.isfinite(fs)
    hs, fs = hs[keep], fs[keep]
    order = np.argsort(hs)
    hs, fs = hs[order], fs[order]
    if np.any(hs <= 0.0) or np.any(np.diff(hs) == 0.0):
        raise ValueError(f"sizes must be positive and distinct, got {hs.tolist()}")
    n = len(hs)
    if n == 0:
        return Extrapolation(math.nan, None, math.nan, None, "none: no answers", 0)
    if n == 1:
        return Extrapolation(float(fs[0]), None, math.nan, None, "none: one answer", 1)
    f1, f2 = float(fs[0]), float(fs[1])
    two = abs(f2 - f1)
    if n == 2:
        return Extrapolation(f1, None, two, None, f"{TWO_FINEST}: two answers", 2)
    f3 = float(fs[2])
    if f1 == f2 == f3:
        return Extrapolation(f1, f1, 0.0, None, RICHARDSON, n)
    p = observed_order([float(v) for v in hs[:3]], [float(v) for v in fs[:3]])
    if p is None:
        why = "not monotone" if (f2 - f1) * (f3 - f2) <= 0.0 else "order out of range"
        return Extrapolation(f1, None, two, None, f"{TWO_FINEST}: {why}", n)
    if p <= 0.0:
        return Extrapolation(f1, None, two, p, f"{TWO_FINEST}: diverging (p = {p:.2f})", n)
    shift = (f2 - f1) / math.expm1(p * math.log(hs[1] / hs[0]))
    limit = f1 - shift
    return Extrapolation(f1, limit, abs(shift), p, RICHARDSON, n)


__all__ = [
    "MAX_ORDER",
    "RICHARDSON",
    "SPREAD",
    "TWO_FINEST",
    "Extrapolation",
    "extrapolate",
    "observed_order",
]
