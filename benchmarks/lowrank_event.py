"""Would a low-rank (Woodbury) update beat refactorising at an interface event?

An event changes the stiffness on the unknowns of a few facets only:
``K1 = K0 + E D E^T`` with ``E`` the r changed unknowns and ``D`` their r x r
block of the change.  With the old factor kept,

    K1^-1 b = y - Z (I + D S)^-1 D y_E,   y = K0^-1 b,  Z = K0^-1 E,  S = E^T Z,

so an event costs r solves with the old factor (one MUMPS solve with r
right-hand sides) and every later solve one back-substitution plus an n x r
product.  For the No. 2 solid (full DG) this prints, per event of ``--facets``
broken interfaces at the tunnel wall (accumulated: the Woodbury terms of all
events since the factorisation): r, the seconds of MUMPS's numeric
refactorisation on the kept pattern (what a run does now), of the r-column
solve, of one back-substitution and of one Woodbury solve, and the Woodbury
solution's relative difference from the refactorised one.

    make run CMD="python3 benchmarks/lowrank_event.py coarse --events 5 --facets 1"
"""

from __future__ import annotations

import argparse
import time

import dolfinx
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.scene import load_scene
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.cdem import Loads
from hfcdem.workflows.run import build_fracture, build_solid

comm = MPI.COMM_WORLD
SCENE = "meshes/scenes/perforation_no2.toml"


def say(msg: str) -> None:
    """Print on rank 0."""
    if comm.rank == 0:
        print(msg, flush=True)


def timed(fn):  # type: ignore[no-untyped-def]
    """Return ``fn()`` and the seconds it took on the slowest rank."""
    comm.Barrier()
    t0 = time.perf_counter()
    out = fn()
    return out, comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)


def changed_block(A1: PETSc.Mat, A0: PETSc.Mat) -> tuple[np.ndarray, np.ndarray]:
    """Global rows where ``A1 - A0`` is nonzero (sorted) and the dense block of the change there."""
    dK = A1.copy()
    dK.axpy(-1.0, A0, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    lo, hi = dK.getOwnershipRange()
    rows, cols, vals = [], [], []
    scale = A0.norm(PETSc.NormType.INFINITY)
    for i in range(lo, hi):
        c, v = dK.getRow(i)
        keep = np.abs(v) > 1e-14 * scale
        if keep.any():
            rows.append(np.full(int(keep.sum()), i))
            cols.append(c[keep])
            vals.append(v[keep])
    dK.destroy()
    trip = [np.concatenate(x) if x else np.zeros(0) for x in (rows, cols, vals)]
    allr, allc, allv = (np.concatenate(comm.allgather(t)) for t in trip)
    E = np.unique(np.concatenate([allr, allc])).astype(np.int64)
    pos = {int(g): k for k, g in enumerate(E)}
    D = np.zeros((len(E), len(E)))
    for i, j, v in zip(allr, allc, allv, strict=True):
        D[pos[int(i)], pos[int(j)]] += v
    return E, D


def columns_solve(factor: PETSc.Mat, A: PETSc.Mat, E: np.ndarray) -> np.ndarray:
    """``K0^-1 E`` by one MUMPS solve with ``len(E)`` right-hand sides: this rank's rows."""
    lo, hi = A.getOwnershipRange()
    r = len(E)
    B = PETSc.Mat().createDense(((hi - lo, None), (r, r)), comm=A.comm)
    B.setUp()
    arr = B.getDenseArray()
    arr[:] = 0.0
    for k, g in enumerate(E):
        if lo <= g < hi:
            arr[g - lo, k] = 1.0
    B.assemble()
    X = B.duplicate()
    factor.matSolve(B, X)
    out = X.getDenseArray().copy()
    B.destroy()
    X.destroy()
    return out


def rows_of(local: np.ndarray, lo: int, E: np.ndarray) -> np.ndarray:
    """The rows ``E`` of a distributed array whose local block starts at ``lo`` (all ranks)."""
    mine = (E >= lo) & (E < lo + local.shape[0])
    part = np.zeros((len(E), *local.shape[1:]))
    part[mine] = local[E[mine] - lo]
    return comm.allreduce(part, op=MPI.SUM)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("resolution", help="coarse, default or paper")
    parser.add_argument("--events", type=int, default=5)
    parser.add_argument("--facets", type=int, default=1, help="facets broken per event")
    args = parser.parse_args()
    res = None if args.resolution == "default" else args.resolution
    scene = load_scene(SCENE, res, overrides={"solver.solid": "full"})
    tmesh = create_scene_mesh(scene, comm).tmesh
    solid = build_solid(scene, tmesh)
    frac = build_fracture(scene, solid)
    loads = Loads(cavity=dict.fromkeys(frac.settings.cavity, 1.0), in_situ_factor=0.0)
    a_form, ksp = solid.factorize()
    A0 = ksp.getOperators()[0].copy()
    # the old factor, kept apart from the solid's (which refactorises in place)
    old = PETSc.KSP().create(comm)
    old.setOperators(A0)
    old.setType("preonly")
    pc = old.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    A0.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    _, t_fact = timed(old.setUp)
    factor = pc.getFactorMatrix()
    b = solid.assemble_load(a_form, solid.load_form(loads))
    y = b.duplicate()
    _, t_back = timed(lambda: old.solve(b, y))
    say(
        f"{args.resolution}: {solid.num_dofs} unknowns, {comm.size} rank(s); factorisation "
        f"from nothing {t_fact:.2f} s, one back-substitution {t_back:.3f} s"
    )
    say(
        "\n| events | facets | r | refactorise s | r-column solve s | Woodbury solve s "
        "| Woodbury / refactorised - 1 |\n|---|---|---|---|---|---|---|"
    )
    at_wall = np.isin(solid.vertex_ids, frac.cavity_vertices).sum(axis=1) >= solid.gdim - 1
    key = np.where(at_wall & solid.owned, solid.midpoints[:, 0], np.inf)
    order = np.sort(np.concatenate(comm.allgather(key[np.isfinite(key)])))
    lo, _ = A0.getOwnershipRange()
    for k in range(args.events):
        targets = order[5 * k * args.facets : 5 * (k + 1) * args.facets : 5]
        chosen = np.flatnonzero(np.isin(key, targets))
        solid.break_facets(chosen, np.ones(len(chosen), dtype=np.int8), 0.0)
        (a_form, ksp), t_refact = timed(solid.factorize)
        A1 = ksp.getOperators()[0]
        E, D = changed_block(A1, A0)
        Z, t_cols = timed(lambda E=E: columns_solve(factor, A0, E))
        S = rows_of(Z, lo, E)
        b1 = solid.assemble_load(a_form, solid.load_form(loads))
        x_ref = b1.duplicate()
        ksp.solve(b1, x_ref)

        def woodbury(b1=b1, Z=Z, S=S, D=D, E=E) -> PETSc.Vec:  # type: ignore[no-untyped-def]
            y = b1.duplicate()
            old.solve(b1, y)
            yE = rows_of(y.getArray(readonly=True)[:, None], lo, E)[:, 0]
            c = np.linalg.solve(np.eye(len(E)) + D @ S, D @ yE)
            y.getArray()[:] -= Z @ c
            return y

        x, t_wood = timed(woodbury)
        x.axpy(-1.0, x_ref)
        diff = x.norm() / x_ref.norm()
        say(
            f"| {k + 1} | {(k + 1) * args.facets} | {len(E)} | {t_refact:.3f} | {t_cols:.3f} "
            f"| {t_wood:.3f} | {diff:.1e} |"
        )
        for v in (b1, x_ref, x):
            v.destroy()
    say(f"\nDOLFINx {dolfinx.__version__}")


if __name__ == "__main__":
    main()
