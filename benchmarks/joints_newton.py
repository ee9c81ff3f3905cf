"""The joints' Newton in No. 2's pumped seepage: would a lagged factorisation pay?

Each Newton iteration of a pumped seepage step
(:meth:`hfcdem.flow.seepage.JointSeepage.step_pumped`) refactorises the
joints' matrix.  This script runs No. 2's ``seepage`` rung (as
``fidelity_ladder.py``) at one resolution, keeps the first ``--matrices``
Newton matrices, and for each one measures what GMRES needs with the
previous matrix's LU as the preconditioner (right-preconditioned, to 1e-12 of
the true residual, at most 60 iterations), against a numeric refactorisation
and a back-substitution.  A lagged factor pays when GMRES takes fewer than
``refactorisation / (2 back-substitutions)`` iterations: each iteration
solves for two right-hand sides.  Prints one row per matrix (its place in its
balance, the relative change from the previous matrix, the rows that changed,
the GMRES iterations) and a summary.  One rank.

    make run CMD="python3 benchmarks/joints_newton.py --resolution default --matrices 60"
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fidelity_ladder

from hfcdem.config.scene import load_scene
from hfcdem.flow import seepage
from hfcdem.workflows.run import run_scene


class _Enough(Exception):
    """Raised inside the run once the matrices are kept."""


def record(resolution: str, duration: str, count: int) -> tuple[list[PETSc.Mat], list[int]]:
    """Run the seepage rung and keep its first ``count`` joints' Newton matrices.

    Returns the matrices and, for each, its Newton iteration within its balance (1, 2, ...).
    """
    matrices: list[PETSc.Mat] = []
    place: list[int] = []
    factorise, pumped = seepage.JointSeepage._factorise, seepage.JointSeepage.step_pumped
    within = [0]

    def keep(self, lin, shift):  # type: ignore[no-untyped-def]
        ksp = factorise(self, lin, shift)
        within[0] += 1
        matrices.append(ksp.getOperators()[0].duplicate(copy=True))
        place.append(within[0])
        if len(matrices) >= count:
            raise _Enough
        return ksp

    def balance(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        within[0] = 0
        return pumped(self, *args, **kwargs)

    seepage.JointSeepage._factorise = keep  # type: ignore[method-assign]
    seepage.JointSeepage.step_pumped = balance  # type: ignore[method-assign]
    try:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "no2_seepage.toml"
            path.write_text(fidelity_ladder.scene_text("seepage"))
            scene = load_scene(path, resolution, overrides={"injection.duration": duration})
            run_scene(scene, Path(tmp) / "out", force=True)
    except _Enough:
        pass
    finally:
        seepage.JointSeepage._factorise = factorise  # type: ignore[method-assign]
        seepage.JointSeepage.step_pumped = pumped  # type: ignore[method-assign]
    return matrices, place


def lu(matrix: PETSc.Mat) -> PETSc.KSP:
    """Sequential MUMPS LU of ``matrix``, as the seepage solve sets it up."""
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(matrix)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setUp()
    return ksp


def costs(matrix: PETSc.Mat) -> tuple[float, float]:
    """Seconds of a numeric refactorisation and of a back-substitution of ``matrix``."""
    ksp = lu(matrix)
    b = matrix.createVecLeft()
    b.setRandom()
    x = b.duplicate()
    ksp.solve(b, x)
    start = time.perf_counter()
    for _ in range(10):
        ksp.solve(b, x)
    solve = (time.perf_counter() - start) / 10
    matrix.scale(1.0 + 1e-14)  # new values on the same pattern: a numeric factorisation
    start = time.perf_counter()
    ksp.setOperators(matrix)
    ksp.setUp()
    refactor = time.perf_counter() - start
    ksp.destroy()
    return refactor, solve


def lagged_iterations(matrix: PETSc.Mat, previous: PETSc.Mat) -> int:
    """GMRES iterations on ``matrix`` with the LU of ``previous`` (-1: not converged)."""
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(matrix, previous)
    ksp.setType("gmres")
    ksp.setPCSide(PETSc.PC.Side.RIGHT)
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setTolerances(rtol=1e-12, atol=0.0, max_it=60)
    ksp.setUp()
    b = matrix.createVecLeft()
    b.setRandom()
    x = b.duplicate()
    ksp.solve(b, x)
    its = ksp.getIterationNumber() if ksp.getConvergedReason() > 0 else -1
    ksp.destroy()
    return its


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolution", default="coarse")
    ap.add_argument("--duration", default="2 s", help="pump for at most this long")
    ap.add_argument("--matrices", type=int, default=60, help="Newton matrices to keep")
    args = ap.parse_args()
    matrices, place = record(args.resolution, args.duration, args.matrices)
    if not matrices:
        raise SystemExit("no joints' Newton matrix was formed")
    refactor, solve = costs(matrices[0].duplicate(copy=True))  # a copy: costs() rescales it
    even = refactor / (2.0 * solve)
    size, nnz = matrices[0].getSize()[0], int(matrices[0].getInfo()["nz_used"])
    print(f"joints: {size} unknowns, {nnz} nonzeros")
    print(f"refactorisation {refactor:.3f} s, back-substitution {1e3 * solve:.2f} ms: "
          f"a lagged factor pays below {even:.1f} GMRES iterations")  # fmt: skip
    print("| matrix | Newton iteration of its balance | change | rows changed | GMRES its |")
    print("|---|---|---|---|---|")
    paying, rows = 0, 0
    for k in range(1, len(matrices)):
        a, b = matrices[k], matrices[k - 1]
        if a.getSize() != b.getSize():  # a new network (cracks joined the cavity)
            continue
        diff = a.duplicate(copy=True)
        diff.axpy(-1.0, b)
        change = diff.norm(PETSc.NormType.FROBENIUS) / a.norm(PETSc.NormType.FROBENIUS)
        indptr, _, values = diff.getValuesCSR()
        row_of = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        changed = np.unique(row_of[np.abs(values) > 0.0]).size
        diff.destroy()
        its = lagged_iterations(a, b)
        rows += 1
        paying += 0 <= its < even
        shown = str(its) if its >= 0 else "> 60"
        print(f"| {k + 1} | {place[k]} | {change:.2e} | {changed} | {shown} |")
    print(f"the lagged factor pays on {paying} of {rows} Newton matrices")


if __name__ == "__main__":
    main()
