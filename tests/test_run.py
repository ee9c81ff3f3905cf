"""`hfcdem run`: a scene file through mesh, solid, fluid and outputs."""

import csv
import gc
import json

import numpy as np
import pytest
from mpi4py import MPI
from stopping import Interrupted, StopAt

from hfcdem.analytic import hubbert_willis_breakdown, kgd_viscosity
from hfcdem.cli import first_crack_pressure_words, main
from hfcdem.config.scene import load_scene, parse_scene
from hfcdem.config.tables import SceneError
from hfcdem.io.series import read_pvd
from hfcdem.solid.states import OPEN
from hfcdem.solvers import SolverError
from hfcdem.workflows.observers import StepObserver
from hfcdem.workflows.run import OutputInUse, pressurised_groups, run_scene, supporting_walls

KGD = "meshes/scenes/kgd_strip.toml"
BOREHOLE = "meshes/scenes/borehole_plate.toml"


def test_kgd_strip_scene_runs_and_matches_the_solution(shared_tmp_path):
    out = shared_tmp_path / "kgd"
    summary = run_scene(load_scene(KGD, "coarse"), out)
    ref = kgd_viscosity(10.0, 4e-3, 25e9, 0.25, 1e-3)
    assert summary["simulated_time_s"] == pytest.approx(10.0)
    assert summary["stopped"] is None
    assert summary["max_mass_error"] < 1e-6
    history = (out / "history.csv").read_text().splitlines()
    header = history[0].split(",")
    last = dict(zip(header, map(float, history[-1].split(",")), strict=True))
    assert last["injection_pressure"] == pytest.approx(ref.net_pressure, rel=0.10)
    # propagation from an open crack: no breakdown peak (the first step is not one)
    assert summary["breakdown_pressure_MPa"] is None
    assert "open crack" in summary["breakdown_note"]
    # 1 m facets: the front is a whole facet past the solution's 20.63 m (measured +6.6 %)
    assert summary["fluid_front_m"] == pytest.approx(ref.half_length, rel=0.08)
    assert summary["inlet_opening_m"] == pytest.approx(ref.inlet_opening, rel=0.04)
    for name in ("run.json", "summary.json", "history.csv", "pressure.png", "fracture.vtu"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "fields.bp").is_dir()
    record = json.loads((out / "run.json").read_text())
    assert "fluid.density" in record["defaults_used"]


class FirstBreaks(StepObserver):
    """Keep the midpoints of the first interfaces that break (all ranks)."""

    midpoints = None

    def step(self, frac, rec):
        events = frac.solid.events
        if self.midpoints is None and events:
            self.midpoints = np.concatenate(frac.solid.comm.allgather(events[0].midpoints))


def test_borehole_scene_breaks_at_the_wall_near_hubbert_willis(shared_tmp_path):
    """The seed-001 borehole pumped through ``hfcdem run`` (coarse: a/5 at the wall).

    The wall cracks along SH, in tension, at 14.42 MPa: -31.3 % from Hubbert-Willis
    3 Sh - SH + T0 = 21 MPa, the error of dry joints at a/5 in
    benchmarks/wall_joint_verification.py (-23.4 % at the default a/10: 16.08 MPa).
    """
    first = FirstBreaks()
    summary = run_scene(load_scene(BOREHOLE, "coarse"), shared_tmp_path / "bh", observers=[first])
    hw = hubbert_willis_breakdown(20e6, 12e6, 5e6)
    assert summary["initial_failures"] == 0
    error = summary["first_crack_pressure_MPa"] * 1e6 / hw - 1
    assert -0.33 < error < -0.29, error
    # a step landed on it: the pressure it broke at is the landed state's
    assert summary["first_crack_pressure_bound_MPa"] == summary["first_crack_pressure_MPa"]
    assert summary["shear_failures"] == 0 and summary["tensile_failures"] > 0
    angle = np.degrees(np.arctan2(np.abs(first.midpoints[:, 1]), np.abs(first.midpoints[:, 0])))
    assert np.all(angle < 5.0), angle  # along SH (x), on both sides of the borehole
    assert np.all(np.hypot(*first.midpoints[:, :2].T) < 0.03 + 4 * 0.006)  # in the wall rings
    assert summary["peak_pressure_MPa"] * 1e6 < hw  # the cracked wall holds less
    # every rebuild has its cause: the start, breaks, and contact switches after them
    causes = summary["rebuild_causes"]
    assert sum(causes.values()) == summary["rebuilds"]
    assert causes["start"] == 1 and causes["break"] >= 1
    # a rebuild reaches the solid's operator (a change or a factorisation) unless it met
    # states condensed before
    op = summary["solid_operator"]
    assert op["assembled"] >= 1
    reused = summary["reused_condensations"]
    assert 0 <= reused < summary["rebuilds"]
    solved = op["assembled"] + op["updated"] + op["low_rank"] + op["unchanged"]
    assert solved >= summary["rebuilds"] - reused


def test_a_run_until_its_first_crack_ends_there_with_the_full_runs_first_crack(
    shared_tmp_path, capsys
):
    """``injection.until = "first crack"``: the run to the end's first crack, and no more."""
    full = run_scene(load_scene(BOREHOLE, "coarse"), shared_tmp_path / "bh_full")
    out = shared_tmp_path / "bh_first"
    code = main(
        ["run", BOREHOLE, "--resolution", "coarse", "-o", str(out), "--set",
         'injection.until="first crack"']
    )  # fmt: skip
    assert code == 0
    if MPI.COMM_WORLD.rank == 0:  # the last line is printed on rank 0
        said = capsys.readouterr().out
        assert 'the run ended there (injection.until = "first crack")' in said
    first = json.loads((out / "summary.json").read_text())
    # the same run up to there (bitwise on one rank; two ranks sum in varying order)
    for key in ("first_crack_time_s", "first_crack_pressure_MPa"):
        assert first[key] == pytest.approx(full[key], rel=1e-9), key
    assert np.allclose(first["first_crack"]["point_m"], full["first_crack"]["point_m"])
    assert first["simulated_time_s"] == first["first_crack_time_s"] < full["simulated_time_s"]
    assert first["steps"] < full["steps"] and first["until"] == "first crack"
    assert first["breakdown_pressure_MPa"] is None
    assert "ended on its first crack" in first["breakdown_note"]
    assert "first crack" not in (full["breakdown_note"] or "")
    # resumed as it was, it stays at its first crack; resumed without until, it goes on
    args = ["run", BOREHOLE, "--resolution", "coarse", "-o", str(out), "--resume"]
    assert main([*args, "--set", 'injection.until="first crack"']) == 0
    again = json.loads((out / "summary.json").read_text())
    assert again["steps"] == first["steps"]
    assert main([*args, "--force"]) == 0
    on = json.loads((out / "summary.json").read_text())
    assert on["simulated_time_s"] == pytest.approx(full["simulated_time_s"])
    assert on["first_crack_pressure_MPa"] == pytest.approx(
        full["first_crack_pressure_MPa"], rel=1e-9
    )
    assert on["peak_pressure_MPa"] == pytest.approx(full["peak_pressure_MPa"], rel=1e-9)


def test_the_reduced_solid_reproduces_the_full_borehole_run(shared_tmp_path):
    """``solver.solid = "reduced"`` against the full-DG reference, coarse borehole scene.

    Measured (band threshold 0.3, 2 rings): first crack 14.583 against 14.417 MPa
    (+1.2 %), peak 15.391 against 15.317 MPa (+0.5 %), 29 tensile failures each.  The
    glued blocks have no spring compliance (stiff-spring limit, O(1/alpha)).
    """
    runs, firsts = {}, {}
    for mode in ("full", "reduced"):
        firsts[mode] = FirstBreaks()
        scene = load_scene(BOREHOLE, "coarse", overrides={"solver.solid": mode})
        runs[mode] = run_scene(scene, shared_tmp_path / mode, observers=[firsts[mode]])
    full, reduced = runs["full"], runs["reduced"]
    assert (full["solid"], reduced["solid"]) == ("full", "reduced")
    first = reduced["first_crack_pressure_MPa"] / full["first_crack_pressure_MPa"] - 1
    peak = reduced["peak_pressure_MPa"] / full["peak_pressure_MPa"] - 1
    assert 0.0 <= first < 0.015, first  # stiffer: never earlier than the reference
    assert abs(peak) < 0.008, peak
    assert abs(reduced["tensile_failures"] - full["tensile_failures"]) <= 2
    assert reduced["shear_failures"] == full["shear_failures"] == 0
    # the first crack is the same pair of wall facets, along SH
    key = lambda m: sorted(map(tuple, np.round(m, 9)))  # noqa: E731
    assert key(firsts["reduced"].midpoints) == key(firsts["full"].midpoints)
    assert reduced["solved_unknowns"] < 0.6 * full["solved_unknowns"]
    assert reduced["free_interfaces"] < full["free_interfaces"]


def test_contact_hysteresis_leaves_a_run_without_reclosing_facets_alone(shared_tmp_path):
    """``solver.contact_hysteresis`` acts only on facets that closed again.

    On the coarse borehole 4 crack facets close again and none of them would
    open again at or below the pressure it closed at, so the run is the same
    with it; those pressures go into the checkpoint.
    """
    runs = {}
    for on in (False, True):
        scene = load_scene(BOREHOLE, "coarse", overrides={"solver.contact_hysteresis": on})
        runs[on] = run_scene(scene, shared_tmp_path / f"hysteresis_{on}")
    keys = ("first_crack_pressure_MPa", "peak_pressure_MPa", "tensile_failures", "rebuilds")
    for key in keys:
        assert runs[True][key] == pytest.approx(runs[False][key], rel=1e-12), key
    assert runs[True]["rebuild_causes"] == runs[False]["rebuild_causes"]
    assert runs[True]["rebuild_causes"]["contact"] > 0
    for on, run in runs.items():
        assert run["contact_held_shut"] == {"count": 0, "excess": 0.0}
        with (shared_tmp_path / f"hysteresis_{on}" / "history.csv").open() as f:
            held = [float(row["held_shut"]) for row in csv.DictReader(f)]
        assert held and set(held) == {0}  # the per-step column agrees with the summary
    rows = json.loads((shared_tmp_path / "hysteresis_True" / "checkpoint.json").read_text())
    assert all(len(row) == 6 for row in rows["interfaces"]) and rows["interfaces"]
    shut = [row[5] for row in rows["interfaces"] if row[2] != OPEN]
    assert len(shut) == 4 and all(row[5] is None for row in rows["interfaces"] if row[2] == OPEN)
    low, high = runs[True]["first_crack_pressure_MPa"], runs[True]["peak_pressure_MPa"]
    assert all(0.9 * low < p / 1e6 <= high for p in shut), shut


def test_another_scenes_results_are_kept_without_force(shared_tmp_path):
    out = shared_tmp_path / "kgd"
    run_scene(load_scene(KGD, "coarse"), out)
    other = load_scene(KGD)  # the default resolution: a different run
    with pytest.raises(OutputInUse, match="--force"):
        run_scene(other, out)
    assert json.loads((out / "run.json").read_text())["resolution"] == "coarse"


class Interrupt(StepObserver):
    """Stop a run at its first step, as Ctrl-C would."""

    def step(self, frac, rec):
        raise KeyboardInterrupt


def test_a_forced_run_that_stops_leaves_no_other_runs_summary(shared_tmp_path):
    from hfcdem.workflows.run import scene_fingerprint
    from hfcdem.workflows.study import case_done

    out = shared_tmp_path / "kgd_forced"
    coarse = load_scene(KGD, "coarse")
    run_scene(coarse, out)
    assert case_done(out, scene_fingerprint(coarse))
    other = load_scene(KGD)
    with pytest.raises(KeyboardInterrupt):
        run_scene(other, out, force=True, observers=[Interrupt()])
    # run.json names the new run; the coarse run's answers are gone, not passed off as its
    assert not (out / "summary.json").exists()
    assert not case_done(out, scene_fingerprint(other))
    assert not case_done(out, scene_fingerprint(coarse))


class _FailOnEveryRank(StepObserver):
    def step(self, frac, rec):
        raise SolverError("a solve failed on every rank", -11)


def _live_ksps():
    from petsc4py import PETSc

    return sum(1 for o in gc.get_objects() if issubclass(type(o), PETSc.KSP) and o.handle)


def test_a_run_that_fails_on_every_rank_frees_its_solver_at_once(shared_tmp_path):
    # the traceback keeps the run's frames, and the solid in them: before, its
    # factorisation stayed alive (on two ranks, in garbage) until the error was dropped
    gc.collect()
    before = _live_ksps()
    with pytest.raises(SolverError) as failed:
        run_scene(load_scene(KGD, "coarse"), shared_tmp_path / "fails",
                  observers=[_FailOnEveryRank()])  # fmt: skip
    assert failed.traceback  # still held here
    assert MPI.COMM_WORLD.allreduce(_live_ksps() - before, op=MPI.MAX) == 0


def test_blocks_loose_in_the_cavity_end_the_run_at_its_validity_limit(
    shared_tmp_path, monkeypatch, capsys
):
    """The loose-block stop is the model's validity limit: said so, exit 0, history kept."""
    import dataclasses

    from hfcdem.flow.balance import GroupBalance

    real, steps = GroupBalance.advance, []

    def blocks_in_the_cavity_at_the_third_balance(self, *args, **kwargs):
        after = real(self, *args, **kwargs)
        steps.append(after)
        return dataclasses.replace(after, cavity_content=-1e-6) if len(steps) == 3 else after

    monkeypatch.setattr(GroupBalance, "advance", blocks_in_the_cavity_at_the_third_balance)
    out = shared_tmp_path / "limit"
    assert main(["run", BOREHOLE, "-o", str(out), "--resolution", "coarse"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["validity_limit"] is True
    assert "cavity walls moved inward" in summary["stopped"] and summary["steps"] >= 1
    with (out / "history.csv").open() as f:
        assert len(f.readlines()) == 1 + summary["steps"]  # header and the steps before it
    # no drop confirmed a peak before the stop: the highest pressure is a lower bound
    assert summary["breakdown_pressure_MPa"] is None
    assert "lower bound" in summary["breakdown_note"]
    if MPI.COMM_WORLD.rank == 0:
        said = capsys.readouterr().out
        assert "ended at the validity limit of the model" in said
        peak = f"highest pressure {summary['peak_pressure_MPa']:.2f} MPa"
        assert "lower bound; " + peak in said


def test_a_scene_without_physics_is_refused_before_meshing(shared_tmp_path):
    scene = parse_scene({"geometry": {"catalogue": "crack_plate"}})
    with pytest.raises(SceneError, match=r"\[rock\]"):
        run_scene(scene, shared_tmp_path / "none")
    assert not (shared_tmp_path / "none").exists()


def test_cli_reports_bad_input_with_the_key(shared_tmp_path, capsys):
    bad = shared_tmp_path / "bad.toml"
    if MPI.COMM_WORLD.rank == 0:
        text = open(KGD).read().replace("poisson_ratio = 0.25", "poisson_ratio = 0.5")
        bad.write_text(text)
    MPI.COMM_WORLD.barrier()
    code = main(["run", str(bad), "-o", str(shared_tmp_path / "bad_out")])
    assert code == 2
    if MPI.COMM_WORLD.rank == 0:
        assert "rock.poisson_ratio" in capsys.readouterr().err
    assert not (shared_tmp_path / "bad_out").exists()


def _straight_and_stopped(tmp):
    """Run KGD to the end into tmp/straight, and again into tmp/resumed stopped at 4 s."""
    scene = load_scene(KGD, "coarse")
    straight = tmp / "straight"
    run_scene(scene, straight)
    out = tmp / "resumed"
    with pytest.raises(Interrupted):
        run_scene(scene, out, observers=[StopAt(4.0)])
    return scene, straight, out


def test_a_resume_on_another_mesh_is_refused(shared_tmp_path):
    scene = load_scene(KGD, "coarse")
    out = shared_tmp_path / "stopped"
    with pytest.raises(Interrupted):
        run_scene(scene, out, observers=[StopAt(1.0)])
    finer = load_scene(KGD)  # the default resolution: another mesh
    with pytest.raises(SceneError, match="another mesh"):
        run_scene(finer, out, resume=True, force=True)
    # nothing written before is lost, run.json included: a plain resume still finds its run
    assert json.loads((out / "checkpoint.json").read_text())["steps"] > 0
    assert json.loads((out / "run.json").read_text())["resolution"] == "coarse"
    from hfcdem.workflows.run import _claim_output

    _claim_output(out, scene, False, MPI.COMM_WORLD)  # would raise OutputInUse


def test_a_forced_run_refused_after_meshing_leaves_the_earlier_run_whole(shared_tmp_path):
    out = shared_tmp_path / "kept_whole"
    run_scene(load_scene(KGD, "coarse"), out)
    before = {n: (out / n).read_text() for n in ("run.json", "summary.json", "history.csv")}
    # refused by a check of the seepage ramp, and a crack plate has nothing to inject at
    ramp = load_scene(
        "meshes/scenes/borehole_seepage.toml", "coarse",
        overrides={"solver.break_landing": "tolerance"},
    )  # fmt: skip
    # named with its file, as a check made while loading it would be
    with pytest.raises(SceneError, match=r"^borehole_seepage\.toml: solver\.break_landing"):
        run_scene(ramp, out, force=True)
    plate = parse_scene(
        {**_toml("meshes/scenes/crack_plate.toml"), **_toml(KGD, ("rock", "stress", "fluid",
         "injection"))}, "plate_injected", "coarse",
    )  # fmt: skip
    with pytest.raises(SceneError, match="no wellbore, tunnel or injection point"):
        run_scene(plate, out, force=True)
    assert {n: (out / n).read_text() for n in before} == before


def _toml(path, sections=None):
    import tomllib

    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    if sections is None:
        return {k: v for k, v in data.items() if k not in ("load",)}
    return {k: data[k] for k in sections if k in data}


def test_a_directory_of_other_files_is_not_written_into_without_force(shared_tmp_path):
    out = shared_tmp_path / "foreign"
    if MPI.COMM_WORLD.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        (out / "history.csv").write_text("mine\n")
    MPI.COMM_WORLD.barrier()
    with pytest.raises(OutputInUse, match=r"no run\.json"):
        run_scene(load_scene(KGD, "coarse"), out)
    assert (out / "history.csv").read_text() == "mine\n"
    assert not (out / "run.json").exists()


def test_cli_refuses_an_output_that_is_a_file(shared_tmp_path, capsys):
    target = shared_tmp_path / "a_file"
    if MPI.COMM_WORLD.rank == 0:
        target.write_text("keep\n")
    MPI.COMM_WORLD.barrier()
    assert main(["run", KGD, "--resolution", "coarse", "-o", str(target)]) == 3
    if MPI.COMM_WORLD.rank == 0:
        assert "is a file, not a directory" in capsys.readouterr().err
    assert target.read_text() == "keep\n"


def test_cli_says_when_a_run_until_its_first_crack_found_none(shared_tmp_path, capsys):
    out = shared_tmp_path / "no_first_crack"
    args = ["run", BOREHOLE, "--resolution", "coarse", "-o", str(out), "--set",
            'injection.until="first crack"', "--set", 'injection.duration="0.05 s"']  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["first_crack_pressure_MPa"] is None
    if MPI.COMM_WORLD.rank == 0:
        assert "no first crack by the end of the injection" in capsys.readouterr().out


@pytest.mark.parametrize(
    "path, what",
    [
        ("meshes/scenes/borehole_seepage.toml", "seepage"),
        ("meshes/scenes/sneddon_plate.toml", "static"),
    ],
)
def test_a_resume_of_a_run_without_checkpoints_is_refused(shared_tmp_path, path, what):
    out = shared_tmp_path / f"no_checkpoint_{what}"
    if MPI.COMM_WORLD.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        (out / "history.csv").write_text("time\n1.0\n")
    MPI.COMM_WORLD.barrier()
    with pytest.raises(SceneError, match=f"--resume: .*{what}.* keeps no checkpoint"):
        run_scene(load_scene(path, "coarse"), out, resume=True)
    # refused before anything was written: the stopped run's files are as they were
    assert (out / "history.csv").read_text() == "time\n1.0\n"
    assert not (out / "run.json").exists()


def test_a_stopped_run_resumes_where_it_stopped(shared_tmp_path):
    scene, straight, out = _straight_and_stopped(shared_tmp_path)
    kept = (out / "history.csv").read_text().splitlines()
    assert 2 < len(kept) < len((straight / "history.csv").read_text().splitlines())
    # the checkpoint holds the state, the history is in history.csv, appended step by step
    data = json.loads((out / "checkpoint.json").read_text())
    assert "history" not in data
    assert data["steps"] == len(kept) - 1
    header, straight_rows = kept[0].split(","), (straight / "history.csv").read_text().splitlines()
    t = header.index("time")
    assert [r.split(",")[t] for r in kept[1:]] == [
        r.split(",")[t] for r in straight_rows[1 : len(kept)]
    ]
    frames_before = read_pvd(out / "interfaces.pvd")
    summary = run_scene(scene, out, resume=True)
    assert summary["simulated_time_s"] == pytest.approx(10.0)
    # what happened before the stop is still counted
    first = json.loads((straight / "summary.json").read_text())
    assert summary["first_crack"]["point_m"] == pytest.approx(first["first_crack"]["point_m"])
    assert summary["first_crack_pressure_bound_MPa"] == pytest.approx(
        first["first_crack_pressure_bound_MPa"], rel=1e-9
    )
    assert summary["initial_failures"] == first["initial_failures"]
    assert summary["rebuilds"] >= first["rebuilds"]
    causes = summary["rebuild_causes"]  # kept through the checkpoint, plus the resume
    assert sum(causes.values()) == summary["rebuilds"] and causes["resume"] == 1
    # the interface frames written before the stop are kept, the series goes on
    frames = read_pvd(out / "interfaces.pvd")
    assert frames[: len(frames_before)] == frames_before
    assert [t for t, _ in frames] == pytest.approx(
        [t for t, _ in read_pvd(straight / "interfaces.pvd")]
    )
    assert (out / "fields_resumed.bp").is_dir()

    def pressures(path):
        lines = (path / "history.csv").read_text().splitlines()
        col = lines[0].split(",").index("injection_pressure")
        return [float(line.split(",")[col]) for line in lines[1:]]

    assert pressures(out) == pytest.approx(pressures(straight), rel=1e-9)


def test_a_reduced_run_resumes_on_the_band_it_had(shared_tmp_path):
    # the borehole cracks at about 12.7 s; stopped after it, the band holds the crack,
    # its rings and the walls: the resumed run solves the same system as the straight one
    scene = load_scene(BOREHOLE, "coarse", overrides={"solver.solid": "reduced"})
    straight = run_scene(scene, shared_tmp_path / "straight")
    out = shared_tmp_path / "resumed"
    with pytest.raises(Interrupted):
        run_scene(scene, out, observers=[StopAt(13.0)])
    data = json.loads((out / "checkpoint.json").read_text())
    assert data["interfaces"] and len(data["band"]) > len(data["interfaces"])
    resumed = run_scene(scene, out, resume=True)
    assert resumed["free_interfaces"] == straight["free_interfaces"]
    assert resumed["tensile_failures"] == straight["tensile_failures"]
    # in-place updates after the resume sum in another order, and the crack's growth
    # amplifies it: 1.14e-7 measured on 2 ranks (the last 4 of 94 steps), below 5e-8 serially
    assert _pressures(out) == pytest.approx(_pressures(shared_tmp_path / "straight"), rel=2e-7)


def _pressures(path):
    lines = (path / "history.csv").read_text().splitlines()
    col = lines[0].split(",").index("injection_pressure")
    return [float(line.split(",")[col]) for line in lines[1:]]


@pytest.mark.mpi
def test_a_run_stopped_on_two_ranks_resumes_on_one(shared_tmp_path):
    # interfaces are keyed by global vertex ids, so the checkpoint does not depend on the
    # partition: stop on every rank, go on with rank 0 alone
    world = MPI.COMM_WORLD
    scene, straight, out = _straight_and_stopped(shared_tmp_path)
    world.barrier()
    error = None
    if world.rank == 0:
        try:
            summary = run_scene(scene, out, comm=MPI.COMM_SELF, resume=True)
            assert summary["simulated_time_s"] == pytest.approx(10.0)
            assert summary["ranks"] == 1
            assert _pressures(out) == pytest.approx(_pressures(straight), rel=1e-6)
        except AssertionError as exc:
            error = exc
    error = world.bcast(error, root=0)
    if error is not None:
        raise error


def test_the_linear_solver_is_a_scene_choice_with_the_same_answer(shared_tmp_path):
    scenes = {
        kind: load_scene(
            KGD, "coarse", overrides={"injection.duration": "2 s", "solver.linear_solver": kind}
        )
        for kind in ("direct", "iterative")
    }
    runs = {kind: run_scene(s, shared_tmp_path / kind) for kind, s in scenes.items()}
    assert runs["direct"]["peak_pressure_MPa"] == pytest.approx(
        runs["iterative"]["peak_pressure_MPa"], rel=1e-5
    )
    assert _pressures(shared_tmp_path / "direct") == pytest.approx(
        _pressures(shared_tmp_path / "iterative"), rel=1e-5
    )


def test_a_cased_wellbore_leaves_only_the_tunnel_walls_pressurised():
    names = ["outer_x0", "perforation_1_tip", "perforation_1_wall", "rock", "wellbore_wall"]
    assert pressurised_groups(names, "cased") == ("perforation_1_tip", "perforation_1_wall")
    assert pressurised_groups(names, "open") == (
        "perforation_1_tip",
        "perforation_1_wall",
        "wellbore_wall",
    )
    # a borehole without tunnels is open hole whatever the setting
    assert pressurised_groups(["outer", "wellbore_wall"], "cased") == ("wellbore_wall",)
    # the casing supports the rock: it holds the blocks cut loose against it
    for wellbore, held in (("cased", ("wellbore_wall",)), ("open", ())):
        assert supporting_walls(names, pressurised_groups(names, wellbore), wellbore) == held
    assert supporting_walls(names, ()) == ()  # no cavity, no debris
    # a drilled wellbore: the tunnels take the pressure, the casing's springs hold the wall
    cavity = pressurised_groups(names, "drilled")
    assert cavity == ("perforation_1_tip", "perforation_1_wall")
    assert supporting_walls(names, cavity, "drilled") == ()


def test_set_replaces_a_scene_field_and_is_checked_like_the_file(shared_tmp_path, capsys):
    scene = load_scene(KGD, "coarse", overrides={"injection.duration": "2 s"})
    assert scene.physics.duration == pytest.approx(2.0)
    with pytest.raises(SceneError, match=r"injection\.duration"):
        load_scene(KGD, "coarse", overrides={"injection.duration": "2 m"})
    out = shared_tmp_path / "bad_set"
    assert main(["run", KGD, "-o", str(out), "--set", "rock.poisson_ratio=0.5"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:  # only rank 0 prints
        assert "rock.poisson_ratio" in err
    assert main(["run", KGD, "-o", str(out), "--set", "novalue"]) == 2
    assert not (out / "run.json").exists()


def test_summary_holds_the_resolved_scene(shared_tmp_path):
    out = shared_tmp_path / "resolved"
    scene = load_scene(KGD, "coarse", overrides={"injection.duration": "1 s"})
    summary = run_scene(scene, out, force=True)
    on_disk = json.loads((out / "summary.json").read_text())
    resolved = on_disk["resolved_scene"]
    assert resolved["physics"]["duration"] == pytest.approx(1.0)
    assert resolved["physics"]["rock"]["youngs_modulus"] == pytest.approx(25e9)
    assert resolved["geometry"]  # every geometry field, defaults filled in
    # zero toughness: the path breaks in the first step, from the initial 0 MPa; no
    # step landed on it, so it is said as a range up to the pressure it broke at
    assert summary["first_crack_pressure_MPa"] == pytest.approx(0.0)
    assert summary["first_crack_time_s"] <= 0.5
    # (the path still shut then: 15.3 MPa, above every accepted step's after it broke)
    high = summary["first_crack_pressure_bound_MPa"]
    assert high > summary["peak_pressure_MPa"] > 0.0
    assert first_crack_pressure_words(summary) == (
        f"between 0.00 and {high:.2f} MPa (no step landed on it)"
    )


def test_a_tunnel_run_records_sigma_xx_at_its_first_crack(shared_tmp_path):
    """The paper's Fig. 18: No. 2 (coarse) pumped 20x faster, so it cracks within 4 s.

    The least compressive sigma_xx of the zone is at the tunnel's tip face, whose
    normal is x: there sigma_xx = -p, the cavity pressure (0.7 % off, cell means).
    """
    fast = {"injection.rate": "1e-6 m3/s", "injection.duration": "4 s"}
    scene = load_scene("meshes/scenes/perforation_no2.toml", "coarse", overrides=fast)
    out = shared_tmp_path / "no2_fast"
    summary = run_scene(scene, out)
    first = summary["first_crack"]
    profile = first["sigma_xx"]
    assert first["time_s"] == summary["first_crack_time_s"]
    assert profile["cells"] > 1000 and len(profile["largest_MPa"]) == 12
    assert profile["peak_MPa"] >= max(v for v in profile["largest_MPa"] if v is not None)
    assert profile["peak_place"] == "beyond the tip"
    with (out / "history.csv").open() as f:
        rows = [r for r in csv.DictReader(f) if float(r["time"]) == first["time_s"]]
    pressure = float(rows[0]["injection_pressure"]) / 1e6
    assert profile["peak_MPa"] == pytest.approx(-pressure, rel=0.01)
    assert (out / "sigma_xx.png").stat().st_size > 0
    # the first crack is the facet that reached its strength first: its part of the
    # tunnel holds the highest failure ratio then, the others how near they came
    ratios = first["ratio_by_place"]
    assert ratios[first["place"]] == max(ratios.values()) and ratios[first["place"]] >= 1.0
    assert first["mode"] == "tensile"
    assert sum(first["interfaces_by_place"].values()) == first["interfaces"]


def test_a_strength_length_below_the_cells_an_unused_fidelity_and_tension_are_said():
    from hfcdem.workflows.run import _warn_unresolved

    def said(path, **sets):
        lines = []
        _warn_unresolved(load_scene(path, "coarse", overrides=sets), lines.append)
        return " ".join(lines)

    assert "below the cells' size at the cavity (6 mm)" in said(
        BOREHOLE, **{"rock.strength_length": "1 mm"}
    )
    assert said(BOREHOLE, **{"rock.strength_length": "12 mm"}) == ""
    assert said(BOREHOLE) == ""
    assert "stress.sh_min = -5 MPa is tension" in said(BOREHOLE, **{"stress.sh_min": "-5 MPa"})
    seepage = "meshes/scenes/borehole_seepage.toml"
    assert "solver.fidelity is not used" in said(seepage, **{"solver.fidelity": "viscous"})
    assert said(seepage) == ""


def test_the_first_step_after_initial_failures_is_shortened_onto_the_first_crack(
    shared_tmp_path,
):
    """The lab specimen at 45 deg: the in-situ stress alone breaks 7 interfaces at the root.

    The step controller took the settled state's failure ratio as 1 (a step that broke),
    so the first step could not be shortened: the first crack came somewhere in 0-2.29 MPa
    at 0.25 s.  With the settled state's own ratio it is located in 0-0.42 MPa, 0.043 s.
    """
    scene = load_scene(
        "meshes/scenes/lab_specimen_45deg.toml",
        "coarse",
        overrides={"injection.until": "first crack"},
    )
    summary = run_scene(scene, shared_tmp_path / "lab45_first")
    assert summary["initial_failures"] == 7
    assert summary["first_crack_time_s"] < 0.05
    assert summary["first_crack_pressure_bound_MPa"] < 0.5
