"""`hfcdem study`: a sweep of one scene field, cases skipped when done."""

from pathlib import Path

import pytest
from mpi4py import MPI
from stopping import Interrupted, StopAt

from hfcdem.cli import main
from hfcdem.config.scene import set_field as _set
from hfcdem.config.tables import SceneError
from hfcdem.workflows.run import OutputInUse, run_scene, scene_fingerprint
from hfcdem.workflows.study import (
    case_directory,
    case_stopped,
    load_study,
    numeric,
    run_study,
)

SCENE = "../meshes/scenes/kgd_strip.toml"


def _write(path, text):
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(text)
    MPI.COMM_WORLD.barrier()


@pytest.fixture
def study_file(shared_tmp_path):
    import os

    scene = os.path.relpath(os.path.abspath("meshes/scenes/kgd_strip.toml"), shared_tmp_path)
    path = shared_tmp_path / "rate.toml"
    _write(
        path,
        f"""
name = "rate"
scene = "{scene}"
resolution = "coarse"
[sweep]
parameter = "injection.rate"
values = ["1e-3 m3/s", "4e-3 m3/s"]
[set]
"injection.duration" = "3 s"
""",
    )
    return path


def test_study_runs_every_case_and_tables_them(study_file, shared_tmp_path):
    out = shared_tmp_path / "out"
    rows = run_study(load_study(study_file), out)
    assert [r["x"] for r in rows] == [pytest.approx(1e-3), pytest.approx(4e-3)]
    # KGD: the length grows as Q^(1/2), the net pressure does not depend on Q
    assert rows[1]["tensile_failures"] > 1.5 * rows[0]["tensile_failures"]
    assert rows[1]["peak_pressure_MPa"] > 0.0
    lines = (out / "results.csv").read_text().splitlines()
    assert len(lines) == 3 and lines[0].startswith("value,case,x,")
    assert lines[2].startswith("4e-3 m3/s,1,0.004,")
    assert (out / "study.png").stat().st_size > 0
    # a second run finds both cases done
    stamp = (out / "case_0_1e-3_m3_s" / "summary.json").stat().st_mtime
    assert main(["study", str(study_file), "-o", str(out)]) == 0
    assert (out / "case_0_1e-3_m3_s" / "summary.json").stat().st_mtime == stamp


def test_bad_study_input_is_named_before_running(shared_tmp_path, study_file):
    bad = shared_tmp_path / "bad.toml"
    _write(bad, study_file.read_text().replace('"1e-3 m3/s"', '"1e-3 m3"'))
    with pytest.raises(SceneError, match=r"injection\.rate"):
        load_study(bad)
    MPI.COMM_WORLD.barrier()  # every rank has read it before rank 0 rewrites it
    _write(bad, study_file.read_text().replace("[sweep]", "colour = 1\n[sweep]"))
    with pytest.raises(SceneError, match="colour"):
        load_study(bad)
    # a case's bad key: the case, then the key, with no empty slot between
    with pytest.raises(SceneError) as err:
        load_study(study_file).with_fixed({"rock.tensile_strenght": "1 MPa"}).case_scene(0)
    assert str(err.value).startswith("case 0 (") and ": :" not in str(err.value)
    assert "rock.tensile_strenght: unknown key" in str(err.value)


def test_keys_moved_with_the_swept_one(shared_tmp_path, study_file):
    text = study_file.read_text().replace(
        "[set]", '[sweep.with]\n"injection.duration" = ["2 s", "1 s"]\n[set]'
    )
    text = text.replace('"injection.duration" = "3 s"\n', "")
    moved = shared_tmp_path / "moved.toml"
    _write(moved, text)
    study = load_study(moved)
    scenes = [study.case_scene(k) for k in range(2)]
    assert [s.physics.duration for s in scenes] == [2.0, 1.0]
    assert [s.physics.injection.points[-1][1] for s in scenes] == [1e-3, 4e-3]
    with pytest.raises(SceneError, match=r"sweep\.values: 3 values, but sweep\.with moves"):
        study.with_values(("1e-3 m3/s", "2e-3 m3/s", "4e-3 m3/s"))
    MPI.COMM_WORLD.barrier()
    _write(moved, text.replace('["2 s", "1 s"]', '["2 s"]'))
    with pytest.raises(SceneError, match=r"sweep\.with\.injection\.duration: expected a list of 2"):
        load_study(moved)
    MPI.COMM_WORLD.barrier()
    _write(moved, text.replace("[sweep.with]", "[sweep.also]"))
    with pytest.raises(SceneError, match=r"sweep\.also: unknown key"):
        load_study(moved)


def test_set_indexes_arrays_of_tables():
    doc = {"geometry": {"perforations": [{"profile": "no2"}, {"profile": "no1"}]}}
    _set(doc, "geometry.perforations.1.profile", "1-1")
    assert doc["geometry"]["perforations"] == [{"profile": "no2"}, {"profile": "1-1"}]
    with pytest.raises(SceneError, match="index below 2"):
        _set(doc, "geometry.perforations.2.profile", "1-1")
    with pytest.raises(SceneError, match="not a table"):
        _set(doc, "geometry.perforations.0.profile.x", 1)


def test_case_folders_are_named_by_value():
    assert case_directory(1, "1-1") == "case_1_1-1"
    assert case_directory(0, "30 deg") == "case_0_30_deg"
    assert case_directory(2, "../x") == "case_2_x"  # never leaves the study folder
    assert case_directory(3, "") == "case_3"


def test_numeric_values():
    assert numeric("4 mm") == pytest.approx(4e-3)
    assert numeric(3) == 3.0
    assert numeric("shape_1-1") is None


@pytest.mark.mpi
def test_cases_run_at_once_in_rank_groups(study_file, shared_tmp_path):
    out = shared_tmp_path / "groups"
    rows = run_study(load_study(study_file), out, groups=MPI.COMM_WORLD.size)
    assert all(r.get("stopped", "missing") is None for r in rows)
    assert all(r["ranks"] == 1 for r in rows)  # each case had its own single rank


def test_a_static_study_tables_the_opening_and_converges_in_alpha(shared_tmp_path):
    # the shipped Sneddon study: the spring softening falls as 1/alpha
    study = load_study("studies/sneddon_alpha.toml").with_values((10, 100, 1000))
    out = shared_tmp_path / "alpha"
    rows = run_study(study, out)
    errors = [r["sneddon"]["centre_relative_error"] for r in rows]
    limit = errors[-1]
    assert abs(limit) < 0.02  # what is left is the discretisation
    assert 5.0 < (errors[0] - limit) / (errors[1] - limit) < 20.0  # one decade of alpha
    lines = (out / "results.csv").read_text().splitlines()
    assert lines[0].startswith("value,case,x,max_crack_opening_m,sneddon_centre_relative_error")
    assert (out / "study.png").stat().st_size > 0


def _stamps(out):
    """The modification time of each case's summary.json, by case folder."""
    return {p.parent.name: p.stat().st_mtime_ns for p in sorted(out.glob("case_*/summary.json"))}


def test_a_study_with_other_settings_is_refused_in_the_same_output(study_file, shared_tmp_path):
    base = load_study(study_file)
    out = shared_tmp_path / "again"
    first_dir, second_dir = (case_directory(k, v) for k, v in enumerate(base.values))
    run_study(base, out)
    first = _stamps(out)
    assert set(first) == {first_dir, second_dir}
    # fewer values, same settings: nothing runs, the tables list the values asked for only
    # and the dropped case's folder stays
    rows = run_study(base.with_values(base.values[:1]), out)
    assert [r["value"] for r in rows] == ["1e-3 m3/s"] and _stamps(out) == first
    lines = (out / "results.csv").read_text().splitlines()
    assert len(lines) == 2 and lines[1].startswith("1e-3 m3/s,0,")
    # other settings: refused before anything runs (once, cases were silently overwritten)
    shorter = base.with_fixed({"injection.duration": "2 s"}).with_values(base.values[:1])
    refused = rf"{first_dir} holds a run of .* with other settings.*--force.*another -o"
    with pytest.raises(OutputInUse, match=refused):
        run_study(shorter, out)
    assert _stamps(out) == first
    assert (out / "results.csv").read_text().splitlines() == lines
    # --force runs it over; then it is that study's, done and skipped
    rows = run_study(shorter, out, force=True)
    assert [r["value"] for r in rows] == ["1e-3 m3/s"]
    forced = _stamps(out)
    assert forced[first_dir] != first[first_dir] and forced[second_dir] == first[second_dir]
    run_study(shorter, out)
    assert _stamps(out) == forced
    # overwrite (as the report runs its cases): the changed case runs, the done one is skipped
    run_study(base, out, overwrite=True)
    last = _stamps(out)
    assert last[first_dir] != forced[first_dir] and last[second_dir] == first[second_dir]


def test_a_started_run_of_another_scene_is_refused_too(shared_tmp_path):
    """A run.json alone (a run that died before its summary) still belongs to that run."""
    study = load_study("studies/sneddon_alpha.toml").with_values((10,))
    out = shared_tmp_path / "started"
    case = out / case_directory(0, 10)
    if MPI.COMM_WORLD.rank == 0:
        case.mkdir(parents=True)
        (case / "run.json").write_text('{"scene": "other", "fingerprint": "0123"}')
    MPI.COMM_WORLD.barrier()
    with pytest.raises(OutputInUse, match="'other' with other settings"):
        run_study(study, out)
    # the command line says it in one line, exit 3
    assert main(["study", "studies/sneddon_alpha.toml", "--values", "10", "-o", str(out)]) == 3
    assert not (case / "summary.json").exists()
    MPI.COMM_WORLD.barrier()
    if MPI.COMM_WORLD.rank == 0:
        (case / "run.json").write_text("{not json")
    MPI.COMM_WORLD.barrier()
    with pytest.raises(OutputInUse, match=r"'\?' with other"):
        run_study(study, out)


def test_a_case_scene_is_named_for_its_case_not_the_base_scene():
    """The lab sweep's base is the 30 deg scene: its 60 deg pictures must not say 30deg."""
    study = load_study("studies/lab_azimuth.toml")
    assert study.case_scene(2).name == "lab_azimuth_case_2_60_deg"
    assert study.case_scene(0).name == "lab_azimuth_case_0_30_deg"


@pytest.mark.parametrize(
    "path",
    sorted(Path(__file__).resolve().parents[1].joinpath("studies").glob("*.toml")),
    ids=lambda p: p.stem,
)
def test_every_shipped_study_file_loads_with_every_case_valid(path):
    import tomllib

    from hfcdem.workflows.convergence import load_convergence

    kind = tomllib.loads(path.read_text()).get("kind", "sweep")
    study = (load_convergence if kind == "convergence" else load_study)(path)
    assert len(study.values) >= 2
    scenes = [study.case_scene(k) for k in range(len(study.values))]
    assert len({repr(s) for s in scenes}) == len(scenes)  # each case a different scene


def test_a_case_stopped_from_outside_goes_on_from_its_checkpoint(study_file, shared_tmp_path):
    study = load_study(study_file)
    out = shared_tmp_path / "stopped_study"
    case = out / case_directory(0, study.values[0])
    scene = study.case_scene(0)
    with pytest.raises(Interrupted):
        run_scene(scene, case, observers=[StopAt(1.0)])
    assert case_stopped(case, scene_fingerprint(scene))
    assert not case_stopped(case, scene_fingerprint(study.case_scene(1)))
    rows = run_study(study, out)
    assert [r["simulated_time_s"] for r in rows] == pytest.approx([3.0, 3.0])
    assert not case_stopped(case, scene_fingerprint(scene))  # finished: summary.json written
    assert (case / "fields_resumed.bp").is_dir()  # the resumed part's solid fields
