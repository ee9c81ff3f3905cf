"""The hfcdem command line."""

import pytest

from hfcdem.cli import breakdown_words, first_crack_pressure_words, main, split_petsc_options


def test_info_prints_the_stack(capsys):
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        for key in ("dolfinx", "petsc", "mumps_orderings", "gmsh", "mpi", "ranks"):
            assert key in out
        assert "\x00" not in out  # Open MPI's library string ends in a NUL
        assert "0.9" in out.split("dolfinx", 1)[1].splitlines()[0]


def test_no_command_prints_help_and_fails(capsys):
    assert main([]) == 2
    assert "usage: hfcdem" in capsys.readouterr().err


def test_unknown_command_exits_with_usage():
    with pytest.raises(SystemExit) as err:
        main(["frobnicate"])
    assert err.value.code == 2


def test_petsc_options_are_split_from_the_command_line():
    ours, petsc = split_petsc_options(
        [
            "run",
            "s.toml",
            "-o",
            "out",
            "-hfcdem_solid_pc_factor_mat_solver_type",
            "mumps",
            "--set",
            "a=1",
            "-log_view",
            "-mat_mumps_icntl_14",
            "-5",
            "--force",
        ]
    )
    assert ours == ["run", "s.toml", "-o", "out", "--set", "a=1", "--force"]
    assert petsc == {
        "hfcdem_solid_pc_factor_mat_solver_type": "mumps",
        "log_view": "",
        "mat_mumps_icntl_14": "-5",
    }


def test_petsc_options_on_the_command_line_reach_the_options_database():
    from petsc4py import PETSc

    db = PETSc.Options()
    try:
        assert main(["info", "-hfcdem_cli_test_value", "7", "-hfcdem_cli_test_flag"]) == 0
        assert db.getInt("hfcdem_cli_test_value") == 7
        assert db.hasName("hfcdem_cli_test_flag")
    finally:
        db.delValue("hfcdem_cli_test_value")
        db.delValue("hfcdem_cli_test_flag")


def test_set_with_an_empty_value_removes_the_field_so_its_default_applies():
    from hfcdem.cli import _overrides
    from hfcdem.config.scene import load_scene

    sets = _overrides(["injection.wall_film=", "injection.wall_joints=seepage", "a.b='1 s'"])
    assert sets == {"injection.wall_film": None, "injection.wall_joints": "seepage", "a.b": "1 s"}
    no2 = "meshes/scenes/perforation_no2.toml"
    assert load_scene(no2).physics.wall_film == pytest.approx(5e-6)
    scene = load_scene(no2, overrides={"injection.wall_film": None})
    assert scene.physics.wall_film is None


def test_the_last_line_gives_the_breakdown_or_why_not_with_the_highest_pressure():
    # the shipped lab at 30 deg (coarse): a drop confirmed 4.61 MPa, then the pressure rose
    # to 10.12 MPa before the validity limit ended the run
    doubted = {
        "breakdown_pressure_MPa": 4.6123,
        "breakdown_time_s": 0.75,
        "breakdown_note": "the pressure rose past it (...)",
        "peak_pressure_MPa": 10.1234,
    }
    assert breakdown_words(doubted) == (
        "4.61 MPa at 0.75 s (the pressure rose past it (...); highest pressure 10.12 MPa)"
    )
    stood = {**doubted, "breakdown_note": None, "peak_pressure_MPa": 4.6123}
    assert breakdown_words(stood) == "4.61 MPa at 0.75 s"
    # how far the pressure fell after the breakdown says how firm it is
    assert breakdown_words({**stood, "breakdown_drop_MPa": 1.41}) == (
        "4.61 MPa at 0.75 s (the pressure fell 1.41 MPa after it)"
    )
    none = {**doubted, "breakdown_pressure_MPa": None, "breakdown_note": "still rises"}
    assert breakdown_words(none) == "none (still rises; highest pressure 10.12 MPa)"
    assert breakdown_words({**none, "breakdown_note": None}) == "none"
    # a pumped run's note quotes its highest pressure already: not said twice
    quoted = {**doubted, "breakdown_note": "the pressure rose past it to 10.12 MPa (at 3 s)"}
    assert breakdown_words(quoted) == (
        "4.61 MPa at 0.75 s (the pressure rose past it to 10.12 MPa (at 3 s))"
    )


def test_ctrl_c_ends_with_one_line_and_exit_130(monkeypatch, capsys):
    import hfcdem.cli as cli

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_info", interrupted)
    assert main(["info"]) == 130
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert err.startswith("interrupted: ") and "Traceback" not in err


def test_a_first_crack_no_step_landed_on_is_said_as_a_range():
    def said(low, high):
        summary = {"first_crack_pressure_MPa": low, "first_crack_pressure_bound_MPa": high}
        return first_crack_pressure_words(summary)

    assert said(0.0, 2.29) == "between 0.00 and 2.29 MPa (no step landed on it)"
    assert said(61.644, 61.644) == "61.64 MPa"  # landed: one value
    assert said(61.644, 61.6441) == "61.64 MPa"
    assert said(62.1, 61.9) == "62.10 MPa"  # the pressure fell before the crack
    assert said(8.8, None) == "8.80 MPa"  # a summary from before the bound


def test_a_study_whose_case_stopped_ends_with_4_after_its_table(monkeypatch, capsys):
    from mpi4py import MPI

    import hfcdem.workflows.study as study_module

    rows = [
        {"case": 0, "value": "1e-3 m3/s", "stopped": None},
        {"case": 1, "value": "2e-3 m3/s", "stopped": "did not settle in 200 iterations"},
        {"case": 2, "value": "4e-3 m3/s", "stopped": "a block came loose", "validity_limit": True},
    ]
    monkeypatch.setattr(study_module, "run_study", lambda *args, **kwargs: rows)
    assert main(["study", "studies/kgd_rate.toml", "-o", "unused"]) == 4
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert err == "cases that stopped before their end: 2e-3 m3/s (results.csv)\n"
    monkeypatch.setattr(study_module, "run_study", lambda *args, **kwargs: rows[::2])
    assert main(["study", "studies/kgd_rate.toml", "-o", "unused"]) == 0
