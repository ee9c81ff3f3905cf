"""``history.csv``: one row per time step, appended as the run goes.

The file is written whole once (header, and the rows a resumed run keeps) and
then grows by one line per step, so writing it costs the same at step 10 and
at step 10,000.  Values are written in full precision (shortest round-trip
form), so a resumed run reads back exactly what it wrote.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from mpi4py import MPI

from hfcdem.io.files import write_atomic


def _line(values: Sequence[float]) -> str:
    return ",".join(repr(float(v)) for v in values) + "\n"


class HistoryFile:
    """Append-only CSV of step records, written by rank 0 of ``comm``."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        columns: Sequence[str],
        comm: MPI.Comm = MPI.COMM_WORLD,
    ) -> None:
        self.path = Path(path)
        self.columns = tuple(columns)
        self.comm = comm

    def start(self, rows: Sequence[Mapping[str, float]] = ()) -> None:
        """Write the header and ``rows`` (a resumed run's history), replacing the file."""
        if self.comm.rank == 0:
            text = ",".join(self.columns) + "\n"
            text += "".join(_line([row[c] for c in self.columns]) for row in rows)
            write_atomic(self.path, text)
        self.comm.barrier()

    def append(self, row: Mapping[str, float]) -> None:
        """Add one row at the end of the file (rank 0; no collective call)."""
        if self.comm.rank == 0:
            with self.path.open("a") as fh:
                fh.write(_line([row[c] for c in self.columns]))

    def read(self, limit: int | None = None) -> list[dict[str, float]]:
        """Return the rows on disk (the first ``limit``), read on rank 0, on every rank."""
        rows = None
        if self.comm.rank == 0:
            with self.path.open(newline="") as fh:
                reader = csv.reader(fh)
                header = next(reader)
                rows = [dict(zip(header, map(float, r), strict=True)) for r in reader if r]
            rows = rows if limit is None else rows[:limit]
        return self.comm.bcast(rows, root=0)


__all__ = ["HistoryFile"]
