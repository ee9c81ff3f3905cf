"""Interface events as low-rank changes of a kept factorisation (Woodbury).

An interface event changes the stiffness only in the rows and columns of the
changed facets' unknowns (18 per facet for DG1 in 3D), and there only through
the jump of the displacement across the facet (9 numbers for DG1 in 3D):
``K = K0 + E D E^T``, with ``E`` an ``n x r`` basis of the changes' range
(orthonormal, non-zero on the changed unknowns only) and ``D`` the ``r x r``
change in it.  With ``Z = K0^-1 E`` and ``S = E^T Z``,

    K^-1 b = y - Z (I + D S)^-1 D E^T y,    y = K0^-1 b,

so the factor of ``K0`` serves the solves after any number of events: an
event costs the new columns of ``Z`` (one MUMPS solve with several sparse
right-hand sides) instead of a numeric refactorisation, and a solve costs ``n x r``
products and, where ``I + D S`` is ill-conditioned, a second back-substitution
(one step of iterative refinement).
A change is compressed to its range (an eigen-decomposition of its dense
block) before it adds columns, and a change inside the range already held (a
contact switch of a facet that broke since the factorisation) adds none: a
spring facet costs 9 columns, not 18.  At No. 2's default mesh a numeric
refactorisation takes 15-19 s, a one-facet event with the solve after it 0.9 s
(benchmarks/README.md).

The compression is exact to round-off of the change (1e-16 of it).  Where the
changed matrix is near singular, a block left held by residual springs only,
that round-off swamps the little stiffness that holds it; since
``det K = det K0 det (I + D S)``, such a change shows as an ill-conditioned
``I + D S`` and is refused, and the caller refactorises exactly.

:class:`LowRankCorrection` keeps ``E``, ``Z``, ``S`` and ``D``;
:func:`corrected_solver` wraps it in a KSP (``preonly`` with a Python PC), so
callers solve through it as through the factor itself.
"""

from __future__ import annotations

import math

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.solvers import check_ksp, dense_rows, solve_columns, solve_sparse_columns

# columns of Z solved together: their dense solution block is n x this
_COLUMN_BATCH = 32
# an eigenvalue of a change below this share of its largest is round-off
_RANGE_TOLERANCE = 1e-13
# the corrected matrix's conditioning relative to the factor's past which the caller
# refactorises: 1e-8 of a spring's stiffness is left where residual springs hold a block
_MAX_CONDITION = 1e8
# a change adds at least this share of its new unknowns as columns (9 of 18 for a 3D
# spring facet); a change that would pass the cap even so is refused before any work
_LEAST_RANK_SHARE = 1 / 3
# a direction of the change's range (unit length) with less than this outside the basis
# held lies in it (a contact switch of a facet broken since the factorisation)
_OUTSIDE_TOLERANCE = 1e-10
# the corrected solve is refined once where I + D S is conditioned worse than this: the
# correction's own error is about cond(I + D S) 1.5e-16 of the solution (measured: 9.4e-13
# at 6.1e3), so 1.5e-13 at most without refinement, below the 3e-13 of a pumped run's
# volume balance
_REFINE_CONDITION = 1e3


class LowRankCorrection:
    """The change ``E D E^T`` added to a factorised ``K0`` since its factorisation.

    ``factor`` is a set-up direct KSP of ``K0``, kept unchanged; at most
    ``max_columns`` columns of ``E`` (the rank ``r``) may be held before
    :meth:`add` refuses and the caller refactorises.  ``after``: the correction
    of the factorisation this one replaces, whose storage for ``Z`` it takes
    over (its memory is touched already: at No. 2's default mesh, growing and
    first touching ``n x r`` anew after every refactorisation took 7.9 s of the
    first 38 s, 4.0 s since); ``after`` is spent then.
    """

    def __init__(
        self, factor: PETSc.KSP, max_columns: int, after: LowRankCorrection | None = None
    ) -> None:
        self.factor = factor
        self.max_columns = max_columns
        A0 = factor.getOperators()[0]
        self.comm: MPI.Comm = A0.getComm().tompi4py()
        self.lo, self.hi = A0.getOwnershipRange()
        self.rows = np.zeros(0, dtype=np.int64)  # changed unknowns (global), the same on every rank
        self.E = np.zeros((0, 0))  # the basis on those rows: E's non-zero rows, orthonormal columns
        # this rank's rows of K0^-1 E: the first ``rank`` columns of a buffer of
        # ``max_columns``, allocated at the first event (pages untouched until used)
        self._Z = np.zeros((self.hi - self.lo, 0))
        if after is not None and after._Z.shape == (self.hi - self.lo, max_columns):
            self._Z, after._Z = after._Z, self._Z
        self.D = np.zeros((0, 0))
        self.M = np.zeros((0, 0))  # I + D S
        self.condition = 1.0  # of M (2-norm)
        self.refused = ""  # why the last refused change was: "cap" or "condition"

    @property
    def rank(self) -> int:
        """The number ``r`` of columns of ``E`` held since the factorisation."""
        return self.E.shape[1]

    @property
    def Z(self) -> np.ndarray:
        """Rows of ``K0^-1 E`` on this rank (a view)."""
        return self._Z[:, : self.rank]

    def _append_columns(self, columns: list[np.ndarray]) -> None:
        """Store new columns of ``Z`` after the ``rank`` held (``E`` grows after)."""
        start = self.rank
        end = start + sum(c.shape[1] for c in columns)
        if end > self._Z.shape[1]:  # the first event (or a cap raised since)
            grown = np.empty((self._Z.shape[0], max(self.max_columns, end)))
            grown[:, :start] = self._Z[:, :start]
            self._Z = grown
        for c in columns:
            self._Z[:, start : start + c.shape[1]] = c
            start += c.shape[1]

    def _gather(self, local: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Gather the rows ``rows`` (global) of a distributed block onto every rank."""
        mine = (rows >= self.lo) & (rows < self.hi)
        part = np.zeros((len(rows), local.shape[1]))
        part[mine] = local[rows[mine] - self.lo]
        return self.comm.allreduce(part, op=MPI.SUM)

    def _entries(self, dK: PETSc.Mat) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global row, column and value of this rank's non-zeros of ``dK``."""
        indptr, cols, vals = dK.getValuesCSR()
        hit = vals != 0.0
        rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))[hit] + self.lo
        return rows, cols[hit].astype(np.int64), vals[hit]

    def add(self, dK: PETSc.Mat) -> bool:
        """Add the symmetric change ``dK`` (collective); False, adding nothing, if refused.

        Refused past the cap on columns, and where the changed matrix is near
        singular (the module docstring).
        """
        rows, cols, vals = self._entries(dK)
        touched = np.unique(np.concatenate(self.comm.allgather(np.union1d(rows, cols))))
        new_rows = np.setdiff1d(touched, self.rows)
        if self.rank + math.ceil(_LEAST_RANK_SHARE * len(new_rows)) > self.max_columns:
            self.refused = "cap"
            return False
        rows_all = np.concatenate([self.rows, new_rows])
        order = np.argsort(rows_all)
        at = order[np.searchsorted(rows_all[order], touched)]  # touched rows in rows_all
        # the change's range: it lives on the touched rows, so eigen-decompose that block
        C = np.zeros((len(touched), len(touched)))
        np.add.at(C, (np.searchsorted(touched, rows), np.searchsorted(touched, cols)), vals)
        C = self.comm.allreduce(C, op=MPI.SUM)
        w, V = np.linalg.eigh(C)
        keep = np.abs(w) > _RANGE_TOLERANCE * np.abs(w).max(initial=0.0)
        U = np.zeros((len(rows_all), int(keep.sum())))
        U[at] = V[:, keep]
        E = np.zeros((len(rows_all), self.rank))
        E[: len(self.rows)] = self.E
        # the part of that range outside the basis held: new columns
        u, sv, _ = np.linalg.svd(U - E @ (E.T @ U), full_matrices=False)
        N = u[:, sv > _OUTSIDE_TOLERANCE]
        if self.rank + N.shape[1] > self.max_columns:
            self.refused = "cap"
            return False
        if N.shape[1]:
            N -= E @ (E.T @ N)  # once more against the basis: orthogonal to round-off
            N, _ = np.linalg.qr(N)
            columns = [
                solve_sparse_columns(self.factor, rows_all, N[:, start : start + _COLUMN_BATCH])
                for start in range(0, N.shape[1], _COLUMN_BATCH)
            ]
            check_ksp(self.factor, "low-rank columns of the CDEM stiffness")
            # past the columns held: a refusal below leaves them unused (rank is E's)
            self._append_columns(columns)
            E = np.hstack([E, N])
        D = np.zeros((E.shape[1], E.shape[1]))
        D[: len(self.D), : len(self.D)] = self.D
        D += E[at].T @ C @ E[at]
        Z = self._Z[:, : E.shape[1]]
        M = np.eye(E.shape[1]) + D @ (E.T @ self._gather(Z, rows_all))
        # det K = det K0 det M: a near-singular M is a near-singular K (a block held by
        # residual springs only), whose solution the compression's round-off (about 1e-16
        # of the change) would swamp; the caller refactorises it exactly instead
        condition = float(np.linalg.cond(M))
        if condition > _MAX_CONDITION:
            self.refused = "condition"
            return False
        self.rows, self.E, self.D, self.M, self.condition = rows_all, E, D, M, condition
        return True

    def correct(self, y: np.ndarray) -> None:
        """Turn ``y = K0^-1 b`` (this rank's rows, a column per right-hand side) into ``K^-1 b``."""
        if self.rank == 0:
            return
        c = np.linalg.solve(self.M, self.D @ (self.E.T @ self._gather(y, self.rows)))
        y -= self.Z @ c


class _CorrectedPC:
    """Python PC context: the factor's solve and the Woodbury correction, refined if needed.

    The correction's own round-off grows with the conditioning of ``I + D S``
    (a change large against the stiffness it changes: a block left held by
    little more than residual springs): 1e-12 of the solution on a small block,
    where a pumped run's volume balance needs 3e-13.  One step of iterative
    refinement on the changed matrix (``operator``) takes it to about 1e-13
    there, where more steps gain nothing (measured: the conditioning's limit, a
    direct solve's own).  Below ``_REFINE_CONDITION`` the step is skipped: on
    No. 2 (cond 4-126) it moved the solution by up to 6e-7 of it, independently of
    the condition, in the directions the factor of ``K0`` itself leaves
    uncertain, and the residual not at all (1e-17 of ``|K| |u|`` before and after),
    so it cost a back-substitution for nothing (benchmarks/README.md).
    ``refinements`` counts the steps taken.
    """

    def __init__(self, correction: LowRankCorrection, operator: PETSc.Mat) -> None:
        self.correction = correction
        self.operator = operator
        self.refinements = 0

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
        if corr.rank == 0 or corr.condition <= _REFINE_CONDITION:
            return Y
        self.refinements += 1
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
