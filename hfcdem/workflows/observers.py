"""Observers of a run: each step record goes to whoever wants it.

:func:`hfcdem.workflows.run.run_scene` steps the fracture and hands every
:class:`~hfcdem.coupling.hydrofrac.StepRecord` to its observers, in order: the
history file, the first-crack locator, the checkpoint, the field frames, the
progress line, and any the caller adds (a test that stops a run after a given
time is one).  Observers are called on every rank; those that write files
write from rank 0.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from hfcdem.config.tables import SceneError
from hfcdem.coupling.hydrofrac import HydraulicFracture, StepRecord
from hfcdem.io.files import read_json, write_json
from hfcdem.io.history import HistoryFile
from hfcdem.io.progress import TimeLeft
from hfcdem.io.series import FieldSeries, output_times


class StepObserver:
    """Base class: override what you need (every method is called on every rank)."""

    def start(self, frac: HydraulicFracture) -> None:
        """Before the first step (of this session: a resumed run has a history)."""

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """After each step."""

    def finish(self, frac: HydraulicFracture, stopped: str | None) -> None:
        """After the last step, or after a stop (``stopped`` names the cause)."""


class ProgressLine(StepObserver):
    """One line per step: time, pressure, broken interfaces, dt, wall time, time left."""

    def __init__(self, say: Callable[[str], None], t_end: float) -> None:
        self.say, self.t_end = say, t_end
        self.pace = TimeLeft(t_end)
        self.begun = 0.0

    def start(self, frac: HydraulicFracture) -> None:
        """Time this session from here (a resumed run, or one that settled first)."""
        self.pace = TimeLeft(self.t_end, frac.t)
        self.begun = frac.wall_time()

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """Print the step's line."""
        self.pace.add(rec.time, rec.wall_time - self.begun)
        self.say(rec.progress_line(self.pace.seconds()))


class HistoryWriter(StepObserver):
    """``history.csv``: written whole at the start, then one appended row per step."""

    def __init__(self, path: Path, comm: MPI.Comm) -> None:
        self.file = HistoryFile(path, list(StepRecord.__dataclass_fields__), comm)

    def start(self, frac: HydraulicFracture) -> None:
        """Write the header and the history a resumed run keeps."""
        self.file.start([r.as_row() for r in frac.history])

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """Append the step's row."""
        self.file.append(rec.as_row())


class FirstCrack(StepObserver):
    """Where the injection's first interfaces broke, located once they have (collective)."""

    def __init__(self, locate: Callable[[HydraulicFracture], dict[str, Any] | None]) -> None:
        self.locate = locate
        self.where: dict[str, Any] | None = None

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """Locate the first crack in the step it appears."""
        if self.where is None and frac.first_break_time is not None:
            self.where = self.locate(frac)


class CheckpointWriter(StepObserver):
    """``checkpoint.json`` after every step: the state to continue from, not the history.

    It holds the number of steps done (``history.csv`` has at least as many rows:
    the history is written first) and the mesh fingerprint, so a resume on
    another mesh is refused.
    """

    def __init__(self, path: Path, mesh: str, first: FirstCrack, comm: MPI.Comm) -> None:
        self.path, self.mesh, self.first, self.comm = path, mesh, first, comm

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """Write the state after the step."""
        data = frac.checkpoint() | {
            "steps": len(frac.history),
            "mesh": self.mesh,
            "first_crack": self.first.where,
        }
        write_json(self.path, data, self.comm)


def read_checkpoint(out: Path, say: Callable[[str], None], comm: MPI.Comm) -> Any:
    """Return ``out/checkpoint.json`` of a stopped run, the same on every rank (collective).

    None when there is none (``say`` tells the run starts from t = 0); a file
    that does not parse raises :class:`SceneError` on every rank.
    """
    try:
        data = read_json(out / "checkpoint.json", comm)
    except ValueError as exc:
        raise SceneError("", f"{exc}; start again with --force") from None
    if data is None:
        say("nothing to resume: no checkpoint.json; starting from t = 0")
    return data


class FrameWriter(StepObserver):
    """Fields over time at the output interval, and the state a stopped run ended in."""

    def __init__(self, series: FieldSeries, t_end: float, interval: float, fresh: bool) -> None:
        self.series, self.fresh = series, fresh
        self.t_end, self.interval = t_end, interval
        self.due = math.inf
        self._times: Any = iter(())

    def start(self, frac: HydraulicFracture) -> None:
        """Plan the output times; a fresh run writes its initial state."""
        self._times = iter(output_times(frac.t, self.t_end, self.interval))
        self.due = next(self._times, math.inf)
        if self.fresh:
            self.series.write(0.0)

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """Write a frame when an output time is reached."""
        if rec.time >= self.due * (1.0 - 1e-12):
            self.series.write(rec.time)
            while self.due <= rec.time * (1.0 + 1e-12):
                self.due = next(self._times, math.inf)

    def finish(self, frac: HydraulicFracture, stopped: str | None) -> None:
        """Write the state a stopped run ended in; close the series."""
        frames = self.series.frames
        if stopped is not None and frames and frames[-1][0] < frac.t:
            self.series.write(frac.t)
        self.series.close()


def mesh_fingerprint(tmesh: Any) -> str:
    """Return a hash of a mesh that is the same on any rank count.

    Global cell and vertex counts, the bounding box, the mean vertex position
    and the tag names.
    """
    mesh = tmesh.mesh
    comm = mesh.comm
    tdim = mesh.topology.dim
    owned = mesh.geometry.index_map().size_local
    x = mesh.geometry.x[:owned]
    gdim = x.shape[1]
    lo, hi, total = np.empty(gdim), np.empty(gdim), np.empty(gdim)
    # buffer reductions: element-wise over the coordinates
    comm.Allreduce(x.min(axis=0) if len(x) else np.full(gdim, np.inf), lo, op=MPI.MIN)
    comm.Allreduce(x.max(axis=0) if len(x) else np.full(gdim, -np.inf), hi, op=MPI.MAX)
    comm.Allreduce(x.sum(axis=0), total, op=MPI.SUM)
    vertices = mesh.geometry.index_map().size_global
    # the mean position in units of the extent, to 9 decimals: the order of the parallel
    # sum (1e-16 relative) does not reach them; + 0.0 turns -0.0 into 0.0
    extent = max(float(np.max(np.abs(lo))), float(np.max(np.abs(hi))), 1e-300)
    mean = np.round(np.asarray(total) / (vertices * extent), 9) + 0.0
    text = repr(
        (
            tdim,
            mesh.topology.index_map(tdim).size_global,
            vertices,
            [f"{v:.12g}" for v in (*lo, *hi)],
            [f"{v:.9f}" for v in mean],
            sorted(tmesh.cell_names),
            sorted(tmesh.facet_names),
        )
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]


__all__ = [
    "CheckpointWriter",
    "FirstCrack",
    "FrameWriter",
    "HistoryWriter",
    "ProgressLine",
    "StepObserver",
    "mesh_fingerprint",
    "read_checkpoint",
]
