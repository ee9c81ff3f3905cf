"""Breakdown: the peak injection pressure before a sustained drop.

Criterion: follow the running maximum of the injection pressure; a peak is
confirmed once the pressure has stayed below that maximum by at least
``drop_fraction`` of the rise ``max - p_start`` for ``hold`` consecutive records
(a sustained drop).  The breakdown is the highest confirmed peak: an earlier,
lower one that the pressure regains before a higher peak is confirmed is a local
event (the first facets at a stress concentration breaking and the cavity's
volume jumping, as in the Rubin case, where such a dip at 1.6 MPa precedes the
6.2 MPa breakdown), not the breakdown.  Where the pressure regains a confirmed
peak and no later peak is confirmed, the earlier one stays the breakdown; a run
that ended early (the model's validity limit, or a stop) then says that the
breakdown is at least its highest pressure (:func:`breakdown_note`), and one
that reached its planned end says nothing more.  A history that never drops
that far for that long has no breakdown (the pressure is still rising, or only
wobbles).  Nor has a history whose peak is
its first record after the start: the rise to it is not resolved, and a run
that starts from an open crack (KGD) only propagates, its pressure falling from
the first step on (:func:`breakdown_note` says which).

How deep the pressure falls after the breakdown (:attr:`Breakdown.drop`) says how
firm it is: a peak confirmed by a dip of about the threshold may move, or vanish,
when only the iteration order changes (No. 2's coarse seepage run with full joints:
a 1 % dip at 109 s; benchmarks/README.md, 2026-12-06), while a collapse of tens of
percent does not.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Breakdown:
    """Peak pressure (Pa) and its time (s), when the drop confirmed it, and its depth.

    ``drop``: how far (Pa) the pressure fell below the peak afterwards, at its
    lowest before it regained the peak or the history ended.
    """

    pressure: float
    time: float
    confirmed_at: float
    drop: float

    @property
    def relative_drop(self) -> float:
        """The drop as a share of the peak pressure (0 for a peak of zero)."""
        return self.drop / self.pressure if self.pressure else 0.0


def detect_breakdown(
    times: Sequence[float],
    pressures: Sequence[float],
    drop_fraction: float = 0.05,
    hold: int = 3,
    not_before: float = -math.inf,
) -> Breakdown | None:
    """Return the breakdown of a pressure history, or None (see the module docstring).

    ``not_before``: a drop confirms a peak only at records from this time on (s);
    a pumped run with seepage passes its first break's, since a fall while
    nothing has broken is the joints taking fluid, not a breakdown.
    """
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
    peak, peak_index = p[0], 0
    below = 0
    found: tuple[int, int] | None = None  # the peak's record and the confirming one
    for i in range(1, len(p)):
        if p[i] > peak:
            peak, peak_index, below = p[i], i, 0
            continue
        rise = peak - start
        below = below + 1 if rise > 0.0 and peak - p[i] >= drop_fraction * rise else 0
        # a peak on the first record is not confirmed: the rise to it is not resolved
        confirms = below >= hold and peak_index > 1 and t[i] >= not_before
        if confirms and (found is None or p[found[0]] < peak):
            found = (peak_index, i)
    if found is None:
        return None
    k, confirmed = found
    after = p[k + 1 :]
    regained = np.flatnonzero(after > p[k])
    after = after[: regained[0]] if regained.size else after
    return Breakdown(
        pressure=float(p[k]),
        time=float(t[k]),
        confirmed_at=float(t[confirmed]),
        drop=float(p[k] - after.min()),
    )


def peak_is_lower_bound(peak: float, breakdown: float | None, ended_early: bool) -> bool:
    """Whether a run's highest pressure ``peak`` only bounds its breakdown from below.

    So it is when the run ended before its planned end (``ended_early``: at the
    model's validity limit, or stopped) and no drop confirmed that peak: no
    breakdown was confirmed, or a lower one that the pressure then rose past
    (any unit, the same for both).
    """
    return ended_early and (breakdown is None or breakdown < peak * (1.0 - 1e-9))


def end_words(validity_limit: bool) -> str:
    """Say how a run ended early: at the model's validity limit, or stopped (every rung's words)."""
    return "the model's validity limit ended the run" if validity_limit else "the run stopped"


#: the note of a run that ended on its first crack (``injection.until = "first crack"``)
FIRST_CRACK_END = (
    'the run ended on its first crack (injection.until = "first crack"): no breakdown sought'
)


def breakdown_note(
    pressures: Sequence[float],
    found: Breakdown | None,
    open_crack: bool,
    validity_limit: bool = False,
    stopped: bool = False,
) -> str | None:
    """Say why a history has no breakdown, or why its breakdown is in doubt (else None).

    ``open_crack``: the run started from a pre-existing open crack.
    ``validity_limit``: the run ended at the model's validity limit, so its
    highest pressure is a lower bound of the breakdown, not a peak; so it is
    too when the run ``stopped`` (a solver's stop) before its planned end.
    """
    highest = float(np.max(pressures)) if len(pressures) else 0.0
    early = validity_limit or stopped
    cut_short = peak_is_lower_bound(highest, found.pressure if found else None, early)
    if found is not None:
        # a peak the pressure regains is no breakdown (module docstring); the stop kept
        # the later one from being confirmed
        return (
            f"the pressure rose past it before {end_words(validity_limit)}: "
            "the breakdown is at least the highest pressure"
            if cut_short
            else None
        )
    if cut_short:
        return (
            f"{end_words(validity_limit)} before a drop confirmed a peak: "
            "its highest pressure is a lower bound"
        )
    if len(pressures) < 3:
        return None
    p = np.asarray(pressures, dtype=float)
    if int(np.argmax(p)) == 1 and p[-1] < p[1]:
        if open_crack:
            return (
                "propagation from an open crack: the pressure falls from the first step, "
                "no breakdown peak"
            )
        return "the pressure is highest at the first step: the peak is not resolved in time"
    if int(np.argmax(p)) == len(p) - 1:
        return "the pressure still rises at the end of the run"
    return "no sustained drop after the peak"


__all__ = [
    "FIRST_CRACK_END",
    "Breakdown",
    "breakdown_note",
    "detect_breakdown",
    "end_words",
    "peak_is_lower_bound",
]
