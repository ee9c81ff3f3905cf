"""Results on disk: JSON records, ParaView fields (XDMF) and pictures (PNG).

Files are written whole or not at all: each goes to a temporary name in the same
directory and is renamed into place, so an interrupted run never leaves a
truncated ``summary.json`` over a good one.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import dolfinx
import numpy as np
from dolfinx.io import XDMFFile
from mpi4py import MPI

from hfcdem.meshing import TaggedMesh


def prepare_output_dir(path: str | os.PathLike[str], comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Create ``path`` (on rank 0) and return it on every rank."""
    out = Path(path)
    error = None
    if comm.rank == 0:
        try:
            out.mkdir(parents=True, exist_ok=True)
            if not os.access(out, os.W_OK):
                error = f"output directory {out} is not writable"
        except OSError as exc:
            error = f"cannot create output directory {out}: {exc}"
    error = comm.bcast(error, root=0)
    if error:
        raise OSError(error)
    return out


def _to_builtin(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _to_builtin(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_to_builtin(v) for v in value]
    if isinstance(value, np.ndarray):
        return _to_builtin(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
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


def write_json(
    path: str | os.PathLike[str], data: Mapping[str, Any], comm: MPI.Comm = MPI.COMM_WORLD
) -> None:
    """Write ``data`` as indented JSON from rank 0 (atomically)."""
    if comm.rank == 0:
        write_atomic(path, json.dumps(_to_builtin(data), indent=2, allow_nan=True) + "\n")
    comm.barrier()


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
