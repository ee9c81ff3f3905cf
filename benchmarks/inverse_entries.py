"""What the low-rank correction's pieces cost on the No. 2 solid: entries of K^-1 against columns.

An interface event needs ``K0^-1`` on the changed unknowns only
(:mod:`hfcdem.solid.lowrank`).  For a growing cluster of neighbouring
interfaces (the facets nearest one of the zone, a crack's shape), this prints
the seconds MUMPS takes for the entries of ten more facets' unknowns at every
unknown held (:func:`hfcdem.solvers.inverse_entries`), against the seconds of
those unknowns' columns of ``K0^-1`` in full (:func:`columns_at_rows`,
what a correction held before 2026-12-07), with the largest difference
between the two; then what a corrected solve adds: one solve whose right-hand
side lives on the held unknowns, against a dense one.

    make run CMD="python3 benchmarks/inverse_entries.py default"
    make run CMD="mpirun -n 2 python3 benchmarks/inverse_entries.py coarse"
"""

from __future__ import annotations

import argparse
import time
from functools import partial
from pathlib import Path

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.scene import load_scene
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solvers import (
    DIRECT_CHOLESKY,
    columns_at_rows,
    create_ksp,
    inverse_entries,
    solve_columns,
    solve_sparse_columns,
)
from hfcdem.workflows.run import build_solid

comm = MPI.COMM_WORLD
SCENE = Path(__file__).resolve().parents[1] / "meshes/scenes/perforation_no2.toml"
say = print if comm.rank == 0 else (lambda *a, **k: None)


def timed(fn):  # type: ignore[no-untyped-def]
    """Return ``fn()`` and its seconds on the slowest rank."""
    comm.Barrier()
    t0 = time.perf_counter()
    out = fn()
    return out, comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)


def cluster(solid: CDEMSolid, count: int) -> np.ndarray:
    """Midpoints of the ``count`` zone interfaces nearest the first one (all ranks)."""
    mids = np.concatenate(comm.allgather(solid.midpoints[solid.owned]))
    order = np.lexsort(mids.T[::-1])
    first = mids[order[0]]
    return mids[np.argsort(np.linalg.norm(mids - first, axis=1), kind="stable")[:count]]


def unknowns(solid: CDEMSolid, points: np.ndarray) -> np.ndarray:
    """Global unknowns of both cells of the local facets whose midpoints are ``points``."""
    index = {tuple(np.round(p, 12)): k for k, p in enumerate(solid.midpoints)}
    V, bs = solid.V, solid.V.dofmap.bs
    imap = V.dofmap.index_map
    found = []
    for p in points:
        f = index.get(tuple(np.round(p, 12)))
        if f is None or not solid.owned[f]:
            continue
        for c in solid.cells[f]:
            blocks = imap.local_to_global(V.dofmap.cell_dofs(int(c)).astype(np.int32))
            found.append((blocks[:, None] * bs + np.arange(bs)).ravel())
    mine = np.concatenate(found) if found else np.zeros(0, dtype=np.int64)
    return np.unique(np.concatenate(comm.allgather(mine))).astype(np.int64)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("resolution", help="coarse, default or paper")
    parser.add_argument("--held", type=int, nargs="+", default=[0, 100, 400, 1000])
    args = parser.parse_args()
    scene = load_scene(SCENE, None if args.resolution == "default" else args.resolution)
    solid = build_solid(scene, create_scene_mesh(scene, comm).tmesh)
    _, A = solid.assemble_stiffness()
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = create_ksp(A, "bench_inverse_", DIRECT_CHOLESKY, comm)
    _, t_factor = timed(ksp.setUp)
    n = A.getSize()[0]
    say(f"{args.resolution}: {n} unknowns, {comm.size} rank(s); factorised in {t_factor:.1f} s")
    points = cluster(solid, max(args.held) + 10)
    say(
        "\n| facets held | unknowns held | 10 more facets' new unknowns | entries of K^-1 s "
        "| their columns in full s | largest difference |\n|---|---|---|---|---|---|"
    )
    for held in args.held:
        old = unknowns(solid, points[:held]) if held else np.zeros(0, dtype=np.int64)
        new = np.setdiff1d(unknowns(solid, points[held : held + 10]), old)
        rows = np.concatenate([old, new])
        block, t_entries = timed(partial(inverse_entries, ksp, rows, new))
        full, t_columns = timed(partial(columns_at_rows, ksp, rows, new))
        gap = float(np.abs(block - full).max() / np.abs(full).max())
        say(f"| {held} | {len(old)} | {len(new)} | {t_entries:.3f} | {t_columns:.3f} | {gap:.1e} |")
    say("\n| right-hand side on | unknowns | sparse solve s | dense solve s |\n|---|---|---|---|")
    rng = np.random.default_rng(0)
    lo, hi = A.getOwnershipRange()
    for held in args.held[1:]:
        rows = unknowns(solid, points[:held])
        values = comm.bcast(rng.standard_normal((len(rows), 1)))
        _, t_sparse = timed(partial(solve_sparse_columns, ksp, rows, values))
        _, t_dense = timed(partial(solve_columns, ksp, np.ones((hi - lo, 1))))
        say(f"| {held} facets | {len(rows)} | {t_sparse:.3f} | {t_dense:.3f} |")


if __name__ == "__main__":
    main()
