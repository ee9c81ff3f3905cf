"""When a long loop of steps says where it is.

A loop that prints every tenth of its steps goes quiet for minutes when its
steps are many and slow (a seepage ramp with a small ``pressure_step``); one
that printed every step would flood a short run.  :class:`Cadence` does both:
every ``1 / parts`` of the steps, and whenever ``seconds`` of wall time have passed
since the last line.  :class:`TimeLeft` says how long the run has left, at its
recent pace rather than its mean one (a cascade of breaks is slow).
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import Any

from mpi4py import MPI


def printer(comm: Any) -> Callable[..., None]:
    """Return ``say(msg, err=False)``: print from rank 0 only (stderr for errors), flushed."""

    def say(msg: str, err: bool = False) -> None:
        if comm.rank == 0:
            print(msg, file=sys.stderr if err else sys.stdout, flush=True)

    return say


class Cadence:
    """Tell a loop of ``steps`` steps when a progress line is due (collective).

    The clock is rank 0's, sent to the others, so that every rank agrees (a
    line may need a collective reduction to write).
    """

    def __init__(self, steps: int, comm: MPI.Comm, parts: int = 10, seconds: float = 30.0) -> None:
        """Space lines ``steps // parts`` steps or ``seconds`` of wall time apart."""
        if not (parts >= 1 and seconds > 0.0):
            raise ValueError(f"parts must be >= 1 and seconds > 0, got {parts}, {seconds}")
        self.every = max(1, steps // parts)
        self.seconds = seconds
        self.comm = comm
        self._last = time.monotonic()

    def due(self, n: int, event: bool = False) -> bool:
        """Return whether step ``n`` (from 1) gets a line; ``event``: it does anyway."""
        late = None
        if self.comm.rank == 0:
            late = time.monotonic() - self._last >= self.seconds
        late = self.comm.bcast(late, root=0)
        if event or late or n % self.every == 0:
            self._last = time.monotonic()
            return True
        return False


def duration_words(seconds: float) -> str:
    """Say a wall time as people read it: ``"42 s"``, ``"12 min"``, ``"3.4 h"``, or ``"?"``."""
    if not math.isfinite(seconds) or seconds < 0.0:
        return "?"
    if seconds < 90.0:
        return f"{seconds:.0f} s"
    if seconds < 90.0 * 60.0:
        return f"{seconds / 60.0:.0f} min"
    return f"{seconds / 3600.0:.1f} h"


class TimeLeft:
    """The wall time a stepped run has left, at its recent pace.

    The pace since the start understates a run that slows down, and a cascade of
    breaks costs tens of times a quiet step: No. 2 on the seepage rung at the
    default mesh had run 35.6 simulated s in 203 s of wall time when its cascade
    began, so the mean pace said 14 s were left for the last 2.4 s, which took
    238 s.  So the pace is taken over the last ``recent`` share of the wall time
    spent (at least the last step): the stretch that best tells the next one.
    """

    def __init__(self, t_end: float, t_start: float = 0.0, recent: float = 0.25) -> None:
        """Estimate for a run from ``t_start`` to ``t_end`` (simulated s), its clock at 0."""
        if not 0.0 < recent <= 1.0:
            raise ValueError(f"recent must be a share in (0, 1], got {recent}")
        self.t_end = t_end
        self.recent = recent
        self._samples: list[tuple[float, float]] = [(t_start, 0.0)]  # (simulated t, wall s)

    def add(self, t: float, wall: float) -> None:
        """Note that the run reached ``t`` after ``wall`` seconds of wall time."""
        self._samples.append((t, wall))
        cutoff = wall * (1.0 - self.recent)
        # keep the last sample at or before the cutoff (the window's start) and the later ones
        while len(self._samples) > 2 and self._samples[1][1] <= cutoff:
            self._samples.pop(0)

    def seconds(self) -> float:
        """Return the wall time left at the recent pace (s); nan before the run moved."""
        (t0, w0), (t1, w1) = self._samples[0], self._samples[-1]
        if not t1 > t0:
            return math.nan
        return (w1 - w0) / (t1 - t0) * max(self.t_end - t1, 0.0)

    def words(self) -> str:
        """Say the wall time spent and left: ``"wall 203 s, about 2 min left at the ..."``."""
        wall = self._samples[-1][1]
        return f"wall {wall:.0f} s, about {duration_words(self.seconds())} left at the recent pace"


__all__ = ["Cadence", "TimeLeft", "duration_words", "printer"]
