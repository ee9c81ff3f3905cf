"""Run only by tests/test_suite_guard.py, under mpirun: rank 1 fails, rank 0 waits."""

from mpi4py import MPI


def test_rank_one_fails_while_rank_zero_waits():
    comm = MPI.COMM_WORLD
    assert comm.rank != 1, "rank 1 fails on purpose"
    comm.barrier()  # rank 0 waits here for a rank that will never come


def test_never_reached():
    MPI.COMM_WORLD.barrier()
