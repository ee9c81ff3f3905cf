"""The time-step check of a run: the same run at half the step, and how far its answers move."""

import json
from pathlib import Path

import pytest
from mpi4py import MPI

from hfcdem.cli import main
from hfcdem.config.scene import load_scene
from hfcdem.config.tables import SceneError
from hfcdem.workflows.time_step_check import check_words, compare_steps, halved_steps

SCENES = Path(__file__).resolve().parents[1] / "meshes/scenes"
PUMPING = SCENES / "borehole_pumping.toml"


def test_the_steps_a_scene_fixes_are_halved_and_a_run_without_them_is_refused():
    # a pumped seepage run steps at time_step (0.1 s): that alone is halved
    assert halved_steps(load_scene(PUMPING, "coarse")) == {"solver.time_step": "0.05 s"}
    # a KGD run grows its steps up to max_time_step (0.5 s): both are halved
    kgd = load_scene(SCENES / "kgd_strip.toml", "coarse")
    assert halved_steps(kgd) == {"solver.time_step": "0.25 s", "solver.max_time_step": "0.25 s"}
    # without a cap its steps grow freely: halving the first would refine nothing
    free = load_scene(SCENES / "kgd_strip.toml", "coarse", overrides={"solver.max_time_step": None})
    with pytest.raises(SceneError, match=r"^--check-time-step: .*give solver.max_time_step"):
        halved_steps(free)
    with pytest.raises(SceneError, match=r"^--check-time-step: a static \[load\] scene"):
        halved_steps(load_scene(SCENES / "sneddon_plate.toml"))


def _summary(breakdown, peak, first, note=None, kind="seepage_pumping"):
    return {
        "kind": kind,
        "breakdown_pressure_MPa": breakdown,
        "peak_pressure_MPa": peak,
        "first_crack_pressure_MPa": first,
        "first_crack_time_s": 1.0 if first else None,
        "breakdown_note": note,
    }


def test_the_check_says_the_move_of_the_breakdown_and_the_first_crack():
    # borehole_pumping at 500 times its rate, coarse (measured 2026-12-07)
    doubt = "the pressure rose past it (...)"
    check = compare_steps(_summary(61.21, 200.6, 14.42, doubt), _summary(106.14, 170.0, 14.42), 0.1)
    moved = check["answers"]["breakdown_pressure_MPa"]
    assert moved["change"] == pytest.approx(44.93)
    assert moved["relative_change"] == pytest.approx(44.93 / 106.14)
    assert moved["first_order_error"] == pytest.approx(2 * 44.93)
    assert check_words(check) == (
        "time step: halving it (0.1 -> 0.05 s) moves the breakdown 61.21 -> 106.14 MPa "
        "(+42.33%), the first crack 14.42 -> 14.42 MPa (0.00%); at first order in the step, "
        "this run's own error is about twice the larger move (84.66%); a breakdown is in "
        "doubt (its note: time_step_check.json)"
    )
    # a breakdown in one run only: the highest pressure is compared, and that is said
    one = compare_steps(_summary(61.21, 70.0, 14.42), _summary(None, 69.3, 14.0), 0.1)
    said = check_words(one)
    assert said.startswith("time step: halving it (0.1 -> 0.05 s) moves the highest pressure ")
    assert said.endswith("; only the run at 0.1 s found a breakdown")
    # a crack that only propagates (KGD) has no breakdown and its highest pressure is its
    # first step's: its fluid front is compared; a pre-existing crack's "first crack" is not
    kgd = [{**_summary(None, p, 0.0), "fluid_front_m": x} for p, x in ((1.24, 22.0), (1.79, 21.0))]
    assert check_words(compare_steps(*kgd, 0.5)) == (
        "time step: halving it (0.5 -> 0.25 s) moves the fluid front 22.00 -> 21.00 m "
        "(-4.76%); at first order in the step, this run's own error is about twice the "
        "larger move (9.52%)"
    )
    # a ramp's "breakdown" is its first break
    ramp = compare_steps(_summary(9.0, 9.0, 9.0, kind="seepage_ramp"), _summary(8.9, 8.9, 8.9), 1)
    assert check_words(ramp).startswith("time step: halving it (1 -> 0.5 s) moves the first break")


def test_a_run_checks_its_time_step_in_a_folder_of_its_own(shared_tmp_path, capsys):
    out = shared_tmp_path / "checked"
    args = ["run", str(PUMPING), "--resolution", "coarse", "-o", str(out)]
    two_seconds = ["--set", 'injection.duration="2 s"']
    assert main([*args, *two_seconds, "--check-time-step"]) == 0
    check = json.loads((out / "time_step_check.json").read_text())
    half = json.loads((out / "half_step" / "summary.json").read_text())
    assert (check["time_step_s"], check["half_step_s"], half["steps"]) == (0.1, 0.05, 40)
    # nothing breaks in 2 s; the joints along the wall take a little of the fluid, less
    # at the half step, so the pressure at 2 s rises 0.18 % (measured)
    peak = check["answers"]["peak_pressure_MPa"]
    assert peak["full_step"] == pytest.approx(2.304, abs=1e-3)
    assert peak["relative_change"] == pytest.approx(0.001785, abs=2e-5)
    assert peak["first_order_relative_error"] == pytest.approx(2 * peak["relative_change"])
    if MPI.COMM_WORLD.rank == 0:
        lines = capsys.readouterr().out.splitlines()
        assert lines[-1].startswith("time step: halving it (0.1 -> 0.05 s) moves the highest")
    # a run without the check leaves no earlier check to pass for its own
    assert main([*args, *two_seconds]) == 0
    assert not (out / "time_step_check.json").exists()


def test_a_static_scene_asked_for_the_check_runs_nothing(shared_tmp_path, capsys):
    out = shared_tmp_path / "static_checked"
    args = ["run", str(SCENES / "sneddon_plate.toml"), "-o", str(out), "--check-time-step"]
    assert main(args) == 2
    assert not out.exists()
    if MPI.COMM_WORLD.rank == 0:
        assert (
            "--check-time-step: a static [load] scene has no time step" in capsys.readouterr().err
        )
