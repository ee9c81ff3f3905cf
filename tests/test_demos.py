"""The demos run end to end and reproduce what they claim."""

import importlib.util
import json
import re
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem import read_results

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def load(name):
    spec = importlib.util.spec_from_file_location(name, DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# A YAML header that jupytext reads as the notebook's metadata (under `jupyter:`, or
# it becomes a raw cell) naming the percent format, and that format's cell markers
# (jupytext takes them indented too, and `# %%%` as a sub-cell; an indented one is
# rejected: it splits a block, so its code cannot run alone and its markdown reads as
# an indented code block).
HEADER = re.compile(r"\A# ---\n((?:#.*\n)*?)# ---\n")
JUPYTEXT_KEYS = re.compile(r"^# jupyter:\n#   jupytext:\n", re.M)
PERCENT_FORMAT = re.compile(r"^#\s+(?:formats: .*py:percent|format_name: percent)\s*$", re.M)
CELL_MARKER = re.compile(r"^[ \t]*#\s*%%+(?:\s(.*))?$", re.M)


def literate_problems(text: str) -> list[str]:
    """What keeps a demo's text from being a literate jupytext percent script."""
    header = HEADER.match(text)
    if not (
        header and JUPYTEXT_KEYS.search(header.group(1)) and PERCENT_FORMAT.search(header.group(1))
    ):
        return ["does not start with a jupytext header naming the percent format"]
    body = text[header.end() :]
    markers = list(CELL_MARKER.finditer(body))
    if not markers or body[: markers[0].start()].strip():
        return ["has code before its first cell marker"]
    markdown = [re.search(r"\[(markdown|md)\]", m.group(1) or "") is not None for m in markers]
    problems = []
    indented = [m for m in markers if m.group(0)[0] in " \t"]
    if indented:
        lines = [text.count("\n", 0, header.end() + m.start()) + 1 for m in indented]
        problems.append(f"has cell markers inside a block (lines {lines})")
    if not markdown[0]:
        problems.append("starts with a code cell, not a markdown one")
    elif not re.match(r"\s*# # \S", body[markers[0].end() :]):
        problems.append("its first markdown cell has no title ('# # ...')")
    if sum(markdown) < 2:
        problems.append(f"has {sum(markdown)} markdown cell(s), fewer than 2")
    if all(markdown):
        problems.append("has no code cell")
    return problems


@pytest.mark.parametrize("path", sorted(DEMOS.glob("*.py")), ids=lambda p: p.stem)
def test_demo_is_a_literate_script_that_compiles(path):
    text = path.read_text()
    compile(text, str(path), "exec")  # a SyntaxError names the line
    assert literate_problems(text) == [], path.name


def test_the_literate_check_rejects_a_plain_script_and_a_bare_header():
    plain = '"""A demo."""\n\nprint(1)\n'
    header = "# ---\n# jupyter:\n#   jupytext:\n#     formats: py:percent\n# ---\n\n"
    assert literate_problems(plain)
    assert literate_problems(header + plain) == ["has code before its first cell marker"]
    one_cell = header + "# %% [markdown]\n# # Title\n\n# %%\nprint(1)\n"
    assert literate_problems(one_cell) == ["has 1 markdown cell(s), fewer than 2"]
    two_cells = one_cell + "\n# %% [markdown]\n# More.\n"
    assert literate_problems(two_cells) == []
    inside = two_cells + "\ndef f():\n    # %% [markdown]\n    # Inside.\n\n    # %%\n    pass\n"
    assert literate_problems(inside) == ["has cell markers inside a block (lines [17, 20])"]


def test_borehole_kirsch_demo_writes_its_results(shared_tmp_path):
    out = shared_tmp_path / "kirsch"
    summary = load("borehole_kirsch").main(["-o", str(out), "--size", "0.014"])
    assert summary["max_relative_error"] < 0.05
    assert summary["hoop_stress_theta0_MPa"] == pytest.approx(
        summary["kirsch_theta0_MPa"], rel=0.05
    )
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["cells"] == summary["cells"]
    for name in ("fields.xdmf", "fields.h5", "hoop_stress.csv", "hoop_stress.png", "sigma_xx.png"):
        assert (out / name).stat().st_size > 0, name


def test_borehole_breakdown_demo_breaks_along_sh_near_hubbert_willis(shared_tmp_path):
    out = shared_tmp_path / "breakdown"
    summary = load("borehole_breakdown").main(
        ["-o", str(out), "--size", "0.007", "--overpressure", "0.0"]
    )
    assert summary["breakdown_pressure_MPa"] == pytest.approx(
        summary["hubbert_willis_MPa"], rel=0.10
    )
    assert summary["first_crack_angle_from_SH_deg"] < 5.0
    assert summary["first_crack_mode"] == "tensile"
    assert 0.0 < summary["fracture_degree"] < 1.0
    for name in ("summary.json", "fracture.png", "sigma_yy.png", "interfaces.vtu"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "fields.bp").is_dir()


def test_borehole_breakdown_demo_keeps_its_results_when_a_cascade_does_not_settle(
    shared_tmp_path, capsys
):
    out = shared_tmp_path / "cascade"
    # one re-solve per pressure level: the cascade at the first break cannot settle
    summary = load("borehole_breakdown").main(
        ["-o", str(out), "--size", "0.014", "--max-iterations", "1"]
    )
    assert "did not settle in 1 iterations" in summary["stopped"]
    assert summary["breakdown_pressure_MPa"] <= summary["reached_pressure_MPa"]
    assert summary["reached_pressure_MPa"] < summary["final_pressure_MPa"]
    assert summary["tensile_failures"] + summary["shear_failures"] >= 1
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["stopped"] == summary["stopped"]
    for name in ("fracture.png", "sigma_yy.png", "interfaces.vtu"):
        assert (out / name).stat().st_size > 0, name
    printed = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # only rank 0 prints
        assert printed.count("the cascade did not settle at") == 1


def test_kgd_demo_matches_the_self_similar_solution(shared_tmp_path):
    out = shared_tmp_path / "kgd"
    summary = load("kgd_fracture").main(["-o", str(out), "--dx", "1.0"])
    for key in ("half_length_m", "net_pressure_MPa", "inlet_opening_mm"):
        assert summary[key] == pytest.approx(summary[f"kgd_{key}"], rel=0.10), key
    assert summary["max_mass_error"] < 1e-6
    for name in ("summary.json", "history.csv", "kgd.png", "fracture.vtu"):
        assert (out / name).stat().st_size > 0, name
    header = (out / "history.csv").read_text().splitlines()[0].split(",")
    assert {"time", "injection_pressure", "injected_volume", "fracture_volume"} <= set(header)


def test_perforation_no2_demo_runs_the_scene_and_names_its_files(shared_tmp_path, capsys):
    out = shared_tmp_path / "no2"
    summary = load("perforation_no2").main(["-o", str(out), "--duration", "1 s"])
    assert summary["scene"] == "perforation_no2"
    assert summary["simulated_time_s"] == pytest.approx(1.0)
    assert summary["stopped"] is None
    assert summary["initial_failures"] >= 0
    # closed form: 60 / 73 / 76 MPa compress the tunnel's wall (no in-situ tension); the
    # cased wellbore keeps its in-situ traction, no hole to check
    walls = summary["in_situ_wall_tension"]
    assert [w["hole"] for w in walls] == ["perforation 1"]
    assert all(w["tension_MPa"] == 0.0 and not w["exceeds"] for w in walls)
    # pumping into the closed cavity raises the pressure from the 30 MPa start, step by step
    history = read_results(out).history
    pressure = history["injection_pressure"]
    assert len(pressure) >= 2 and pressure[0] > 30e6
    assert np.all(np.diff(pressure) > 0.0)
    assert summary["peak_pressure_MPa"] == pytest.approx(pressure.max() / 1e6)
    for name in ("summary.json", "history.csv", "pressure.png", "fracture.png", "interfaces.pvd"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "fields.bp").is_dir()
    printed = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # only rank 0 prints
        assert "paper 64.01 MPa" in printed
        assert "fracture.png" in printed


def test_joint_seepage_demo_fills_the_joints_around_no2_from_dry(shared_tmp_path, capsys):
    out = shared_tmp_path / "seepage"
    result = load("joint_seepage").main(["-o", str(out), "--times", "0.05,1"])
    # the paper's permeability coefficient 8.33e-11 m^2/(Pa s) as a^2 / (12 mu), water
    assert result["aperture_m"] == pytest.approx(1.0e-6, rel=1e-3)
    rows = result["rows"]
    filled = np.array([r["fluid_over_void"] for r in rows])
    full = np.array([r["full_share_of_joints"] for r in rows])
    # full joints hold V (1 + p / Kw): the scene's Kw is the paper's 10 MPa, p 60 MPa
    assert filled[0] > 0.0 and np.all(np.diff(filled) > 0.0) and filled[-1] < 1.0 + 60 / 10
    assert np.all(np.diff(full) >= 0.0) and full[-1] > full[0] + 0.2
    assert rows[-1]["time_s"] == pytest.approx(1.0)
    frames = (out / "joints.pvd").read_text()
    assert frames.count("<DataSet") == 2
    for name in ("seepage.csv", "saturation.png", "joints/frame_0001.vtu"):
        assert (out / name).stat().st_size > 0, name
    if MPI.COMM_WORLD.rank == 0:
        assert "saturation.png" in capsys.readouterr().out


def test_field_cluster_demo_starts_from_the_completion_pressure(shared_tmp_path, capsys):
    out = shared_tmp_path / "field"
    summary = load("field_cluster").main(["-o", str(out), "--duration", "1 s"])
    assert summary["scene"] == "field_cluster"
    assert summary["simulated_time_s"] == pytest.approx(1.0)
    assert summary["stopped"] is None
    # pumping into the cased well's six tunnels raises the pressure from the 17 MPa start
    assert summary["peak_pressure_MPa"] > 17.0
    assert summary["cells"] > 10_000
    printed = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # only rank 0 prints
        assert "field 43.0 MPa" in printed


def test_shape_study_demo_sweeps_profiles_and_checks_orderings(shared_tmp_path, capsys):
    out = shared_tmp_path / "shapes"
    rows = load("shape_study").main(["-o", str(out), "--models", "no2,1-2", "--duration", "0.5 s"])
    assert [r["value"] for r in rows] == ["no2", "1-2"]
    lines = (out / "results.csv").read_text().splitlines()
    assert lines[1].startswith("no2,0,") and lines[2].startswith("1-2,1,")
    # each case ran its scene: the pressure rose from the 30 MPa start
    for row in rows:
        assert row["peak_pressure_MPa"] > 30.0
        assert row["stopped"] is None
    printed = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # only rank 0 prints
        assert "paper 64.01 MPa" in printed and "paper 53.86 MPa" in printed


def test_sneddon_demo_matches_eq_21_on_a_wide_plate(shared_tmp_path, capsys):
    out = shared_tmp_path / "sneddon"
    from petsc4py import PETSc

    # a PETSc option on a demo's line reaches PETSc (the direct solve stays the default)
    argv = ["-o", str(out), "--half-width", "5", "--alpha", "1000", "--size", "0.01"]
    try:
        summary = load("sneddon_plate").main([*argv, "-hfcdem_demo_test_option", "3"])
        assert PETSc.Options().getInt("hfcdem_demo_test_option") == 3
    finally:
        PETSc.Options().delValue("hfcdem_demo_test_option")
    assert abs(summary["sneddon"]["centre_relative_error"]) < 0.02
    assert summary["sneddon"]["max_relative_error_inner"] < 0.05
    assert len(summary["sneddon"]["points"]) == 11
    assert (out / "crack_opening.png").stat().st_size > 0
    printed = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # only rank 0 prints
        assert "eq. (21)" in printed


def test_api_tour_runs_the_chain_and_reads_back_sneddons_plate(shared_tmp_path):
    out = shared_tmp_path / "api_tour"
    tour = load("api_tour").main(["-o", str(out)])
    # the 1 m plate with a fixed edge: stiffer than Sneddon's infinite plate (README: -3.8 %)
    gap = tour["centre_uy_m"] / tour["sneddon_centre_uy_m"] - 1.0
    assert -0.06 < gap < -0.02
    assert tour["cells"] > 100
    assert (out / "crack_opening.csv").stat().st_size > 0


def test_a_demo_given_bad_input_ends_with_one_line_naming_the_field(shared_tmp_path, capsys):
    from hfcdem.workflows.demos import run_demo

    # before, a --duration that is no time ended in a SceneError traceback on every rank
    out = shared_tmp_path / "bad_duration"
    no2 = load("perforation_no2")
    with pytest.raises(SystemExit) as ended:
        run_demo(lambda: no2.main(["-o", str(out), "--duration", "abc"]))
    assert ended.value.code == 2
    assert not out.exists()  # nothing was meshed or written
    seepage = load("joint_seepage")
    with pytest.raises(SystemExit) as ended:
        run_demo(lambda: seepage.main(["-o", str(out), "--times", "1,x"]))
    assert ended.value.code == 2
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err.splitlines()
        assert err == [
            "error: perforation_no2.toml: injection.duration: expected a time such as "
            "'60 s', got 'abc'",
            "error: --times: expected positive seconds such as '1,10,60', got '1,x'",
        ]


@pytest.mark.parametrize(
    ("error", "message"),
    [
        ("OutputInUse", "results/x holds another scene's results"),  # kept, not overwritten
        # before, a demo ended this in a traceback on every rank; hfcdem run said one line
        ("MeshingError", "the model has no named cell group"),
    ],
)
def test_a_refused_output_or_an_unmeshable_geometry_ends_a_demo_with_one_line_and_exit_3(
    error, message, capsys
):
    from hfcdem.mesh.tagged import MeshingError
    from hfcdem.workflows.demos import run_demo
    from hfcdem.workflows.run import OutputInUse

    kind = {"OutputInUse": OutputInUse, "MeshingError": MeshingError}[error]

    def fail():
        raise kind(message)

    with pytest.raises(SystemExit) as ended:
        run_demo(fail)
    assert ended.value.code == 3
    if MPI.COMM_WORLD.rank == 0:
        assert capsys.readouterr().err == f"error: {message}\n"


def test_a_demo_keeps_the_traceback_of_an_unforeseen_error():
    from hfcdem.workflows.demos import run_demo

    def bug():
        raise ZeroDivisionError("a bug")

    with pytest.raises(ZeroDivisionError):
        run_demo(bug)


def test_a_demo_whose_run_stopped_ends_as_hfcdem_run_does():
    from hfcdem.workflows.demos import run_demo

    # before, a demo ended 0 where hfcdem run, on the same stop, ended 4
    for stopped in (
        {"stopped": "the cascade did not settle", "breakdown_pressure_MPa": 9},
        [{"stopped": None}, {"stopped": "a case's solver gave up"}],  # a study's rows
    ):
        with pytest.raises(SystemExit) as ended:
            run_demo(lambda stopped=stopped: stopped)
        assert ended.value.code == 4
    run_demo(lambda: {"stopped": "a block came loose", "validity_limit": True})  # 0: returns
    run_demo(lambda: [{"stopped": None}, {}])  # a case not run has no summary
    run_demo(lambda: {"centre_uy_m": 1e-5})  # a demo that shows no run


def test_a_study_demo_takes_the_scene_and_study_options():
    from hfcdem.workflows.demos import demo_parser

    args = demo_parser("Four charges.\n\nMore.", "results/x", study=True).parse_args(
        ["--resolution", "default", "--duration", "30 s", "--groups", "2", "--force"]
    )
    assert (args.output, args.resolution, args.duration) == ("results/x", "default", "30 s")
    assert args.groups == 2 and args.force
    plain = demo_parser(None, "results/y", scene=False).parse_args([])
    assert vars(plain) == {"output": "results/y", "force": False}
