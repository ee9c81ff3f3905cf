"""history.csv: written whole once, then appended a row per step, read back exactly."""

import pytest
from mpi4py import MPI

from hfcdem.io.history import HistoryFile


def test_rows_are_appended_and_read_back_to_the_last_digit(shared_tmp_path, comm):
    path = shared_tmp_path / "history.csv"
    rows = [{"time": 0.1 * k, "p": 1e6 / 3.0 + k} for k in range(1, 4)]
    history = HistoryFile(path, ["time", "p"], comm)
    history.start(rows[:1])
    for row in rows[1:]:
        history.append(row)
    comm.barrier()
    assert history.read() == rows  # full precision: 0.30000000000000004 survives
    assert history.read(limit=2) == rows[:2]
    if comm.rank == 0:
        assert len(path.read_text().splitlines()) == 1 + len(rows)


@pytest.mark.serial
def test_start_replaces_the_file_with_the_kept_rows(tmp_path):
    path = tmp_path / "history.csv"
    history = HistoryFile(path, ["time"], MPI.COMM_SELF)
    history.start([{"time": 1.0}, {"time": 2.0}])
    history.append({"time": 3.0})
    history.start([{"time": 1.0}])  # a resume that keeps one step
    assert history.read() == [{"time": 1.0}]
