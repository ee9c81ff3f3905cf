"""Progress lines of long loops: every tenth of the steps, and at least every so often."""

import time

import pytest
from mpi4py import MPI

from hfcdem.io.progress import Cadence


def test_a_line_every_tenth_of_the_steps_and_on_events():
    cadence = Cadence(200, MPI.COMM_WORLD, seconds=1e6)
    due = [n for n in range(1, 201) if cadence.due(n, event=n == 33)]
    assert due == [20, 33, 40, 60, 80, 100, 120, 140, 160, 180, 200]
    assert Cadence(7, MPI.COMM_WORLD).every == 1  # fewer steps than parts: every step


def test_a_slow_loop_says_where_it_is_before_its_tenth(monkeypatch):
    # 2,500 steps (a ramp's small pressure_step): the 250th would come after minutes
    clock = [0.0]
    monkeypatch.setattr(time, "monotonic", lambda: clock[0])
    cadence = Cadence(2500, MPI.COMM_WORLD, seconds=30.0)
    due = []
    for n in range(1, 101):
        clock[0] += 4.0  # wall seconds a step
        if cadence.due(n):
            due.append(n)
    assert due == [8, 16, 24, 32, 40, 48, 56, 64, 72, 80, 88, 96]
    # the same on every rank (a line may need a collective to write)
    assert MPI.COMM_WORLD.allgather(due) == [due] * MPI.COMM_WORLD.size


def test_bad_cadences_are_refused():
    with pytest.raises(ValueError, match="parts must be >= 1"):
        Cadence(10, MPI.COMM_WORLD, parts=0)
