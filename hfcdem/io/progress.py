"""When a long loop of steps says where it is.

A loop that prints every tenth of its steps goes quiet for minutes when its
steps are many and slow (a seepage ramp with a small ``pressure_step``); one
that printed every step would flood a short run.  :class:`Cadence` does both:
every ``1 / parts`` of the steps, and whenever ``seconds`` of wall time have passed
since the last line.
"""

from __future__ import annotations

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


__all__ = ["Cadence", "printer"]
