"""The solid's stiffness, assembled and factorised once, then updated where interfaces changed.

An interface event (a break, a contact switch) changes the integral of a few
facets only.  Rather than assembling and analysing the whole system again, the
operator adds the change of those facets, ``dK`` (reduced through ``P`` in the
reduced mode), to the matrix it keeps.  The sparsity and the KSP stay, so MUMPS
redoes only its numeric factorisation (no ordering, no symbolic analysis).

With a direct solver and ``max_columns > 0`` an event does not even
refactorise: the change joins a low-rank (Woodbury) correction of the kept
factor (:mod:`hfcdem.solid.lowrank`) until ``max_columns`` columns have
changed; then the changes are added to the factorised matrix and it is
refactorised numerically.

It assembles afresh when the structure changes (a new band in the reduced mode),
when a numeric refactorisation fails, and every ``refresh_every`` updates, so
round-off of the sums cannot build up.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.solid.lowrank import LowRankCorrection, corrected_solver
from hfcdem.solvers import WORKSPACE_ERRORS, mumps_info

Reduce = Callable[[PETSc.Mat, float], PETSc.Mat]


class StiffnessOperator:
    """The assembled (possibly reduced) stiffness and its factorised KSP, kept between events.

    ``assemble()`` returns the whole stiffness (Dirichlet rows and columns set);
    ``assemble_change(old, new)`` the change of the interfaces whose integral went
    from ``old`` to ``new`` (Dirichlet rows and columns zero); ``reduce(A,
    diagonal)`` (or None) maps a DG matrix to the solved one; ``create_solver(A)``
    factorises it.  ``max_columns`` caps the low-rank correction (0: none).
    """

    def __init__(
        self,
        comm: MPI.Comm,
        assemble: Callable[[], PETSc.Mat],
        assemble_change: Callable[[np.ndarray, np.ndarray], PETSc.Mat],
        create_solver: Callable[[PETSc.Mat], PETSc.KSP],
        refresh_every: int = 50,
        max_columns: int = 0,
    ) -> None:
        self.comm = comm
        self._assemble = assemble
        self._assemble_change = assemble_change
        self._create_solver = create_solver
        self.refresh_every = refresh_every
        self.max_columns = max_columns
        self._A: PETSc.Mat | None = None  # the factorised matrix
        self._ksp: PETSc.KSP | None = None  # its factorisation
        # low-rank mode: the matrix with the changes since, the changes, their correction
        self._current: PETSc.Mat | None = None
        self._pending: list[PETSc.Mat] = []
        self._correction: LowRankCorrection | None = None
        self._solver: PETSc.KSP | None = None  # what solver() hands out
        self._values: np.ndarray | None = None
        self._key: Hashable = None
        self._updates = 0
        # assembled: afresh (with analysis); updated: numeric refactorisations; low_rank:
        # events taken as a correction, adding ``columns`` columns in all
        self.counts = {"assembled": 0, "updated": 0, "unchanged": 0, "low_rank": 0, "columns": 0}
        # why changes went into a refactorisation instead: past the cap, near singular
        self.refusals = {"cap": 0, "condition": 0}
        self.seconds = {"assemble": 0.0, "update": 0.0, "factorise": 0.0, "low_rank": 0.0}

    @property
    def low_rank_columns(self) -> int:
        """Columns of the low-rank correction held now (0 right after a factorisation)."""
        return 0 if self._correction is None else self._correction.rank

    def statistics(self) -> dict[str, object]:
        """Return the counts and seconds of factorisations and low-rank events (for a summary)."""
        seconds = {k: round(v, 3) for k, v in self.seconds.items()}
        return {**self.counts, "refused": dict(self.refusals), "seconds": seconds}

    def solver(self, values: np.ndarray, key: Hashable, reduce: Reduce | None) -> PETSc.KSP:
        """Return the factorised KSP of the interfaces' integrals ``values`` (collective).

        ``key`` names the structure (e.g. the band's version): a new key assembles
        afresh.  The operator owns the KSP; it stays valid until the next call.
        """
        values = np.asarray(values).copy()
        if self._ksp is not None and self._values is not None and key == self._key:
            changed = int(np.count_nonzero(values != self._values))
            if self.comm.allreduce(changed, op=MPI.SUM) == 0:
                self.counts["unchanged"] += 1
                assert self._solver is not None
                return self._solver
            if self._updates < self.refresh_every and self._update(values, reduce):
                assert self._solver is not None
                return self._solver
        self._fresh(values, key, reduce)
        assert self._solver is not None
        return self._solver

    def _fresh(self, values: np.ndarray, key: Hashable, reduce: Reduce | None) -> None:
        previous = self._correction  # its storage serves the next one, if of the same size
        self.destroy()
        t0 = time.perf_counter()
        A = self._assemble()
        if reduce is not None:
            A_dg, A = A, reduce(A, 1.0)
            A_dg.destroy()
        t1 = time.perf_counter()
        self._ksp = self._solver = self._create_solver(A)
        self._A = A
        if self.max_columns > 0 and mumps_info(self._ksp) is not None:
            self._current = A.copy()
            self._correction = LowRankCorrection(self._ksp, self.max_columns, previous)
        self._values, self._key, self._updates = values, key, 0
        self.counts["assembled"] += 1
        self.seconds["assemble"] += t1 - t0
        self.seconds["factorise"] += time.perf_counter() - t1

    def _update(self, values: np.ndarray, reduce: Reduce | None) -> bool:
        """Take the change into the correction or refactorise numerically; False if that failed."""
        assert self._A is not None and self._ksp is not None and self._values is not None
        t0 = time.perf_counter()
        dK = self._assemble_change(self._values, values)
        if reduce is not None:
            dK_dg, dK = dK, reduce(dK, 0.0)
            dK_dg.destroy()
        subset = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN
        if self._current is not None:
            self._current.axpy(1.0, dK, structure=subset)
        held = self.low_rank_columns
        if self._correction is not None and self._correction.add(dK):
            assert self._current is not None
            self.counts["columns"] += self.low_rank_columns - held
            self._pending.append(dK)
            if self._solver is self._ksp:
                self._solver = corrected_solver(self._correction, self._current)
            self._values = values
            self._updates += 1
            self.counts["low_rank"] += 1
            self.seconds["low_rank"] += time.perf_counter() - t0
            return True
        if self._correction is not None:
            self.refusals[self._correction.refused] += 1
        # the kept factor's matrix takes every change since, in the order _current did
        for change in (*self._pending, dK):
            self._A.axpy(1.0, change, structure=subset)
            change.destroy()
        self._pending = []
        t1 = time.perf_counter()
        self._ksp.setOperators(self._A)
        self._ksp.setUp()  # same sparsity: MUMPS keeps its analysis
        codes = [c for c in self.comm.allgather(mumps_info(self._ksp)) if c is not None]
        self.seconds["update"] += t1 - t0
        self.seconds["factorise"] += time.perf_counter() - t1
        if codes and (min(codes) in WORKSPACE_ERRORS or min(codes) < 0):
            return False  # assembled afresh with more room by the caller
        if self._correction is not None:
            self._correction = LowRankCorrection(self._ksp, self.max_columns, self._correction)
        if self._solver is not self._ksp and self._solver is not None:
            self._solver.destroy()
        self._solver = self._ksp
        self._values = values
        self._updates += 1
        self.counts["updated"] += 1
        return True

    def destroy(self) -> None:
        """Free the kept matrices and KSPs."""
        if self._solver is not None and self._solver is not self._ksp:
            self._solver.destroy()
        for obj in (self._ksp, self._A, self._current, *self._pending):
            if obj is not None:
                obj.destroy()
        self._ksp, self._A, self._current, self._solver = None, None, None, None
        self._pending, self._correction, self._values = [], None, None


__all__ = ["StiffnessOperator"]
