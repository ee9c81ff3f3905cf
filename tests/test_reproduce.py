"""`hfcdem reproduce`: the report of the four papers, at CI size (two quick cases)."""

import csv
import dataclasses
import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from stopping import Interrupted, StopAt

from hfcdem import references
from hfcdem.cli import main
from hfcdem.config.scene import load_scene
from hfcdem.reproduce import cases
from hfcdem.reproduce.cases import CASES, Tier, select_cases
from hfcdem.reproduce.compare import (
    DEGREE_FIGURE,
    PEAK_MESH_ERROR,
    SHARE_NOT_CONVERGED,
    STRESS_FIGURE,
    WITHIN_ERROR,
    CaseResult,
    Comparison,
    all_tensile,
    charge_degrees,
    failure_modes,
    first_cracks,
    four_charges,
    lab_specimen,
    peak_against,
    peak_cut_short,
    resolved,
    shape_degrees,
    stress_at_root,
    stresses_at_roots,
    trend,
)
from hfcdem.reproduce.report import BEGIN, END, summary_table, update_readme
from hfcdem.reproduce.runner import ROOT, CaseRecord, case_status, run_reproduction


def _rows(path):
    with path.open() as f:
        return list(csv.DictReader(f))


def test_quick_report_of_sneddon_and_kgd_and_its_resume(shared_tmp_path, capsys):
    out = shared_tmp_path / "report"
    readme = shared_tmp_path / "README.md"
    if MPI.COMM_WORLD.rank == 0:
        readme.write_text(f"# title\n{BEGIN}\nold table\n{END}\nafter\n")
    MPI.COMM_WORLD.barrier()
    argv = ["reproduce", "--quick", "--only", "sneddon,kgd,griffith", "-o", str(out)]
    assert main([*argv, "--readme", str(readme)]) == 0
    text = readme.read_text()
    assert "old table" not in text and text.endswith(f"{END}\nafter\n")
    assert "| sneddon | crack-centre u_y |" in text
    assert "| griffith | crack-centre opening w |" in text
    printed = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert "[1/3] sneddon" in printed and "left in all" in printed
    rows = {(r["case"], r["quantity"]): r for r in _rows(out / "results.csv")}
    centre = rows[("sneddon", "crack-centre u_y")]
    # the 1 m fixed plate at coarse: -4.1 % of Sneddon's infinite plate
    assert centre["met"] == "met" and -0.05 < float(centre["gap"].rstrip("%")) / 100 < -0.03
    assert centre["resolution"].startswith("coarse (h = ")
    for quantity in ("half-length (fluid front)", "inlet net pressure", "inlet opening"):
        row = rows[("kgd", quantity)]
        assert row["met"] == "met", row
        assert abs(float(row["gap"].rstrip("%"))) < 8.0, row  # measured 6.6, 6.3, 2.6 %
    assert rows[("kgd", "breakdown peak")]["ours"] == "none"
    # Griffith under p - sigma0 on the 100 m fixed plate at coarse: -4.1 % of eq. (17)
    griffith = rows[("griffith", "crack-centre opening w")]
    assert griffith["met"] == "met" and -0.045 < float(griffith["gap"].rstrip("%")) / 100 < -0.035
    text = (out / "report.html").read_text()
    assert "figures/sneddon_crack_opening.png" in text and "Griffith" in text
    assert (out / "figures" / "gaps.png").stat().st_size > 5_000
    assert "| crack-centre u_y |" in (out / "report.md").read_text()
    first = json.loads((out / "cases" / "kgd" / "case.json").read_text())
    commit = rows[("kgd", "inlet opening")]["commit"]
    assert first["commit"] == commit and commit in (out / "report.md").read_text()

    # the tier's other cases are listed as not run, not left out
    others = {r["case"]: r for r in _rows(out / "results.csv")}
    assert others["lab_specimen"]["status"] == "not run"
    assert "not run yet" in (out / "report.md").read_text()

    # again: every case is done, nothing runs, the wall times are the first run's; the
    # report still holds griffith (read back, though not named) and lists the rest
    records = run_reproduction(out, tier="quick", only=["sneddon", "kgd"])
    assert [r.name for r in records] == ["sneddon", "kgd"]  # what this call ran
    assert all(r.skipped for r in records)
    listed = {r["case"]: r["status"] for r in _rows(out / "results.csv")}
    assert set(listed) == {c.name for c in select_cases("quick")}
    assert listed["griffith"] == "ok" and listed["lab_specimen"] == "not run"
    griffith = {r["quantity"]: r for r in _rows(out / "results.csv") if r["case"] == "griffith"}
    assert griffith["crack-centre opening w"]["met"] == "met"
    assert "ran only sneddon, kgd" in (out / "report.md").read_text()
    kgd = next(r for r in records if r.name == "kgd")
    assert kgd.wall_time_s == pytest.approx(first["wall_time_s"])
    assert kgd.commit == commit  # the run's, read back
    assert [c.met for c in kgd.comparisons] == [c["met"] for c in first["comparisons"]]


def test_a_failing_case_is_reported_and_the_report_still_written(
    shared_tmp_path, capsys, monkeypatch
):
    # sneddon's tier with a bad field: its scene cannot be built, the report goes on
    bad = {"quick": Tier("coarse", fixed={"rock.youngs_modulus": "10 m"})}
    registry = tuple(dataclasses.replace(c, tiers=bad) if c.name == "sneddon" else c for c in CASES)
    monkeypatch.setattr(cases, "CASES", registry)
    out = shared_tmp_path / "bad"
    argv = ["reproduce", "--quick", "--only", "sneddon", "-o", str(out)]
    assert main(argv) == 4
    (row,) = [r for r in _rows(out / "results.csv") if r["case"] == "sneddon"]
    assert row["status"] == "failed" and "youngs_modulus" in row["case_note"]
    if MPI.COMM_WORLD.rank == 0:
        assert "sneddon" in capsys.readouterr().err


def _files(top):
    """Every file under ``top``: its bytes and modification time."""
    files = sorted(p for p in top.rglob("*") if p.is_file())
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in files}


def test_a_resolution_no_case_has_is_refused_before_anything_is_written(shared_tmp_path, capsys):
    out = shared_tmp_path / "unknown"
    argv = ["reproduce", "--quick", "-o", str(out)]
    assert main([*argv, "--only", "sneddon"]) == 0
    before = _files(out)
    MPI.COMM_WORLD.barrier()
    capsys.readouterr()
    # once, every case of the report was rewritten as failed: sneddon's results lost
    assert main([*argv, "--only", "griffith", "--resolution", "ultra"]) == 2
    assert _files(out) == before
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert err.count("\n") == 1, err
        assert "--resolution" in err and "'ultra'" in err and "coarse, default" in err
    with pytest.raises(ValueError, match=r"--resolution: .*'ultra'"):
        run_reproduction(shared_tmp_path / "never", tier="quick", resolution="ultra")
    assert not (shared_tmp_path / "never").exists()


def test_cases_left_out_by_only_are_read_back_never_run_or_rewritten(shared_tmp_path, capsys):
    out = shared_tmp_path / "partial"
    argv = ["reproduce", "--quick", "-o", str(out)]
    assert main([*argv, "--only", "griffith"]) == 0
    kept = out / "cases" / "griffith" / "case.json"
    before = kept.read_bytes(), kept.stat().st_mtime_ns
    MPI.COMM_WORLD.barrier()
    capsys.readouterr()
    # griffith ran at the tier's resolution, coarse: read back, its case.json untouched;
    # the KGD mesh series cannot be built at coarse: neither tried nor marked failed
    assert main([*argv, "--only", "sneddon", "--resolution", "coarse"]) == 0
    assert (kept.read_bytes(), kept.stat().st_mtime_ns) == before
    assert sorted(p.name for p in (out / "cases").iterdir()) == ["griffith", "sneddon"]
    listed = {r["case"]: r for r in _rows(out / "results.csv")}
    assert listed["griffith"]["status"] == "ok" and listed["sneddon"]["status"] == "ok"
    assert {r["status"] for n, r in listed.items() if n not in ("griffith", "sneddon")} == {
        "not run"
    }
    others = len(select_cases("quick")) - 1
    if MPI.COMM_WORLD.rank == 0:
        printed = capsys.readouterr().out
        assert f"--only: 1 of the tier's {others} other cases read back" in printed
        assert f"{others - 1} not run yet" in printed


def test_bad_choices_name_the_option(shared_tmp_path):
    with pytest.raises(ValueError, match=r"--only: unknown case.*sneddon"):
        run_reproduction(shared_tmp_path, only=["nope"])
    with pytest.raises(ValueError, match="--fidelity"):
        run_reproduction(shared_tmp_path, fidelity="exact")
    with pytest.raises(ValueError, match="tier"):
        select_cases("slow")
    with pytest.raises(SystemExit):
        main(["reproduce", "-o", str(shared_tmp_path), "--fidelity", "exact"])
    for minutes in ("-1", "soon", "nan"):
        with pytest.raises(SystemExit):
            main(["reproduce", "-o", str(shared_tmp_path), "--watchdog", minutes])
    plain = shared_tmp_path / "plain.md"
    if MPI.COMM_WORLD.rank == 0:
        plain.write_text("no markers\n")
        with pytest.raises(ValueError, match=r"--readme: .*plain.md has no block"):
            update_readme(plain, "table")
        assert plain.read_text() == "no markers\n"


@pytest.mark.serial
def test_every_case_is_well_formed():
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    names = [c.name for c in CASES]
    assert len(set(names)) == len(names)
    quick = select_cases("quick")
    assert {"sneddon", "kgd", "griffith", "rubin", "hubbert_willis", "no2"} <= {
        c.name for c in quick
    }
    for case in CASES:
        if case.kind != "missing":
            assert (root / case.source).exists(), case.source
            assert case.compare is not None


@pytest.mark.serial
def test_a_case_at_the_models_validity_limit_is_not_a_failure(tmp_path):
    limit = {"stopped": "blocks came loose", "validity_limit": True}
    solver = {"stopped": "SNES diverged", "validity_limit": False}
    assert case_status(CaseResult(tmp_path, (), summary=limit)) == ("limit", "blocks came loose")
    assert case_status(CaseResult(tmp_path, (), summary={"stopped": None})) == ("ok", "")
    rows = ({"value": 30, **limit}, {"value": 45, "stopped": None}, {"value": 60, **limit})
    status, message = case_status(CaseResult(tmp_path, (), rows=rows))
    assert status == "limit" and message == "30: blocks came loose; 60: blocks came loose"
    mixed = ({"value": 30, **limit}, {"value": 45, **solver})
    assert case_status(CaseResult(tmp_path, (), rows=mixed))[0] == "stopped"
    # a summary written before the flag existed: a stop is a stop
    assert case_status(CaseResult(tmp_path, (), summary={"stopped": "x"}))[0] == "stopped"


@pytest.mark.serial
def test_a_peak_cut_short_by_the_validity_limit_is_not_judged(tmp_path):
    # the lab rows of the full report: a drop at 4.61 MPa, then a higher peak cut
    # short; a pressure still rising at the limit; a drop that confirms the peak
    cut = {"peak_pressure_MPa": 10.11, "breakdown_pressure_MPa": 4.61, "validity_limit": True}
    rising = {"peak_pressure_MPa": 7.71, "breakdown_pressure_MPa": None, "validity_limit": True}
    confirmed = {"peak_pressure_MPa": 9.91, "breakdown_pressure_MPa": 9.91, "validity_limit": True}
    ended = {"peak_pressure_MPa": 36.4, "breakdown_pressure_MPa": None, "validity_limit": False}
    assert "lower bound" in peak_cut_short(cut) and "lower bound" in peak_cut_short(rising)
    assert peak_cut_short(confirmed) is None and peak_cut_short(ended) is None
    rows = tuple({"x": math.radians(a), **s} for a, s in ((30, cut), (45, rising), (60, confirmed)))
    wall = {"hole": "perforation 1", "tension_MPa": 10.29, "tensile_strength_MPa": 2.59}
    rows[0]["in_situ_wall_tension"] = [{**wall, "exceeds": True}]
    r30, r45, r60, rise = lab_specimen(CaseResult(tmp_path, (), rows=rows))
    assert "cracks its walls (closed form, tension in MPa: perforation 1 10.29; T0 2.59)" in (
        r30.note
    )
    assert "closed form" not in r45.note
    assert r30.gap == pytest.approx(10.11 / 10.39 - 1) and r30.met is None and r45.met is None
    assert r30.note.startswith("not judged") and r60.met is False  # -36 %
    assert rise.met is None and rise.ours_text == "no" and rise.withheld == "a lower bound"
    (row,) = peak_against("p", 10.0, "s", 0.1)(CaseResult(tmp_path, (), summary=cut))
    assert row.met is None and row.target == ""
    (row,) = peak_against("p", 36.0, "s", 0.1)(CaseResult(tmp_path, (), summary=ended))
    assert row.met is True


@pytest.mark.serial
def test_a_breakdown_row_says_how_deep_the_pressure_fell_after_it(tmp_path):
    # No. 2's coarse seepage run with full joints: a dip of about 1 % confirmed 72.16 MPa
    shallow = {"peak_pressure_MPa": 72.58, "breakdown_pressure_MPa": 72.16,
               "breakdown_drop_MPa": 0.72}  # fmt: skip
    (row,) = peak_against("p", 64.01, "s", 0.1)(CaseResult(tmp_path, (), summary=shallow))
    assert "confirmed by a drop (it fell 0.72 MPa after it, 1.0% of the peak)" in row.note
    # a summary written before the depth was recorded keeps the old words
    old = {k: v for k, v in shallow.items() if k != "breakdown_drop_MPa"}
    (row,) = peak_against("p", 64.01, "s", 0.1)(CaseResult(tmp_path, (), summary=old))
    assert row.note == "confirmed by a drop"


def test_a_first_crack_row_says_where_its_step_broke_and_how_near_the_rest_came(tmp_path):
    # No. 2 coarse: the far-end facet reached its strength first, five in the middle followed
    first = {"distance_from_wellbore_wall_m": 0.1539, "place": "far end",
             "interfaces_by_place": {"middle": 5, "far end": 2},
             "ratio_by_place": {"root": 0.8675, "middle": 0.861, "far end": 1.0005,
                                "beyond the tip": 0.585}}  # fmt: skip
    summary = {"peak_pressure_MPa": 64.17, "first_crack": first, "first_crack_time_s": 53.14}
    _, row = peak_against("p", 64.01, "s", 0.1)(CaseResult(tmp_path, (), summary=summary))
    assert row.ours_text == (
        "far end, 153.9 mm from the wellbore wall at 53.1 s; its step broke 5 middle, "
        "2 far end; highest failure ratio then: root 0.87, middle 0.86, far end 1.00, "
        "beyond the tip 0.58"
    )
    assert row.met is False
    alone = first | {"interfaces_by_place": {"far end": 2}, "ratio_by_place": {}}
    _, row = peak_against("p", 64.01, "s", 0.1)(
        CaseResult(tmp_path, (), summary=summary | {"first_crack": alone})
    )
    assert row.ours_text == "far end, 153.9 mm from the wellbore wall at 53.1 s"
    assert "the tunnel's length" not in row.note  # no share shown, none explained
    # the distance as a share of the tunnel shows how near the thirds' line it lies
    shared = alone | {"fraction_of_tunnel": 0.6691}
    _, row = peak_against("p", 64.01, "s", 0.1)(
        CaseResult(tmp_path, (), summary=summary | {"first_crack": shared})
    )
    assert row.ours_text == "far end, 153.9 mm from the wellbore wall (0.67 L) at 53.1 s"
    assert "0.67 L" in row.note
    both = first | {"ratio_by_place": {"root": 1.02, "far end": 1.3}}
    _, row = peak_against("p", 64.01, "s", 0.1)(
        CaseResult(tmp_path, (), summary=summary | {"first_crack": both})
    )
    assert row.met is True and "1: at its strength too" in row.note


def _facets_at(path, centres):
    """A fracture.vtu of small triangles centred at ``centres`` (the lab's broken interfaces)."""
    import meshio

    corners = np.concatenate([c + 1e-4 * np.array([[1, 0, 0], [0, 1, 0], [-1, -1, 0]])
                              for c in np.asarray(centres)])  # fmt: skip
    cells = np.arange(len(corners)).reshape(-1, 3)
    path.parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, meshio.Mesh(corners, [("triangle", cells)]))


@pytest.mark.serial
@pytest.mark.parametrize("reach, met", [(0.010, False), (0.035, True)])
def test_the_lab_fracture_must_grow_a_tunnel_length_past_the_tips_and_turn(tmp_path, reach, met):
    """Fig. 8 at 60 deg: tunnels from r = 10 to 40 mm; the broken faces beyond at 50 deg."""
    scene = load_scene("meshes/scenes/lab_specimen_60deg.toml", "coarse")
    angle = np.radians(50.0)
    centres = [[r * np.cos(angle), r * np.sin(angle), 1e-3] for r in (0.042, 0.040 + reach)]
    _facets_at(tmp_path / "case_0_60_deg" / "fracture.vtu", centres)
    row = {"x": math.radians(60), "value": "60 deg", "peak_pressure_MPa": 9.9}
    turn = lab_specimen(CaseResult(tmp_path, (scene,), rows=(row,)))[1]
    assert turn.ours == pytest.approx(10.0, abs=0.05)  # 60 deg tunnels, faces at 50 deg
    assert turn.met is met
    assert f"up to {1e3 * reach:.1f} mm (the tunnels are 30 mm long)" in turn.ours_text


@pytest.mark.serial
def test_comparison_rows_judge_gaps_and_trends(tmp_path):
    c = Comparison("p", 10.45, 10.0, "MPa", tolerance=0.05)
    assert c.gap == pytest.approx(0.045) and c.met and c.target == "within 5%"
    assert not Comparison("p", 10.6, 10.0, tolerance=0.05).met
    assert Comparison("p", 10.6, 10.0).met is None  # no target: not judged
    assert Comparison("p", None, 10.0, tolerance=0.1).met is None
    assert Comparison("p", math.nan, 10.0, tolerance=0.1).gap is None

    rows = tuple(
        {"x": x, "breakdown_pressure_MPa": p} for x, p in ((1, 10.0), (3, 12.0), (2, 11.5))
    )
    result = CaseResult(tmp_path, (), rows=rows)
    (rising,) = trend("b", "rises", True, 1.0, "")(result)
    assert rising.met and rising.ours == pytest.approx(0.2) and rising.note == "monotone"
    (falling,) = trend("b", "falls", False, 1.0, "")(result)
    assert falling.met is False
    rows = ({"x": 1, "breakdown_pressure_MPa": 10.0}, {"x": 2, "breakdown_pressure_MPa": None})
    (lonely,) = trend("b", "rises", True, 1.0, "")(CaseResult(tmp_path, (), rows=rows))
    assert lonely.met is False and "fewer than two" in lonely.note


@pytest.mark.serial
def test_the_shear_share_trend_counts_failures(tmp_path):
    rows = (
        {"x": 5e-7, "tensile_failures": 103, "shear_failures": 1},
        {"x": 8e-6, "tensile_failures": 140, "shear_failures": 21},
        {"x": 2e-6, "tensile_failures": 136, "shear_failures": 24},
        {"x": 1e-5, "tensile_failures": math.nan, "shear_failures": math.nan},  # a ramp's row
        {"x": 1e-4, "tensile_failures": 0, "shear_failures": 0},  # nothing broke
    )
    (row,) = trend("s", "rises", True, 1e6, "cm3/s", shear_share=True)(
        CaseResult(tmp_path, (), rows=rows)
    )
    assert row.ours == pytest.approx(21 / 161 - 1 / 104)
    assert row.ours_text == "rises 1% -> 13% (0.5 -> 8 cm3/s; 1 of 104, 24 of 160, 21 of 161)"
    assert row.note == "1 step(s) against the trend"
    # 12 points, less than the share moves between meshes: the paper's way, not judged
    assert row.agrees and row.met is None and row.withheld == SHARE_NOT_CONVERGED
    wide = ({**rows[0], "shear_failures": 0}, {**rows[1], "shear_failures": 70})
    (row,) = trend("s", "rises", True, 1e6, "cm3/s", shear_share=True)(
        CaseResult(tmp_path, (), rows=wide)
    )
    assert row.ours == pytest.approx(70 / 210) and row.met and not row.withheld
    (row,) = trend("s", "falls", False, 1.0, "", True)(CaseResult(tmp_path, (), rows=rows[3:]))
    assert row.met is False and "fewer than two" in row.note


@pytest.mark.serial
def test_all_tensile_allows_an_insignificant_shear_share(tmp_path):
    """DEM-LBM sec. 3.5: "all tensile" at every value holds up to 5 % of failures in shear."""
    rows = (
        {"x": 2e-5, "tensile_failures": 96, "shear_failures": 4},
        {"x": 1e-6, "tensile_failures": 100, "shear_failures": 0},
        {"x": 5e-6, "tensile_failures": 0, "shear_failures": 0},  # nothing broke
    )
    judge = all_tensile("s", "all tensile", 1e6, "um")
    (row,) = judge(CaseResult(tmp_path, (), rows=rows))
    assert row.met and row.ours == pytest.approx(0.04)
    assert row.ours_text == (
        "largest shear share 4% (1 -> 20 um; 0 of 100, 4 of 100); 1 case(s) did not break"
    )
    over = ({"x": 1e-6, "tensile_failures": 94, "shear_failures": 6}, *rows[:1])
    (row,) = judge(CaseResult(tmp_path, (), rows=over))
    assert row.met is False and row.ours == pytest.approx(0.06)
    (row,) = judge(CaseResult(tmp_path, (), rows=rows[2:]))
    assert row.met is False and row.note == "no case broke"


def _study(tmp_path, peaks, degrees):
    rows = [
        {"value": k, "peak_pressure_MPa": peaks[k], "fracture_degree": degrees.get(k)}
        for k in peaks
    ]
    return CaseResult(tmp_path, (), rows=tuple(rows))


def test_fracture_degrees_are_judged_by_the_papers_orderings(tmp_path):
    """Fig. 19 and 21: which charge fractures most, and the lower breakdown the higher degree."""
    peaks = references.CHARGES  # No. 2 < No. 4 < No. 1 < No. 3
    as_paper = {"no2": 4e-4, "no4": 3e-4, "no1": 2e-4, "no3": 1e-4}
    extremes, pairs = charge_degrees(_study(tmp_path, peaks, as_paper))
    # No. 1 and No. 3 (68.02, 68.56 MPa) lie within the mesh error: 5 pairs, not 6
    assert extremes.met and pairs.met and pairs.ours_text.startswith("5 of 5 pairs of charges")
    swapped = as_paper | {"no2": 1e-4, "no3": 4e-4}
    extremes, pairs = charge_degrees(_study(tmp_path, peaks, swapped))
    assert extremes.met is False and extremes.ours_text.startswith("No. 3 and No. 2")
    assert pairs.met is False and pairs.ours == 1  # only No. 4 against No. 1 agrees
    assert charge_degrees(_study(tmp_path, peaks, {"no1": 1e-4})) == []  # one degree: no rows
    assert not (tmp_path / DEGREE_FIGURE).exists()
    rows = four_charges(_study(tmp_path, peaks, as_paper))  # draws the degrees too
    assert (tmp_path / DEGREE_FIGURE).stat().st_size > 0 and len(rows) >= 6

    shapes = dict(references.SHAPES)
    degrees = {"1-1": 2e-4, "2-1": 5e-4, "2-2": 2e-4, "3-1": 5e-4, "3-2": 2e-4, "4-2": 2e-4}
    degrees |= references.SHAPE_FRACTURE_DEGREE
    d12, d41, single, both = shape_degrees(_study(tmp_path, shapes, degrees))
    assert d12.gap == pytest.approx(0.0) and d12.unit == "%" and d12.met is None  # listed only
    assert d41.ours == pytest.approx(0.056)
    assert single.met and single.ours == 4 and both.met
    degrees["4-2"] = 9e-4  # the shorter tunnel now fractures more, though it breaks higher
    rows = shape_degrees(_study(tmp_path, shapes, degrees | {"no2": None}))
    assert rows[2].met is False and rows[2].ours_text.startswith("3 of 4 pairs")
    assert rows[3].met  # 1-2 and 4-1 unchanged


def test_orderings_of_peaks_within_the_mesh_error_are_not_judged(tmp_path):
    """The coarse four charges: 64.15 / 64.52 / 64.65 / 65.18 MPa, all within 1.7 %."""
    assert PEAK_MESH_ERROR == pytest.approx(1 - 63.04 / 64.11, abs=5e-4)
    assert resolved(64.01, 68.56) and not resolved(64.15, 65.18)
    ours = {"no1": 64.52, "no2": 64.15, "no3": 65.18, "no4": 64.65}
    degrees = {"no1": 1.82e-2, "no2": 2.23e-2, "no3": 2.93e-2, "no4": 3.32e-2}
    rows = {c.quantity: c for c in four_charges(_study(tmp_path, ours, degrees))}
    order = rows["No. 2 breaks below No. 3 (lowest and highest)"]
    assert order.agrees and order.met is None and order.withheld == WITHIN_ERROR
    pairs = rows["the lower the breakdown, the higher the fracture degree"]
    assert pairs.met is None and pairs.ours_text.startswith("0 of 0 pairs")
    # the same rows on the paper's peaks are judged
    rows = {c.quantity: c for c in four_charges(_study(tmp_path, references.CHARGES, degrees))}
    assert rows["No. 2 breaks below No. 3 (lowest and highest)"].met is True
    assert rows["the lower the breakdown, the higher the fracture degree"].met is False
    # a shape pair within the error is listed, not counted; 1-2 against 4-1 is resolved
    shapes = dict(references.SHAPES) | {"2-1": 63.90, "2-2": 64.62}
    marks = {k: 2e-4 for k in shapes} | {"1-2": 3e-4, "3-1": 3e-4, "4-1": 3e-4}
    single = shape_degrees(_study(tmp_path, shapes, marks))[-2]
    assert single.ours_text.startswith("3 of 3 pairs") and "(within the mesh error)" in (
        single.ours_text
    )


def test_first_cracks_of_the_four_charges_against_the_root(tmp_path):
    crack = [("no1", "far end", 0.157), ("no2", "root", 0.041), ("no3", None, None)]
    rows = tuple(
        {"value": v, "first_crack": {"place": p, "distance_from_wellbore_wall_m": d}}
        for v, p, d in crack
    )
    (row,) = first_cracks(CaseResult(tmp_path, (), rows=rows))
    assert row.met is False and row.ours == 1
    assert row.ours_text == "1 of 2: No. 1 far end (157 mm), No. 2 root (41 mm)"
    (row,) = first_cracks(CaseResult(tmp_path, (), rows=rows[1:]))
    assert row.met
    # how near the root came when the first facet reached its strength
    near = {"ratio_by_place": {"root": 0.867, "middle": 0.86, "far end": 1.0}}
    rows = ({"value": "no1", "first_crack": rows[0]["first_crack"] | near},)
    (row,) = first_cracks(CaseResult(tmp_path, (), rows=rows))
    assert row.ours_text == "0 of 1: No. 1 far end (157 mm, root at 0.87)" and row.met is False
    shared = rows[0]["first_crack"] | {"fraction_of_tunnel": 0.68}
    (row,) = first_cracks(CaseResult(tmp_path, (), rows=({"value": "no1", "first_crack": shared},)))
    assert row.ours_text == "0 of 1: No. 1 far end (157 mm, 0.68 L, root at 0.87)"
    # No. 4 coarse: a step that did not land broke the far end (1.29) and the root (1.10)
    both = {"ratio_by_place": {"root": 1.101, "far end": 1.291}}
    rows = ({"value": "no4", "first_crack": rows[0]["first_crack"] | both},)
    (row,) = first_cracks(CaseResult(tmp_path, (), rows=rows))
    assert row.ours_text == "1 of 1: No. 4 far end (157 mm, root at 1.10)" and row.met
    assert first_cracks(CaseResult(tmp_path, (), rows=({"value": "no1"},))) == []


def _profile(peak, place, largest):
    """A stress_along_tunnels result: six bins of 40 mm, the largest of the zone at ``place``."""
    return {
        "component": "sigma_xx", "unit": "MPa", "cells": 500, "tensile_cells": int(peak > 0),
        "distance_m": [0.02 + 0.04 * k for k in range(6)], "largest_MPa": largest,
        "mean_MPa": [v - 3 if v is not None else None for v in largest], "peak_MPa": peak,
        "peak_point_m": [0.1, 0.0, 0.0], "peak_distance_from_wellbore_wall_m": 0.03,
        "peak_place": place,
    }  # fmt: skip


def test_sigma_xx_at_the_first_crack_against_the_papers_root(tmp_path):
    """Fig. 18: the largest sigma_xx, in tension, at the root; a row per scene, one per study."""
    hot = _profile(1.5, "root", [1.5, -60.0, -61.0, -62.0, None, -63.0])
    cold = _profile(-62.1, "beyond the tip", [-70.6, -70.8, -69.8, -70.5, -68.3, -72.3])
    (row,) = stress_at_root({"first_crack": {"place": "middle", "sigma_xx": hot}})
    assert row.met and row.ours == pytest.approx(1.5) and row.unit == "MPa"
    assert "largest per third: root 1.5, middle -61.0, far end -63.0 MPa" in row.ours_text
    assert "1 of 500 cells in tension" in row.ours_text
    (row,) = stress_at_root({"first_crack": {"sigma_xx": cold}})
    assert row.met is False
    assert row.ours_text.startswith("largest -62.1 MPa, beyond the tip (30 mm)")
    compressed_root = _profile(-5.0, "root", [-5.0] * 6)  # at the root, but not in tension
    assert stress_at_root({"first_crack": {"sigma_xx": compressed_root}})[0].met is False
    assert stress_at_root({"first_crack": {"place": "root"}}) == []  # a run from before
    summary = {"peak_pressure_MPa": 64.0, "first_crack": {"sigma_xx": hot}}
    field = peak_against("p", 43.0, "s", 0.1)(CaseResult(tmp_path, (), summary=summary))
    assert [r.quantity for r in field] == ["p"]  # a scene whose tunnels do not run along x
    no2 = peak_against("p", 64.0, "s", 0.05, stress=True)(CaseResult(tmp_path, (), summary=summary))
    assert [r.quantity for r in no2] == ["p", "largest sigma_xx at the first crack"]

    rows = ({"value": "no1", "first_crack": {"sigma_xx": hot}}, {"value": "no2"})
    (row,) = stresses_at_roots(CaseResult(tmp_path, (), rows=rows))
    assert row.met and row.ours == 1 and row.ours_text.startswith("1 of 1: No. 1: largest 1.5")
    assert (tmp_path / STRESS_FIGURE).stat().st_size > 0
    rows += ({"value": "no3", "first_crack": {"sigma_xx": cold}},)
    (row,) = stresses_at_roots(CaseResult(tmp_path, (), rows=rows))
    assert row.met is False and row.ours == 1 and "No. 3: largest -62.1" in row.ours_text
    assert stresses_at_roots(CaseResult(tmp_path, (), rows=rows[1:2])) == []


def test_failure_modes_of_the_four_charges_are_mostly_tensile(tmp_path):
    rows = ({"value": "no1", "tensile_failures": 151, "shear_failures": 9},)
    (row,) = failure_modes(CaseResult(tmp_path, (), rows=rows))
    assert row.met and row.ours_text == "No. 1 151 / 9 (tensile / shear interfaces)"
    rows += ({"value": "no2", "tensile_failures": 8, "shear_failures": 8},)
    assert failure_modes(CaseResult(tmp_path, (), rows=rows))[0].met is False
    assert failure_modes(CaseResult(tmp_path, (), rows=({"value": "no3"},))) == []


@pytest.mark.serial
def test_the_summary_puts_the_unit_after_numbers_not_after_texts():
    text = {"unit": "%", "ours_text": "0.08 %", "reference_text": "<= 10 %", "agrees": True}
    rows = (Comparison("p", 10.45, 10.0, "MPa", tolerance=0.05), Comparison("g", 0.08, **text))
    record = CaseRecord("c", "perforation", "t", "ok", rows, resolution="coarse")
    meta = {"tier": "quick", "fidelity": "scene", "date": "d", "commit": "x", "ranks": 1}
    table = summary_table([record], meta)
    assert "| 10 MPa | 10.45 MPa |" in table
    assert "| <= 10 % | 0.08 % |" in table and "% %" not in table


@pytest.mark.serial
def test_time_left_scales_with_the_cases_done_once_a_minute_has_run():
    from hfcdem.reproduce.runner import _Clock

    clock = _Clock(spent=3.0, estimated=1.0, left=[100.0, 200.0])
    assert clock.remaining() == pytest.approx(300.0)  # one short case: no scaling
    clock = _Clock(spent=180.0, estimated=90.0, left=[100.0, 200.0])
    assert clock.remaining() == pytest.approx(600.0)  # twice as slow as estimated
    clock = _Clock(spent=900.0, estimated=90.0, left=[100.0])
    assert clock.remaining() == pytest.approx(300.0)  # at most 3x


def test_a_case_stopped_from_outside_goes_on_from_its_checkpoint(shared_tmp_path):
    from hfcdem.workflows.run import run_scene

    out = shared_tmp_path / "stopped_report"
    kgd = next(c for c in CASES if c.name == "kgd")
    tier = kgd.tiers["quick"]
    scene = load_scene(ROOT / kgd.source, tier.resolution, overrides=dict(tier.fixed))
    with pytest.raises(Interrupted):  # as a time limit would stop it
        run_scene(scene, out / "cases" / "kgd", observers=[StopAt(2.0)])
    (record,) = run_reproduction(out, tier="quick", only=["kgd"])
    assert not record.skipped and record.status == "ok"
    assert (out / "cases" / "kgd" / "fields_resumed.bp").is_dir()  # went on, not again
    rows = {c.quantity: c for c in record.comparisons}
    for quantity in ("half-length (fluid front)", "inlet net pressure", "inlet opening"):
        assert rows[quantity].met is True, rows[quantity]  # as the straight run's rows


def test_a_case_at_another_resolution_than_its_tiers_gets_no_estimate(shared_tmp_path):
    said = []
    out = shared_tmp_path / "griffith_default"
    (record,) = run_reproduction(out, only=["griffith"], resolution="default", say=said.append)
    assert record.status == "ok" and record.resolution.startswith("default")
    # the quick tier's 1 s is for its coarse mesh: not said of the default one
    (line,) = [m for m in said if m.startswith("[1/1] griffith: Griffith")]
    assert line.endswith("(no estimate at this resolution: the tier's is for its own mesh)")
    said.clear()
    run_reproduction(out, only=["griffith"], resolution="default", say=said.append)
    (line,) = [m for m in said if m.startswith("[1/1] griffith: Griffith")]
    assert "(about " in line  # its own wall time, now that it has run here
