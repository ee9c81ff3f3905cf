"""Results on disk: JSON records, ParaView fields (XDMF) and pictures (PNG).

Files are written whole or not at all: each goes to a temporary name in the same
directory and is renamed into place, so an interrupted run never leaves a
truncated ``summary.json`` over a good one.
"""

from __future__ import annotations

import csv
import json
import math
import os
import tempfile
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import dolfinx
import numpy as np
from dolfinx.io import XDMFFile
from mpi4py import MPI

from hfcdem.mesh.tagged import TaggedMesh


class OutputDirError(OSError):
    """The output directory cannot be made or written (the message says why)."""


def prepare_output_dir(path: str | os.PathLike[str], comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Create ``path`` (on rank 0) and return it on every rank (:class:`OutputDirError`)."""
    out = Path(path)
    error = None
    if comm.rank == 0:
        try:
            if out.exists() and not out.is_dir():
                error = f"output {out} is a file, not a directory: give another -o"
            else:
                out.mkdir(parents=True, exist_ok=True)
                if not os.access(out, os.W_OK):
                    error = f"output directory {out} is not writable"
        except OSError as exc:
            error = f"cannot create output directory {out}: {exc.strerror or exc}"
    error = comm.bcast(error, root=0)
    if error:
        raise OutputDirError(error)
    return out


def to_builtin(value: Any, strict: bool = False) -> Any:
    """Return ``value`` as JSON-ready builtins (mappings, sequences, NumPy values, paths).

    ``strict``: non-finite floats become strings and any other object its repr,
    so the result is plain JSON whatever went in.
    """
    if isinstance(value, Mapping):
        return {str(k): to_builtin(v, strict) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_builtin(v, strict) for v in value]
    if isinstance(value, np.ndarray):
        return to_builtin(value.tolist(), strict)
    if isinstance(value, np.generic):
        return to_builtin(value.item(), strict)
    if isinstance(value, Path):
        return str(value)
    if strict:
        if isinstance(value, float) and not math.isfinite(value):
            return str(value)
        if not (value is None or isinstance(value, bool | int | float | str)):
            return repr(value)
    return value


def write_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename."""
    target = Path(path)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it is renamed to ``path``.

    For writers that take a file name (``fig.savefig(tmp, format="png")``).
    """
    target = Path(path)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.")
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_json(
    path: str | os.PathLike[str], data: Mapping[str, Any], comm: MPI.Comm = MPI.COMM_WORLD
) -> None:
    """Write ``data`` as indented JSON from rank 0 (atomically)."""
    if comm.rank == 0:
        write_atomic(path, json.dumps(to_builtin(data), indent=2, allow_nan=True) + "\n")
    comm.barrier()


def read_json(path: str | os.PathLike[str], comm: MPI.Comm = MPI.COMM_WORLD) -> Any:
    """Return the JSON in ``path`` read on rank 0, on every rank (None: no such file).

    A file that cannot be read or parsed raises ValueError on every rank, so
    that no rank waits for one that failed.
    """
    data, problem = None, None
    if comm.rank == 0 and os.path.exists(path):
        try:
            with open(path) as fh:
                data = json.load(fh)
        except (OSError, json.JSONDecodeError) as exc:
            problem = f"{path} cannot be read: {exc}"
    data, problem = comm.bcast((data, problem), root=0)
    if problem is not None:
        raise ValueError(problem)
    return data


def write_csv(
    path: str | os.PathLike[str],
    header: Sequence[str],
    rows: Iterable[Sequence[float]],
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> None:
    """Write a small CSV table from rank 0 (atomically)."""
    if comm.rank == 0:
        lines = [",".join(header)] + [",".join(f"{v:.10g}" for v in row) for row in rows]
        write_atomic(path, "\n".join(lines) + "\n")
    comm.barrier()


def write_fields(
    path: str | os.PathLike[str], tmesh: TaggedMesh, functions: Sequence[dolfinx.fem.Function]
) -> Path:
    """Write the mesh, its facet tags and ``functions`` to one XDMF file for ParaView.

    Functions must be first-order Lagrange or cell-wise constant (DG0).
    """
    target = Path(path).with_suffix(".xdmf")
    with XDMFFile(tmesh.comm, target, "w") as xdmf:
        xdmf.write_mesh(tmesh.mesh)
        tmesh.mesh.topology.create_connectivity(
            tmesh.mesh.topology.dim - 1, tmesh.mesh.topology.dim
        )
        xdmf.write_meshtags(tmesh.facet_tags, tmesh.mesh.geometry)
        for f in functions:
            xdmf.write_function(f)
    return target


def write_vtx(
    path: str | os.PathLike[str], functions: Sequence[dolfinx.fem.Function], t: float = 0.0
) -> Path:
    """Write ``functions`` (same element) to an ADIOS2 VTX folder that ParaView opens."""
    target = Path(path).with_suffix(".bp")
    writer = dolfinx.io.VTXWriter(
        functions[0].function_space.mesh.comm, target, list(functions), engine="BP4"
    )
    writer.write(t)
    writer.close()
    return target


def write_interfaces(
    path: str | os.PathLike[str],
    points: np.ndarray,
    cell_data: Mapping[str, np.ndarray],
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> Path:
    """Write interface facets (one segment or triangle per facet) with data as VTU.

    Each rank passes its owned facets: ``points`` (F, nv, 3) vertex coordinates,
    ``cell_data`` arrays of length F; rank 0 gathers and writes.
    """
    import meshio

    target = Path(path).with_suffix(".vtu")
    parts = comm.gather((points, {k: np.asarray(v) for k, v in cell_data.items()}), root=0)
    if comm.rank == 0:
        assert parts is not None
        pts = np.concatenate([p.reshape(-1, 3) for p, _ in parts]) if parts else np.zeros((0, 3))
        nv = points.shape[1] if points.ndim == 3 else 2
        conn = np.arange(len(pts)).reshape(-1, nv)
        data = {k: [np.concatenate([d[k] for _, d in parts])] for k in cell_data}
        kind = "line" if nv == 2 else "triangle"
        tmp = target.with_name(f".{target.name}.tmp.vtu")
        meshio.write(str(tmp), meshio.Mesh(pts, [(kind, conn)], cell_data=data))
        os.replace(tmp, target)
    comm.barrier()
    return target


def write_solid_results(out: Path, solid: Any, loads: Any, t: float = 0.0) -> dict[str, Path]:
    """Fields (``fields.bp``) and interfaces (``interfaces.vtu``) of a :class:`CDEMSolid`.

    Fields: displacement, sigma_xx, sigma_yy (MPa, tension positive) as DG1.
    Interfaces: failure state (0 intact, 1 tensile, 2 shear), opening (m),
    normal and shear traction (MPa) per facet of the fracturable zone and cracks.
    """
    from hfcdem.io.sampling import interpolate_expression

    mesh, gdim = solid.mesh, solid.gdim
    u1 = interpolate_expression(solid.u, mesh, ("DG", 1, (gdim,)), "displacement")
    sigma = solid.total_stress()
    fields = [u1]
    for name, (i, j) in (("sigma_xx", (0, 0)), ("sigma_yy", (1, 1)), ("sigma_xy", (0, 1))):
        fields.append(interpolate_expression(sigma[i, j] / 1e6, mesh, ("DG", 1), name))
    paths = {"fields": write_vtx(out / "fields", fields, t)}
    snap = solid.snapshot(loads)
    own = solid.owned
    paths["interfaces"] = write_interfaces(
        out / "interfaces",
        solid.vertex_coords[own],
        {
            "state": solid.state[own].astype(np.int32),
            "pre_existing": solid.is_crack[own].astype(np.int32),
            "debris_face": solid.released[own].astype(np.int32),
            "opening": snap.opening[own],
            "normal_traction_MPa": snap.normal_traction[own] / 1e6,
            "shear_traction_MPa": snap.shear_traction[own] / 1e6,
        },
        solid.comm,
    )
    return paths


@dataclass(frozen=True)
class Results:
    """What a finished (or stopped) run left in its output directory.

    ``summary``: ``summary.json`` as a dict; ``history``: the columns of
    ``history.csv`` as float arrays (empty for a static run).
    """

    directory: Path
    summary: dict[str, Any]
    history: dict[str, np.ndarray]


def read_results(path: str | os.PathLike[str]) -> Results:
    """Read ``summary.json`` and ``history.csv`` of a run directory (any rank)."""
    out = Path(path)
    summary_file = out / "summary.json"
    if not summary_file.exists():
        raise FileNotFoundError(
            f"{out}: no summary.json (not a run directory, or the run has not finished)"
        )
    summary = json.loads(summary_file.read_text())
    history: dict[str, np.ndarray] = {}
    history_file = out / "history.csv"
    if history_file.exists():
        with history_file.open(newline="") as fh:
            rows = list(csv.reader(fh))
        if rows:
            columns = list(zip(*rows[1:], strict=True)) if len(rows) > 1 else [()] * len(rows[0])
            history = {
                name: np.array([float(v) for v in col])
                for name, col in zip(rows[0], columns, strict=True)
            }
    return Results(out, summary, history)


__all__ = [
    "OutputDirError",
    "Results",
    "atomic_path",
    "prepare_output_dir",
    "read_json",
    "read_results",
    "write_atomic",
    "write_csv",
    "write_fields",
    "write_interfaces",
    "write_json",
    "write_solid_results",
    "write_vtx",
]
