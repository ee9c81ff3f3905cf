"""The hfcdem command line."""

import pytest

from hfcdem.cli import main


def test_info_prints_the_stack(capsys):
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        for key in ("dolfinx", "petsc", "gmsh", "mpi", "ranks"):
            assert key in out
        assert "0.9" in out.split("dolfinx", 1)[1].splitlines()[0]


def test_no_command_prints_help_and_fails(capsys):
    assert main([]) == 2
    assert "usage: hfcdem" in capsys.readouterr().err


def test_unknown_command_exits_with_usage():
    with pytest.raises(SystemExit) as err:
        main(["frobnicate"])
    assert err.value.code == 2
