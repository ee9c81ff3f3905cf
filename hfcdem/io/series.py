"""Fields over time for ParaView: a VTX folder of solid fields and a PVD of interface frames.

``fields.bp`` holds the displacement and the normal stresses (MPa, tension
positive, DG1) at every output time; ``interfaces.pvd`` lists one VTU per
output time (``interfaces/frame_K.vtu``) with each interface's failure state,
opening, normal traction, fluid pressure, saturation and aperture.  ParaView
opens both as time series.  Frames are written atomically and the PVD is
rewritten after each, so a stopped run keeps every frame it wrote.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import dolfinx
import numpy as np

from hfcdem.io.files import write_atomic, write_interfaces


class FieldSeries:
    """Write the state of a :class:`~hfcdem.coupling.hydrofrac.HydraulicFracture` at chosen times.

    ``resume_from``: the simulated time a resumed run starts at; frames written
    before it are kept and the solid fields go to ``fields_resumed.bp``.
    """

    def __init__(self, out: Path, frac: Any, resume_from: float | None = None) -> None:
        solid = frac.solid
        mesh, gdim = solid.mesh, solid.gdim
        self.out, self.frac, self.comm = out, frac, mesh.comm
        vec = dolfinx.fem.functionspace(mesh, ("DG", 1, (gdim,)))
        scal = dolfinx.fem.functionspace(mesh, ("DG", 1))
        self.u = dolfinx.fem.Function(vec, name="displacement")
        self._u_expr = dolfinx.fem.Expression(solid.u, vec.element.interpolation_points())
        sigma = solid.total_stress()
        self.stresses = []
        for k, axis in enumerate("xyz"[:gdim]):
            f = dolfinx.fem.Function(scal, name=f"sigma_{axis}{axis}")
            expr = dolfinx.fem.Expression(sigma[k, k] / 1e6, scal.element.interpolation_points())
            self.stresses.append((f, expr))
        name = "fields.bp" if resume_from is None else "fields_resumed.bp"
        self.fields_path = out / name
        self._writer = dolfinx.io.VTXWriter(
            self.comm, self.fields_path, [self.u] + [f for f, _ in self.stresses], engine="BP4"
        )
        kept: list[tuple[float, str]] = []
        if resume_from is not None and self.comm.rank == 0:
            kept = [f for f in read_pvd(out / "interfaces.pvd") if f[0] <= resume_from]
        self._frames = PvdFrames(out, "interfaces", self.comm, self.comm.bcast(kept, root=0))

    @property
    def frames(self) -> list[tuple[float, str]]:
        """``(time, file)`` of the interface frames written (and kept from before a resume)."""
        return self._frames.frames

    def write(self, t: float) -> None:
        """Write the last accepted state at simulated time ``t`` (collective)."""
        loads = self.frac.current_loads()
        self.u.interpolate(self._u_expr)
        for f, expr in self.stresses:
            f.interpolate(expr)
        self._writer.write(t)
        self._frames.add(t, *self.frac.interface_fields(loads))

    def close(self) -> None:
        """Close the VTX writer (collective)."""
        self._writer.close()


class PvdFrames:
    """Interface frames ``DIR/STEM/frame_K.vtu`` listed in ``DIR/STEM.pvd`` (collective).

    Each frame is written atomically and the PVD rewritten after it, so a
    stopped run keeps its frames.  ``frames``: those of an earlier run to keep
    (a resumed run); without them an earlier run's frame files are removed.
    """

    def __init__(
        self, out: Path, stem: str, comm: Any, frames: list[tuple[float, str]] | None = None
    ) -> None:
        self.out, self.stem, self.comm = out, stem, comm
        self.frames: list[tuple[float, str]] = list(frames or [])
        if comm.rank == 0:
            (out / stem).mkdir(exist_ok=True)
            if frames is None:
                for stale in (out / stem).glob("frame_*.vtu"):  # an earlier run's (--force)
                    stale.unlink()
        comm.barrier()

    def add(self, t: float, points: np.ndarray, data: dict[str, np.ndarray]) -> None:
        """Write ``data`` on the interfaces ``points`` as the frame at ``t``."""
        name = f"{self.stem}/frame_{len(self.frames):04d}.vtu"
        write_interfaces(self.out / name, points, data, self.comm)
        self.frames.append((t, name))
        if self.comm.rank == 0:
            write_atomic(self.out / f"{self.stem}.pvd", pvd_text(self.frames))
        self.comm.barrier()


class InterfaceFrames:
    """Interface frames at output times: ``DIR/STEM/frame_K.vtu`` listed in ``DIR/STEM.pvd``.

    :meth:`offer` writes the first state offered and then the first at or
    after each time ``k * interval`` (and ``t_end``); each frame is written
    atomically and the PVD rewritten after it, so a stopped run keeps its
    frames.  ``resume_from``: the simulated time a resumed run starts at; the
    frames listed up to it are kept and the next is due at the next output
    time after it.  Collective.
    """

    def __init__(
        self,
        out: Path,
        stem: str,
        t_end: float,
        interval: float,
        comm: Any,
        resume_from: float | None = None,
    ) -> None:
        if not (interval > 0.0):
            raise ValueError(f"output interval must be a positive time (s), got {interval!r}")
        kept = None
        if resume_from is not None:
            listed = read_pvd(out / f"{stem}.pvd") if comm.rank == 0 else []
            kept = comm.bcast([f for f in listed if f[0] <= resume_from * (1.0 + 1e-12)], root=0)
        self._frames = PvdFrames(out, stem, comm, kept)
        self._times = iter(output_times(resume_from or 0.0, t_end, interval))
        self.due = 0.0 if resume_from is None else next(self._times, math.inf)

    @property
    def frames(self) -> list[tuple[float, str]]:
        """``(time, file)`` of the frames written."""
        return self._frames.frames

    def offer(self, t: float, points: np.ndarray, data: dict[str, np.ndarray]) -> bool:
        """Write ``data`` on the interfaces ``points`` at ``t`` if an output time is due."""
        if t < self.due * (1.0 - 1e-12):
            return False
        self._frames.add(t, points, data)
        while self.due <= t * (1.0 + 1e-12):
            self.due = next(self._times, math.inf)
        return True


def pvd_text(frames: list[tuple[float, str]]) -> str:
    rows = "\n".join(
        f'    <DataSet timestep="{t:.10g}" group="" part="0" file="{name}"/>' for t, name in frames
    )
    return (
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
        f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n"
    )


def read_pvd(path: Path) -> list[tuple[float, str]]:
    import re

    if not path.exists():
        return []
    pattern = re.compile(r'timestep="([^"]+)".*file="([^"]+)"')
    return [(float(m[1]), m[2]) for m in pattern.finditer(path.read_text())]


def read_facets(path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Centroids, sizes (areas; lengths in 2D) and cell data of the facets of one VTU file."""
    import meshio

    mesh = meshio.read(path)
    corners = mesh.points[mesh.cells[0].data]
    edge = corners[:, 1] - corners[:, 0]
    if corners.shape[1] == 3:
        size = 0.5 * np.linalg.norm(np.cross(edge, corners[:, 2] - corners[:, 0]), axis=1)
    else:
        size = np.linalg.norm(edge, axis=1)
    data = {k: np.asarray(v[0]) for k, v in mesh.cell_data.items()}
    return corners.mean(axis=1), size, data


def output_times(t_start: float, t_end: float, interval: float) -> np.ndarray:
    """Return the output times k * interval after ``t_start``, and ``t_end``.

    The grid starts at 0, so a resumed run keeps the times of an unbroken one.
    """
    first = int(np.floor(t_start / interval + 1e-9)) + 1
    last = int(np.floor(t_end / interval + 1e-9))
    times = interval * np.arange(first, last + 1, dtype=float)
    if not len(times) or times[-1] < t_end * (1 - 1e-12):
        times = np.append(times, t_end)
    return times


__all__ = [
    "FieldSeries",
    "InterfaceFrames",
    "PvdFrames",
    "output_times",
    "read_facets",
]
