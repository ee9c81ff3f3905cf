"""PETSc solver configuration and failure checks shared by every solver of hfcdem.

Every KSP or SNES here carries an options prefix; the defaults given in code go
into the PETSc options database only where the user (command line,
``PETSC_OPTIONS``) has not set that name, and are removed after
``setFromOptions`` so the global database holds only what the user put there.

A failed solve raises :class:`SolverError` on every rank at once: the reason is
reduced over the communicator before anyone raises, so no rank is left waiting
in a collective that a failed rank never reaches.  A computation that cannot go
on (a coupled step, a cascade of breaks) raises a :class:`SimulationStopped`,
after which what was computed so far is kept.
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

#: MUMPS LU for general systems.
DIRECT_LU: dict[str, object] = {
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}

#: MUMPS LDL^T for symmetric systems (about half the time and memory of LU).
DIRECT_CHOLESKY: dict[str, object] = {
    "ksp_type": "preonly",
    "pc_type": "cholesky",
    "pc_factor_mat_solver_type": "mumps",
}

# MUMPS INFOG(1) codes worth a sentence (MUMPS 5 users' guide, section 8)
_MUMPS_ERRORS = {
    -5: "out of memory in the analysis",
    -6: "the matrix is structurally singular",
    -7: "out of memory",
    -8: "the integer workspace is too small (raise mat_mumps_icntl_14)",
    -9: "the real workspace is too small (raise mat_mumps_icntl_14)",
    -10: "the matrix is numerically singular: a block may be free to move",
    -13: "out of memory",
    -17: "the workspace is too small (raise mat_mumps_icntl_14)",
    -20: "the workspace is too small (raise mat_mumps_icntl_14)",
}


class SimulationStopped(RuntimeError):
    """The computation could not continue; what it found so far is kept.

    Raised on every rank at once.  The coupled run
    (:mod:`hfcdem.coupling.hydrofrac`) and the solid's cascade of breaks
    (:class:`hfcdem.solid.states.CascadeStopped`) stop with it.
    """


class ValidityLimit(SimulationStopped):
    """The run reached a state the model does not represent; its history up to there stands.

    Not a solver failure: e.g. blocks come loose from a cavity wall and move
    into the cavity, past what the small-displacement solid follows.  Runs and
    reports mark such a stop as the model's validity limit (``summary.json``:
    ``validity_limit``), not as a failure.
    """


class SolverError(RuntimeError):
    """A linear or nonlinear solve that did not converge (raised on every rank).

    ``reason`` is PETSc's converged reason (negative), ``mumps_info`` MUMPS's
    INFOG(1) when MUMPS factorised (0 when it succeeded, ``None`` otherwise).
    """

    def __init__(self, message: str, reason: int, mumps_info: int | None = None) -> None:
        super().__init__(message)
        self.reason = reason
        self.mumps_info = mumps_info


def reason_name(reason: int, kind: type = PETSc.KSP.ConvergedReason) -> str:
    """Return the PETSc name of a converged reason, e.g. ``DIVERGED_PC_FAILED`` (-11)."""
    for name in dir(kind):
        if not name.startswith("_") and getattr(kind, name) == reason:
            return f"{name} ({reason})"
    return str(reason)


@contextmanager
def petsc_options(prefix: str, defaults: Mapping[str, object]) -> Iterator[None]:
    """Put ``defaults`` under ``prefix`` into the options database for the block.

    Names the user already set keep the user's value; the ones added here are
    removed afterwards.
    """
    db = PETSc.Options()
    ours = []
    for key, value in defaults.items():
        if not db.hasName(prefix + key):
            db.setValue(prefix + key, value)
            ours.append(prefix + key)
    try:
        yield
    finally:
        for name in ours:
            db.delValue(name)


def create_ksp(
    A: PETSc.Mat, prefix: str, defaults: Mapping[str, object], comm: MPI.Comm | None = None
) -> PETSc.KSP:
    """Create a KSP on ``A`` configured from ``defaults`` and the options under ``prefix``."""
    ksp = PETSc.KSP().create(A.comm if comm is None else comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A)
    with petsc_options(prefix, defaults):
        ksp.setFromOptions()
    return ksp


def mumps_info(ksp: PETSc.KSP) -> int | None:
    """Return MUMPS's INFOG(1) for the factorisation behind ``ksp`` (None if not MUMPS)."""
    try:
        pc = ksp.getPC()
        if pc.getType() not in ("lu", "cholesky"):
            return None
        if pc.getFactorSolverType() != "mumps":
            return None
        return int(pc.getFactorMatrix().getMumpsInfog(1))
    except (PETSc.Error, AttributeError):
        return None


#: MUMPS's ICNTL(7) codes of the orderings it takes from other libraries
_EXTERNAL_ORDERINGS = {3: "scotch", 4: "pord", 5: "metis"}


def mumps_orderings() -> list[str]:
    """Return the external fill-reducing orderings the linked MUMPS honours, by name.

    MUMPS quietly falls back to another ordering when asked for one it was built
    without (Debian's links only PORD), so each is asked for on a small matrix and
    kept if INFOG(7), the ordering used, says it ran.  MUMPS's automatic choice
    prefers METIS where present: the numeric factorisation of the No. 2 solid takes
    25-35 % less time with it than with PORD (benchmarks/README.md).  Runs on
    ``COMM_SELF``; not collective.
    """
    n = 30  # a path graph: milliseconds per ordering
    A = PETSc.Mat().createAIJ([n, n], nnz=3, comm=PETSc.COMM_SELF)
    for i in range(n):
        A.setValue(i, i, 2.0)
        if i + 1 < n:
            A.setValue(i, i + 1, -1.0)
            A.setValue(i + 1, i, -1.0)
    A.assemble()
    found = []
    for code, name in _EXTERNAL_ORDERINGS.items():
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        try:  # a PETSc without MUMPS fails here: no ordering to name
            ksp.setOperators(A)
            ksp.setType("preonly")
            pc = ksp.getPC()
            pc.setType("cholesky")
            pc.setFactorSolverType("mumps")
            pc.setFactorSetUpSolverType()
            pc.getFactorMatrix().setMumpsIcntl(7, code)
            ksp.setUp()
            if int(pc.getFactorMatrix().getMumpsInfog(7)) == code:
                found.append(name)
        except PETSc.Error:
            pass
        finally:
            ksp.destroy()
    A.destroy()
    return sorted(found)


#: INFOG(1) codes of a workspace that proved too small: a retry with more room helps
WORKSPACE_ERRORS = (-8, -9, -17, -20)


def retry_factorisation(
    attempt: Callable[[int | None], int | None], tries: int = 3, first: int = 20
) -> int | None:
    """Factorise through ``attempt(relaxation)`` until MUMPS has room; return INFOG(1).

    ``attempt`` factorises with MUMPS's ICNTL(14) (the percentage added to its
    workspace estimate; ``None``: the configured value) and returns the INFOG(1)
    reached on every rank (the minimum).  MUMPS schedules the parallel
    factorisation dynamically, by the load of each process, so on a busy machine
    a process may need more than the estimate: INFOG(1) = -9.  Each retry doubles
    the relaxation, from ``first``.
    """
    info = attempt(None)
    relaxation = first
    for _ in range(tries):
        if info not in WORKSPACE_ERRORS:
            break
        relaxation *= 2
        info = attempt(relaxation)
    return info


def setup_factorisation(
    make_ksp: Callable[[], PETSc.KSP], comm: MPI.Comm, tries: int = 3
) -> PETSc.KSP:
    """Create and set up a KSP from ``make_ksp``, refactorising with more MUMPS room if needed.

    A KSP that is not a MUMPS factorisation is set up once.  The last KSP is
    returned whatever happened; :func:`check_ksp` after its solve reports a
    failure that remains.
    """
    box: list[PETSc.KSP] = []

    def attempt(relaxation: int | None) -> int | None:
        for old in box:
            old.destroy()
        box.clear()
        ksp = make_ksp()
        box.append(ksp)
        if relaxation is not None:
            if comm.rank == 0:
                print(
                    f"note: MUMPS ran out of workspace (busy machine?): refactorising with "
                    f"ICNTL(14) = {relaxation} %",
                    file=sys.stderr,
                    flush=True,
                )
            pc = ksp.getPC()
            pc.setFactorSetUpSolverType()
            pc.getFactorMatrix().setMumpsIcntl(14, relaxation)
        ksp.setUp()
        codes = [c for c in comm.allgather(mumps_info(ksp)) if c is not None]
        return min(codes) if codes else None

    retry_factorisation(attempt, tries)
    return box[0]


def check_ksp(ksp: PETSc.KSP, what: str, hint: str = "") -> None:
    """Raise :class:`SolverError` on every rank if ``ksp``'s last solve failed.

    The reason is reduced (minimum) over the KSP's communicator, so all ranks
    agree; the message names the prefix, PETSc's reason and MUMPS's INFOG(1).
    """
    comm = ksp.comm.tompi4py()
    reason = comm.allreduce(int(ksp.getConvergedReason()), op=MPI.MIN)
    if reason >= 0:
        return
    local = mumps_info(ksp)
    codes = comm.allgather(local)
    info = min((c for c in codes if c is not None), default=None)
    text = f"{what} (prefix {ksp.getOptionsPrefix()!r}) did not converge: PETSc reason "
    text += reason_name(reason)
    if info is not None:
        text += f", MUMPS INFOG(1) = {info}"
        if info in _MUMPS_ERRORS:
            text += f" ({_MUMPS_ERRORS[info]})"
    if hint:
        text += f"; {hint}"
    raise SolverError(text, reason, info)


def solve_together(ksp: PETSc.KSP, rhs: Sequence[PETSc.Vec]) -> np.ndarray:
    """Solve ``K x_i = b_i`` for all ``i`` in one call of a direct ``ksp`` (collective).

    Returns this rank's rows of the solutions, one column each (a copy).
    """
    block = np.column_stack([b.getArray(readonly=True) for b in rhs])
    return solve_columns(ksp, block)


def dense_rows(comm: PETSc.Comm, block: np.ndarray, n: int) -> PETSc.Mat:
    """Return an assembled dense ``n x k`` matrix with this rank's rows ``block`` (collective)."""
    sizes = ((block.shape[0], n), (PETSc.DECIDE, block.shape[1]))
    M = PETSc.Mat().createDense(sizes, comm=comm)
    M.setUp()
    M.getDenseArray()[:] = block
    M.assemble()
    return M


def solve_columns(ksp: PETSc.KSP, block: np.ndarray) -> np.ndarray:
    """Solve ``K X = B`` for this rank's rows ``block`` of a dense ``B`` (collective).

    One call of ``KSP.matSolve``: a direct solver reads its factor once for all
    the columns.  Returns this rank's rows of ``X`` (a copy).
    """
    n = ksp.getOperators()[0].getSize()[0]
    B = dense_rows(ksp.getComm(), block, n)
    X = B.duplicate()
    ksp.matSolve(B, X)
    solved = np.array(X.getDenseArray(readonly=True))
    B.destroy()
    X.destroy()
    return solved


def solve_sparse_columns(ksp: PETSc.KSP, rows: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Solve ``K X = B`` for a ``B`` non-zero on the global ``rows`` only (collective).

    ``ksp`` is set up (a direct one: factorised).  ``values`` (``len(rows) x
    k``) are ``B``'s entries on those rows, the same on every rank.  A MUMPS
    factor takes them as a sparse right-hand side (ICNTL(20)), so its forward
    substitution skips the parts of the factor those rows do not reach: a
    low-rank event's columns (:mod:`hfcdem.solid.lowrank`) on No. 2's default
    mesh cost 40 % less than as dense columns (benchmarks/README.md).  Any
    other ``ksp`` solves the dense columns (:func:`solve_columns`).  Returns
    this rank's rows of ``X`` (a copy).
    """
    A = ksp.getOperators()[0]
    lo, hi = A.getOwnershipRange()
    n, k = A.getSize()[0], values.shape[1]
    if mumps_info(ksp) is None:
        block = np.zeros((hi - lo, k))
        mine = (rows >= lo) & (rows < hi)
        block[rows[mine] - lo] = values[mine]
        return solve_columns(ksp, block)
    comm = ksp.getComm()
    # PETSc hands MUMPS the host's block of B^T: the whole k x n of it sits on rank 0
    host = comm.getRank() == 0
    Bt = PETSc.Mat().createAIJ(((k if host else 0, k), (n if host else 0, n)), comm=comm)
    Bt.setPreallocationNNZ(len(rows) if host else 0)
    if host:
        index = np.asarray(rows, dtype=PETSc.IntType)
        for j in range(k):
            Bt.setValues([j], index, values[:, j])
    Bt.assemble()
    B = PETSc.Mat().createTranspose(Bt)
    X = PETSc.Mat().createDense(((hi - lo, n), (PETSc.DECIDE, k)), comm=comm)
    X.setUp()
    X.assemble()
    ksp.getPC().getFactorMatrix().matSolve(B, X)
    solved = np.array(X.getDenseArray(readonly=True))
    for M in (X, B, Bt):
        M.destroy()
    return solved


def _mumps_inverse_call() -> Callable[[int, int], int] | None:
    """``MatMumpsGetInverseTranspose`` of the PETSc library petsc4py runs on (None: absent).

    petsc4py does not wrap it; the symbol is found through petsc4py's own
    extension module, whose dependencies include libpetsc.
    """
    try:
        call = ctypes.CDLL(PETSc.__file__).MatMumpsGetInverseTranspose
    except (OSError, AttributeError):
        return None
    call.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    call.restype = ctypes.c_int
    return call


_INVERSE_CALL = _mumps_inverse_call()


def columns_at_rows(ksp: PETSc.KSP, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """Return ``K^-1[rows, columns]`` from the columns solved in full (collective).

    Global indices, the same on every rank, as is the block returned; what
    :func:`inverse_entries` does without a MUMPS factor.
    """
    rows = np.asarray(rows, dtype=np.int64)
    lo, hi = ksp.getOperators()[0].getOwnershipRange()
    solved = solve_sparse_columns(ksp, np.asarray(columns), np.eye(len(columns)))
    mine = (rows >= lo) & (rows < hi)
    part = np.zeros((len(rows), len(columns)))
    part[mine] = solved[rows[mine] - lo]
    return ksp.getComm().tompi4py().allreduce(part, op=MPI.SUM)


def inverse_entries(ksp: PETSc.KSP, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """Return the block ``K^-1[rows, columns]`` of a symmetric ``K`` (collective).

    ``rows`` and ``columns``: global indices, the same on every rank; so is the
    ``len(rows) x len(columns)`` block returned.  ``ksp`` is set up (factorised).
    A MUMPS factor computes those entries alone (ICNTL(30)): its forward and
    backward substitutions skip the parts of the factor that neither index set
    reaches.  On No. 2's default mesh the entries of 10 neighbouring facets'
    unknowns (60-108 columns) at up to 7,500 rows take 0.3-0.5 s, where the same
    columns in full take 1.4-4.0 s (``benchmarks/inverse_entries.py``).  Any
    other ``ksp`` solves the columns (:func:`solve_sparse_columns`) and keeps
    the rows.  Not used by a run yet: a low-rank correction built on it measured
    5 % faster at the default mesh and 9 % slower at the coarse one
    (benchmarks/README.md, 2026-12-07).
    """
    rows = np.asarray(rows, dtype=np.int64)
    columns = np.asarray(columns, dtype=np.int64)
    for name, index in (("rows", rows), ("columns", columns)):
        if len(np.unique(index)) != len(index):  # the requested pattern has one entry each
            raise ValueError(f"inverse_entries: {name} must be distinct indices")
    comm = ksp.getComm().tompi4py()
    if len(rows) == 0 or len(columns) == 0:
        return np.zeros((len(rows), len(columns)))
    if mumps_info(ksp) is None or _INVERSE_CALL is None:
        return columns_at_rows(ksp, rows, columns)
    n = ksp.getOperators()[0].getSize()[0]
    host = comm.rank == 0
    # the requested pattern: row c of an n x n AIJ held whole on rank 0 (PETSc hands
    # MUMPS the host's diagonal block) asks for column c of the inverse at ``rows``
    row_order, column_order = np.argsort(rows), np.argsort(columns)
    itype = PETSc.IntType
    indptr = np.zeros(n + 1 if host else 1, dtype=itype)
    indices = np.zeros(0, dtype=itype)
    if host:
        counts = np.zeros(n, dtype=itype)
        counts[columns] = len(rows)
        indptr[1:] = np.cumsum(counts)
        indices = np.tile(rows[row_order].astype(itype), len(columns))
    local = n if host else 0
    Bt = PETSc.Mat().createAIJ(
        ((local, n), (local, n)), csr=(indptr, indices, np.zeros(len(indices))), comm=comm
    )
    F = ksp.getPC().getFactorMatrix()
    # the call leaves MUMPS set for inverse entries, sparse right-hand sides and a
    # centralised solution; the solves after it need the settings before it
    saved = {k: F.getMumpsIcntl(k) for k in (20, 21, 30)}
    try:
        code = _INVERSE_CALL(F.handle, Bt.handle)
    finally:
        for key, value in saved.items():
            F.setMumpsIcntl(key, value)
    if comm.allreduce(code, op=MPI.MAX) != 0:
        Bt.destroy()
        info = int(F.getMumpsInfog(1))
        failed = int(PETSc.KSP.ConvergedReason.DIVERGED_PC_FAILED)
        raise SolverError(
            f"MUMPS's entries of the inverse failed: PETSc error {code}, INFOG(1) = {info}",
            failed,
            info,
        )
    block = np.zeros((len(rows), len(columns)))
    if host:
        held = Bt.getDiagonalBlock() if comm.size > 1 else Bt
        _, _, values = held.getValuesCSR()
        # CSR rows in increasing column index, each with ``rows`` in increasing order
        block[np.ix_(row_order, column_order)] = values.reshape(len(columns), len(rows)).T
    Bt.destroy()
    return comm.bcast(block, root=0)


__all__ = [
    "DIRECT_CHOLESKY",
    "DIRECT_LU",
    "WORKSPACE_ERRORS",
    "SimulationStopped",
    "SolverError",
    "ValidityLimit",
    "check_ksp",
    "columns_at_rows",
    "create_ksp",
    "dense_rows",
    "inverse_entries",
    "mumps_info",
    "mumps_orderings",
    "petsc_options",
    "reason_name",
    "retry_factorisation",
    "setup_factorisation",
    "solve_columns",
    "solve_sparse_columns",
    "solve_together",
]
