"""Interface events as low-rank changes of a kept factorisation (Woodbury).

An interface event changes the stiffness only in the rows and columns of the
changed facets' unknowns (18 per facet for DG1 in 3D): ``K = K0 + E D E^T``,
with ``E`` the selection of those ``r`` unknowns and ``D`` the ``r x r``
change.  With ``Z = K0^-1 E`` and ``S = E^T Z``,

    K^-1 b = y - Z (I + D S)^-1 D E^T y,    y = K0^-1 b,

so the factor of ``K0`` serves the solves after any number of events: an
event costs the new columns of ``Z`` (one MUMPS solve with several right-hand
sides) instead of a numeric refactorisation, and a solve costs a second
back-substitution (one step of iterative refinement) and ``n x r`` products.
At No. 2's default mesh a numeric refactorisation takes 15-19 s, the columns
of one facet about 1 s (benchmarks/README.md).

:class:`LowRankCorrection` keeps ``E``, ``Z``, ``S`` and ``D``;
:func:`corrected_solver` wraps it in a KSP (``preonly`` with a Python PC), so
callers solve through it as through the factor itself.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.solvers import check_ksp, dense_rows, solve_columns

# columns of Z solved together: MUMPS's dense right-hand side is n x this
_COLUMN_BATCH = 32


class LowRankCorrection:
    """The change ``E D E^T`` added to a factorised ``K0`` since its factorisation.

    ``factor`` is a set-up direct KSP of ``K0``, kept unchanged; at most
    ``max_columns`` unknowns (the rank ``r``) may change before :meth:`add`
    refuses and the caller refactorises.
    """

    def __init__(self, factor: PETSc.KSP, max_columns: int) -> None:
        self.factor = factor
        self.max_columns = max_columns
        A0 = factor.getOperators()[0]
        self.comm: MPI.Comm = A0.getComm().tompi4py()
        self.lo, self.hi = A0.getOwnershipRange()
        self.rows = np.zeros(0, dtype=np.int64)  # E: global indices, the same on every rank
        self.Z = np.zeros((self.hi - self.lo, 0))  # this rank's rows of K0^-1 E
        self.D = np.zeros((0, 0))
        self.M = np.zeros((0, 0))  # I + D S

    @property
    def rank(self) -> int:
        """The number ``r`` of unknowns changed since the factorisation."""
        return len(self.rows)

    def _gather(self, local: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Gather the rows ``rows`` (global) of a distributed block onto every rank."""
        mine = (rows >= self.lo) & (rows < self.hi)
        part = np.zeros((len(rows), local.shape[1]))
        part[mine] = local[rows[mine] - self.lo]
        return self.comm.allreduce(part, op=MPI.SUM)

    def add(self, dK: PETSc.Mat) -> bool:
        """Add the change ``dK`` (collective); False, adding nothing, if ``r`` passes the cap."""
        indptr, cols, vals = dK.getValuesCSR()
        hit = vals != 0.0
        rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))[hit] + self.lo
        cols = cols[hit].astype(np.int64)
        touched = np.union1d(rows, cols)
        touched = np.unique(np.concatenate(self.comm.allgather(touched)))
        new = np.setdiff1d(touched, self.rows)
        if self.rank + len(new) > self.max_columns:
            return False
        if len(new):
            columns = []
            for start in range(0, len(new), _COLUMN_BATCH):
                part = new[start : start + _COLUMN_BATCH]
                block = np.zeros((self.hi - self.lo, len(part)))
                mine = (part >= self.lo) & (part < self.hi)
                block[part[mine] - self.lo, np.flatnonzero(mine)] = 1.0
                columns.append(solve_columns(self.factor, block))
            check_ksp(self.factor, "low-rank columns of the CDEM stiffness")
            self.Z = np.hstack([self.Z, *columns])
            self.rows = np.concatenate([self.rows, new])
            D = np.zeros((self.rank, self.rank))
            D[: len(self.D), : len(self.D)] = self.D
            self.D = D
        order = np.argsort(self.rows)
        where = order[np.searchsorted(self.rows[order], rows)]
        part = np.zeros_like(self.D)
        np.add.at(part, (where, order[np.searchsorted(self.rows[order], cols)]), vals[hit])
        self.D += self.comm.allreduce(part, op=MPI.SUM)
        S = self._gather(self.Z, self.rows)
        self.M = np.eye(self.rank) + self.D @ S
        return True

    def correct(self, y: np.ndarray) -> None:
        """Turn ``y = K0^-1 b`` (this rank's rows, a column per right-hand side) into ``K^-1 b``."""
        if self.rank == 0:
            return
        c = np.linalg.solve(self.M, self.D @ self._gather(y, self.rows))
        y -= self.Z @ c


class _CorrectedPC:
    """Python PC context: the factor's solve and the Woodbury correction, refined.

    The correction's own round-off grows with the change (a broken facet drops a
    penalty stiffness of ``alpha E / h``): 1e-12 of the solution on a small
    block, where a pumped run's volume balance needs 3e-13.  One step of
    iterative refinement on the changed matrix (``operator``) takes it to about
    1e-13 on the small block, where more steps gain nothing (measured: the
    conditioning's limit, a direct solve's own).
    """

    def __init__(self, correction: LowRankCorrection, operator: PETSc.Mat) -> None:
        self.correction = correction
        self.operator = operator

    def _times(self, Y: np.ndarray) -> np.ndarray:
        """``K Y`` for this rank's rows ``Y``."""
        M = dense_rows(self.operator.getComm(), Y, self.operator.getSize()[1])
        KY = self.operator.matMult(M)
        out = np.array(KY.getDenseArray(readonly=True))
        M.destroy()
        KY.destroy()
        return out

    def solve(self, B: np.ndarray) -> np.ndarray:
        """Solve ``K Y = B`` for this rank's rows ``B`` (a column per right-hand side)."""
        corr = self.correction
        Y = solve_columns(corr.factor, B)
        check_ksp(corr.factor, "CDEM solve on the kept factor")
        corr.correct(Y)
        if corr.rank == 0:
            return Y
        Z = solve_columns(corr.factor, B - self._times(Y))
        corr.correct(Z)
        return Y + Z

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        y.setArray(self.solve(x.getArray(readonly=True).reshape(-1, 1))[:, 0])

    def matApply(self, pc: PETSc.PC, X: PETSc.Mat, Y: PETSc.Mat) -> None:
        Y.getDenseArray()[:] = self.solve(np.array(X.getDenseArray(readonly=True)))


def corrected_solver(correction: LowRankCorrection, operator: PETSc.Mat) -> PETSc.KSP:
    """Return a set-up KSP solving with ``operator`` (``K0 + E D E^T``) through ``correction``."""
    ksp = PETSc.KSP().create(correction.comm)
    ksp.setOperators(operator)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.PYTHON)
    pc.setPythonContext(_CorrectedPC(correction, operator))
    ksp.setUp()
    return ksp


__all__ = ["LowRankCorrection", "corrected_solver"]
