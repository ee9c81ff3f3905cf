"""End a report run that stops making progress, instead of letting it hang.

A case that hangs (a rank waiting in a collective the other never reaches,
seen once under load) would hold the report for hours with no output.  The
watchdog hears every progress line; after ``limit_s`` seconds without one it
names the case, flushes and ends the process with :data:`EXIT_STALLED`, which
makes ``mpirun`` end every rank.  Cases already done keep their files: the
report resumes from them.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable

from hfcdem.workflows.exit_codes import ExitCode

#: exit status of a run the watchdog ended
EXIT_STALLED = ExitCode.STALLED


def _exit(message: str) -> None:
    print(message, file=sys.stderr, flush=True)
    sys.stdout.flush()
    os._exit(EXIT_STALLED)  # from a thread: sys.exit would end only the thread


class Watchdog:
    """A timer reset by :meth:`beat`; expiry calls ``on_expire(message)`` once.

    ``limit_s`` <= 0 disables it.  Use as a context manager around the run.
    """

    def __init__(
        self,
        limit_s: float,
        on_expire: Callable[[str], None] = _exit,
        poll_s: float | None = None,
    ) -> None:
        self.limit_s = float(limit_s)
        self.on_expire = on_expire
        self.poll_s = poll_s if poll_s is not None else min(30.0, max(self.limit_s / 4.0, 0.01))
        self.doing = ""  # what runs now, for the message
        self.expired = False
        self._last = time.monotonic()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def beat(self, doing: str | None = None) -> None:
        """Record progress (and, if given, what runs now)."""
        self._last = time.monotonic()
        if doing is not None:
            self.doing = doing

    def __enter__(self) -> Watchdog:
        if self.limit_s > 0.0:
            self._last = time.monotonic()
            self._thread = threading.Thread(target=self._watch, name="hfcdem-watchdog", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()

    def _watch(self) -> None:
        while not self._stop.wait(self.poll_s):
            quiet = time.monotonic() - self._last
            if quiet > self.limit_s:
                self.expired = True
                where = f" in {self.doing}" if self.doing else ""
                self.on_expire(
                    f"hfcdem reproduce: no progress for {quiet / 60:.1f} min{where} "
                    f"(limit {self.limit_s / 60:g} min, --watchdog); ending the run. Cases done "
                    "are kept: run the same command again to resume, or --only the others."
                )
                return


__all__ = ["EXIT_STALLED", "Watchdog"]
