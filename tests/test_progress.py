"""Progress lines of long loops: every tenth of the steps, and at least every so often."""

import math
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


def test_the_time_left_follows_the_recent_pace_not_the_mean():
    from hfcdem.io.progress import TimeLeft

    # quiet for 35 s of simulated time in 200 s of wall time, then a cascade at 60 s a second
    left = TimeLeft(t_end=38.0)
    for k in range(1, 36):
        left.add(float(k), 200.0 * k / 35.0)
    assert left.seconds() == pytest.approx(3.0 * 200.0 / 35.0)  # the pace so far: 17 s
    for k in range(1, 6):
        left.add(35.0 + 0.2 * k, 200.0 + 12.0 * k)
    # 260 s spent; the recent quarter (from 195 s) is the cascade and the quiet step before it
    recent = (260.0 - 200.0 * 34 / 35) / (36.0 - 34.0)
    assert left.seconds() == pytest.approx(recent * 2.0)
    assert left.seconds() > 4.0 * (260.0 / 36.0 * 2.0)  # the mean pace would say 14 s
    assert left.words() == "wall 260 s, about 66 s left at the recent pace"


def test_the_time_left_is_unknown_before_the_run_moves_and_zero_at_its_end():
    from hfcdem.io.progress import TimeLeft, duration_words

    left = TimeLeft(t_end=10.0, t_start=4.0)  # a resumed run: the pace from where it began
    assert math.isnan(left.seconds()) and left.words().endswith("about ? left at the recent pace")
    left.add(5.0, 30.0)
    assert left.seconds() == pytest.approx(150.0)
    left.add(10.0, 40.0)
    assert left.seconds() == 0.0
    said = [duration_words(s) for s in (42.4, 720.0, 12240.0, -1.0)]
    assert said == ["42 s", "12 min", "3.4 h", "?"]
    with pytest.raises(ValueError, match="recent"):
        TimeLeft(10.0, recent=0.0)
