"""Results on disk are written whole or not at all."""

import json
import os
from pathlib import Path

import pytest
from mpi4py import MPI

from hfcdem.io.files import prepare_output_dir, read_json, write_atomic, write_csv, write_json


def test_json_and_csv_round_trip(shared_tmp_path):
    out = prepare_output_dir(shared_tmp_path / "run")
    write_json(out / "summary.json", {"pressure_MPa": 64.0, "counts": (1, 2)})
    write_csv(out / "h.csv", ["t", "p"], [(0.0, 1.0), (1.0, 2.5)])
    assert json.loads((out / "summary.json").read_text()) == {
        "pressure_MPa": 64.0,
        "counts": [1, 2],
    }
    assert (out / "h.csv").read_text().splitlines() == ["t,p", "0,1", "1,2.5"]


@pytest.mark.serial
def test_failed_write_keeps_the_previous_file(tmp_path, monkeypatch):
    target = tmp_path / "summary.json"
    target.write_text("good\n")
    real_replace = os.replace

    def interrupted(src, dst):
        # the new text is fully written to the temporary file; the rename never happens
        assert Path(src).read_text() == "new text"
        raise KeyboardInterrupt("interrupted before the rename")

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt, match="interrupted before the rename"):
        write_atomic(target, "new text")
    monkeypatch.setattr(os, "replace", real_replace)
    assert target.read_text() == "good\n"
    assert os.listdir(tmp_path) == ["summary.json"]  # no temporary file left behind


@pytest.mark.serial
def test_unwritable_output_dir_is_a_clear_error(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(OSError, match="cannot create output directory"):
        prepare_output_dir(tmp_path / "file" / "sub", MPI.COMM_SELF)


def test_read_json_is_rank_0s_on_every_rank_and_fails_on_every_rank(shared_tmp_path):
    comm = MPI.COMM_WORLD
    path = shared_tmp_path / "state.json"
    assert read_json(path, comm) is None  # no such file
    write_json(path, {"steps": 3}, comm)
    assert read_json(path, comm) == {"steps": 3}
    if comm.rank == 0:
        path.write_text('{"steps": ')  # cut short
    comm.barrier()
    with pytest.raises(ValueError, match=r"state\.json cannot be read"):
        read_json(path, comm)  # on every rank: none is left waiting
