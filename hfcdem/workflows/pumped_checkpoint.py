"""``checkpoint.json`` of a pumped seepage run, and the stopped run ``--resume`` goes on from.

A pumped run at the default mesh takes hours; one stopped from outside
(Ctrl-C, a batch system's wall-time limit) goes on from its last checkpoint
instead of from the start.  The checkpoint holds the state after a step
(:meth:`hfcdem.coupling.pumping._PumpedCavity.checkpoint`: interface states
and the joints' fluid keyed by global vertex ids, so it resumes on any number
of ranks), plus the mesh fingerprint and the stress measured at the first
break; the step rows stay in ``history.csv`` and ``step_costs.csv``.

It is written after a step only once the wall time since the last one is
:data:`SPACING` times what writing the last one took, so checkpoints cost at
most about a tenth of the run (a step of the default mesh's cascade takes a
minute, a step of the coarse borehole milliseconds).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from mpi4py import MPI

from hfcdem.config.tables import SceneError
from hfcdem.coupling.pumping import COST_COLUMNS, Resume
from hfcdem.io.files import to_builtin, write_atomic
from hfcdem.io.history import HistoryFile
from hfcdem.workflows.observers import read_checkpoint

#: what the checkpoint says it is: a hydraulic-fracture run's checkpoint has no ``kind``
KIND = "seepage_pumping"

#: a checkpoint is written once the wall time since the last is this many times its cost
SPACING = 10.0


class CheckpointFile:
    """Write a pumped run's checkpoint after a step when it is due (collective).

    ``mesh``: the mesh fingerprint a resume must match; ``extra``: entries of
    the workflow's own, read when written (the first break's stress);
    ``earlier_wall``: the wall time of the sessions before this one (s), to
    which each checkpoint adds this one's so far (``wall_s``).
    """

    def __init__(
        self,
        path: Path,
        mesh: str,
        extra: Mapping[str, Any],
        comm: MPI.Comm,
        earlier_wall: float = 0.0,
    ) -> None:
        self.path, self.mesh, self.extra, self.comm = path, mesh, extra, comm
        self.earlier_wall, self._began = earlier_wall, time.perf_counter()
        self._last = -math.inf  # wall clock of the last write's end (rank 0)
        self._cost = 0.0  # what the last write took (s)
        self.written = 0

    def offer(self, build: Callable[[], dict[str, Any]]) -> None:
        """Write ``build()`` if due: the first offer, then after :data:`SPACING` write costs."""
        due = None
        if self.comm.rank == 0:
            due = time.perf_counter() - self._last >= SPACING * self._cost
        if not self.comm.bcast(due, root=0):
            return
        start = time.perf_counter()
        data = build() | {
            "kind": KIND,
            "mesh": self.mesh,
            "workflow": dict(self.extra),
            "wall_s": self.earlier_wall + (start - self._began),
        }
        if self.comm.rank == 0:  # compact: the joints' arrays hold tens of thousands of values
            write_atomic(self.path, json.dumps(to_builtin(data), allow_nan=True) + "\n")
        self.comm.barrier()
        self._last = time.perf_counter()
        self._cost = self._last - start
        self.written += 1


def _exists(path: Path, comm: MPI.Comm) -> bool:
    return bool(comm.bcast(path.exists() if comm.rank == 0 else None, root=0))


def earlier_run(
    out: Path,
    mesh: str,
    history_columns: tuple[str, ...],
    say: Callable[[str], None],
    comm: MPI.Comm,
) -> Resume | None:
    """Return the stopped run in ``out`` to go on from (None: nothing to resume; collective).

    Raises :class:`SceneError` for another run's or another mesh's checkpoint,
    and for step files shorter than the checkpoint; nothing is written.
    """
    path = out / "checkpoint.json"
    data = read_checkpoint(out, say, comm)
    if data is None:
        return None
    if not isinstance(data, dict) or data.get("kind") != KIND:
        raise SceneError(
            "",
            f"{path} is not a pumped seepage run's checkpoint: resume the scene that wrote it, "
            "or start again with --force",
        )
    if data.get("mesh") != mesh:
        raise SceneError(
            "",
            f"{path} was written on another mesh (fingerprint {data.get('mesh')}, now {mesh}): "
            "resume with the scene, resolution and --set values of the stopped run, or start "
            "again with --force",
        )
    steps = int(data["steps"])
    rows: dict[str, list[tuple[float, ...]]] = {}
    for name, columns in (("history.csv", history_columns), ("step_costs.csv", COST_COLUMNS)):
        file = out / name
        read = HistoryFile(file, (), comm).read(limit=steps) if _exists(file, comm) else []
        if len(read) < steps:
            raise SceneError("", f"{file} holds {len(read)} steps, the checkpoint {steps}")
        rows[name] = [tuple(row[c] for c in columns) for row in read]
    say(f"resumed at t = {float(data['t']):.6g} s ({steps} steps done)")
    return Resume(data, rows["history.csv"], rows["step_costs.csv"])


__all__ = ["KIND", "SPACING", "CheckpointFile", "earlier_run"]
