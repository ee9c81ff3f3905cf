import os

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc
from test_lowrank import chain

from hfcdem.solvers import (
    DIRECT_CHOLESKY,
    DIRECT_LU,
    SolverError,
    check_ksp,
    create_ksp,
    inverse_entries,
    mumps_orderings,
    petsc_options,
    reason_name,
    retry_factorisation,
    setup_factorisation,
    solve_columns,
    solve_sparse_columns,
    solve_together,
)


def diagonal(comm: MPI.Comm, values: list[float]) -> PETSc.Mat:
    """A distributed diagonal matrix with the given entries (global order)."""
    n = len(values)
    A = PETSc.Mat().createAIJ((n, n), nnz=1, comm=comm)
    lo, hi = A.getOwnershipRange()
    for i in range(lo, hi):
        A.setValue(i, i, values[i])
    A.assemble()
    return A


def test_a_singular_factorisation_raises_on_every_rank_with_mumps_info(comm):
    # a zero pivot on the last row: MUMPS reports it as numerically singular
    A = diagonal(comm, [1.0] * 7 + [0.0])
    ksp = create_ksp(A, "hfcdem_test_singular_", DIRECT_LU)
    b = A.createVecLeft()
    b.set(1.0)
    x = A.createVecRight()
    ksp.solve(b, x)
    with pytest.raises(SolverError) as err:
        check_ksp(ksp, "test solve", "a hint")
    # every rank raised (the assertion block is reached on all), with the same cause
    assert err.value.reason < 0
    assert err.value.mumps_info is not None and err.value.mumps_info < 0
    text = str(err.value)
    assert "DIVERGED_PCSETUP_FAILED" in text and "INFOG(1)" in text and "a hint" in text
    assert "hfcdem_test_singular_" in text
    reasons = comm.allgather((err.value.reason, err.value.mumps_info))
    assert len(set(reasons)) == 1
    for obj in (ksp, A, b, x):
        obj.destroy()


def test_a_converged_solve_passes_the_check(comm):
    A = diagonal(comm, [2.0] * 6)
    ksp = create_ksp(A, "hfcdem_test_ok_", DIRECT_LU)
    b = A.createVecLeft()
    b.set(1.0)
    x = A.createVecRight()
    ksp.solve(b, x)
    check_ksp(ksp, "test solve")
    assert x.min()[1] == pytest.approx(0.5) and x.max()[1] == pytest.approx(0.5)
    for obj in (ksp, A, b, x):
        obj.destroy()


def test_options_in_code_yield_to_the_users_and_leave_the_database_clean():
    db = PETSc.Options()
    db.setValue("hfcdem_test_opt_ksp_type", "cg")
    try:
        with petsc_options("hfcdem_test_opt_", {"ksp_type": "preonly", "pc_type": "lu"}):
            assert db.getString("hfcdem_test_opt_ksp_type") == "cg"
            assert db.getString("hfcdem_test_opt_pc_type") == "lu"
        assert not db.hasName("hfcdem_test_opt_pc_type")
        assert db.getString("hfcdem_test_opt_ksp_type") == "cg"
    finally:
        db.delValue("hfcdem_test_opt_ksp_type")


def test_reason_names_are_petsc_names():
    assert reason_name(-11).startswith("DIVERGED_PC")
    assert reason_name(PETSc.KSP.ConvergedReason.DIVERGED_MAX_IT) == "DIVERGED_MAX_IT (-3)"
    assert reason_name(12345) == "12345"


def test_a_workspace_too_small_is_retried_with_doubled_room():
    # MUMPS returns -9 under load until the relaxation reaches 80 %
    tried = []

    def attempt(relaxation):
        tried.append(relaxation)
        return 0 if relaxation is not None and relaxation >= 80 else -9

    assert retry_factorisation(attempt) == 0
    assert tried == [None, 40, 80]


def test_other_failures_and_successes_are_not_retried():
    for code in (0, -10, None):
        tried = []
        assert retry_factorisation(lambda r, c=code, t=tried: t.append(r) or c) == code
        assert tried == [None]
    tried = []
    assert retry_factorisation(lambda r: tried.append(r) or -9, tries=2) == -9
    assert tried == [None, 40, 80]


def test_setup_factorisation_gives_a_working_factorisation(comm):
    A = diagonal(comm, [4.0] * 5)
    ksp = setup_factorisation(lambda: create_ksp(A, "hfcdem_test_setup_", DIRECT_LU), comm)
    assert ksp.getPC().getFactorMatrix().getMumpsInfog(1) == 0
    b = A.createVecLeft()
    b.set(1.0)
    x = A.createVecRight()
    ksp.solve(b, x)
    check_ksp(ksp, "test solve")
    assert x.max()[1] == pytest.approx(0.25)
    for obj in (ksp, A, b, x):
        obj.destroy()


def test_right_hand_sides_solved_together_are_those_solved_one_by_one(comm):
    values = [1.0 + i for i in range(9)]
    A = diagonal(comm, values)
    ksp = create_ksp(A, "hfcdem_test_together_", DIRECT_LU)
    lo, hi = A.getOwnershipRange()
    rhs = []
    for k in range(3):
        b = A.createVecLeft()
        b.setArray([(k + 1.0) * (i + 2.0) for i in range(lo, hi)])
        rhs.append(b)
    solved = solve_together(ksp, rhs)
    assert solved.shape == (hi - lo, 3)
    for k, b in enumerate(rhs):
        x = A.createVecRight()
        ksp.solve(b, x)
        assert solved[:, k] == pytest.approx(x.getArray(), rel=1e-15)
        exact = [(k + 1.0) * (i + 2.0) / (1.0 + i) for i in range(lo, hi)]
        assert solved[:, k] == pytest.approx(exact, rel=1e-15)


def tight_cg(A: PETSc.Mat, comm: MPI.Comm) -> PETSc.KSP:
    """A set-up CG (Jacobi, to 1e-14): a solver without a factor."""
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType("jacobi")
    ksp.setTolerances(rtol=1e-14, atol=0.0)
    ksp.setUp()
    return ksp


@pytest.mark.parametrize("solver", ["mumps", "cg"])
def test_sparse_columns_are_the_dense_columns_on_those_rows(comm, solver):
    A = chain()  # SPD tridiagonal, 40 unknowns: every solution reaches every row
    if solver == "mumps":
        ksp = create_ksp(A, "hfcdem_test_sparse_", DIRECT_LU)
        ksp.setUp()
    else:  # no factor to hand a sparse right-hand side: dense columns
        ksp = tight_cg(A, comm)
    lo, hi = A.getOwnershipRange()
    rows = np.array([3, 17, 18, 35])  # on both ranks' parts under mpirun -n 2
    values = np.arange(1.0, 1.0 + 4 * 3).reshape(4, 3)
    block = np.zeros((hi - lo, 3))
    mine = (rows >= lo) & (rows < hi)
    block[rows[mine] - lo] = values[mine]
    sparse = solve_sparse_columns(ksp, rows, values)
    assert sparse.shape == (hi - lo, 3)
    dense = solve_columns(ksp, block)
    rel = 1e-15 if solver == "mumps" else 1e-12
    assert sparse == pytest.approx(dense, rel=rel, abs=rel * np.abs(dense).max())
    # and they solve the system: the residual of every column
    for k in range(3):
        x, r = A.createVecRight(), A.createVecLeft()
        x.setArray(sparse[:, k])
        A.mult(x, r)
        assert r.getArray() == pytest.approx(block[:, k], abs=1e-12 * np.abs(values).max())
        x.destroy()
        r.destroy()
    ksp.destroy()
    A.destroy()


@pytest.mark.parametrize("solver", ["mumps", "cg"])
def test_inverse_entries_are_the_dense_inverse_s_block(comm, solver):
    A = chain()  # SPD tridiagonal: its inverse is dense, every entry non-zero
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    if solver == "mumps":
        ksp = create_ksp(A, "hfcdem_test_inverse_", DIRECT_CHOLESKY)
        ksp.setUp()
    else:  # no MUMPS factor: the columns solved, their rows kept
        ksp = tight_cg(A, comm)
    n = A.getSize()[0]
    lo, hi = A.getOwnershipRange()
    dense = np.zeros((n, n))
    dense[lo:hi] = A.getValues(range(lo, hi), range(n))
    inverse = np.linalg.inv(comm.allreduce(dense, op=MPI.SUM))
    rows = np.array([35, 3, 18, 17, 30])  # unsorted, on both ranks' parts under mpirun -n 2
    columns = np.array([18, 3, 39])
    block = inverse_entries(ksp, rows, columns)
    assert block.shape == (5, 3)
    want = inverse[np.ix_(rows, columns)]
    rel = 1e-14 if solver == "mumps" else 1e-11
    assert np.abs(block - want).max() < rel * np.abs(want).max()
    # the same on every rank, and the factor's plain solves work after it
    assert comm.allreduce(float(np.abs(block - comm.bcast(block)).max()), op=MPI.MAX) == 0.0
    x = solve_columns(ksp, np.ones((hi - lo, 1)))
    assert x[:, 0] == pytest.approx(inverse[lo:hi].sum(axis=1), rel=1e-12)
    assert inverse_entries(ksp, np.zeros(0, dtype=int), columns).shape == (0, 3)
    with pytest.raises(ValueError, match="columns must be distinct"):
        inverse_entries(ksp, rows, np.array([3, 3]))
    ksp.destroy()
    A.destroy()


def test_mumps_orderings_names_only_the_orderings_that_ran():
    found = mumps_orderings()
    assert set(found) <= {"metis", "pord", "scotch"}
    assert "pord" in found  # MUMPS always carries its own PORD
    assert found == sorted(found)


@pytest.mark.skipif(not os.environ.get("HFCDEM_IMAGE"), reason="the image's MUMPS build only")
def test_the_image_s_mumps_orders_with_metis_and_scotch():
    # docker/build-mumps.sh: Debian's own libmumps links neither
    assert mumps_orderings() == ["metis", "pord", "scotch"]
