"""A pumped seepage run stopped from outside goes on from its checkpoint with ``--resume``.

The coarse pumped borehole to 14 s breaks first at 9.75 MPa (10.2 s); stopped
after 11 s and resumed, it ends as the run that was never stopped: the same
steps, pressures (to 5e-14 measured: the resumed solid is factorised afresh,
the straight one carries low-rank corrections), failures, counters and
frames.  A checkpoint written on one rank resumes on two.
"""

import json
import re
import time
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.cli import main
from hfcdem.config.scene import load_scene
from hfcdem.config.tables import SceneError
from hfcdem.io.series import read_pvd
from hfcdem.workflows import pumped_checkpoint
from hfcdem.workflows.pumped_checkpoint import CheckpointFile
from hfcdem.workflows.run import run_scene

SCENES = Path(__file__).resolve().parents[1] / "meshes/scenes"
PUMPING = SCENES / "borehole_pumping.toml"
SHORT = {"injection.duration": "14 s", "output.interval": "1 s"}


class _Stop(Exception):
    pass


def _stop_after(time_s):
    """A progress callback that stops the run at its first step line past ``time_s``."""

    def say(message):
        if message.startswith("  t ") and float(message.split()[1]) >= time_s:
            raise _Stop

    return say


def _rows(path):
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    """The run never stopped (COMM_WORLD), its summary and output directory."""
    out = Path(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("straight")), root=0))
    scene = load_scene(PUMPING, "coarse", overrides=SHORT)
    return run_scene(scene, out), out


def _stopped(out, comm=MPI.COMM_WORLD):
    scene = load_scene(PUMPING, "coarse", overrides=SHORT)
    with pytest.raises(_Stop):
        run_scene(scene, out, comm=comm, say=_stop_after(11.0))
    return scene


def test_a_stopped_pumped_run_resumes_where_it_stopped(straight, shared_tmp_path):
    first, straight_out = straight
    out = shared_tmp_path / "stopped"
    scene = _stopped(out)
    assert not (out / "summary.json").exists()
    data = json.loads((out / "checkpoint.json").read_text())
    kept = _rows(out / "history.csv")
    assert data["kind"] == "seepage_pumping" and 0 < data["steps"] <= len(kept)
    assert data["t"] == pytest.approx(kept[data["steps"] - 1, 0], rel=1e-12)
    assert data["first"] is not None  # stopped past the first break, which it keeps
    frames_before = read_pvd(out / "joints.pvd")
    said = []
    summary = run_scene(scene, out, resume=True, say=said.append)
    assert any(m.startswith(f"resumed at t = {data['t']:.6g} s") for m in said)
    assert not any(m.startswith("initial state") for m in said)  # said once, by the first run
    a, b = _rows(straight_out / "history.csv"), _rows(out / "history.csv")
    assert a.shape == b.shape
    assert b[:, 0] == pytest.approx(a[:, 0], rel=1e-12)
    assert b[:, 1] == pytest.approx(a[:, 1], rel=1e-12)  # measured 5e-14
    assert np.array_equal(b[:, 4:6], a[:, 4:6])  # tensile, shear after every step
    costs = _rows(out / "step_costs.csv")
    assert costs.shape[0] == b.shape[0] and costs[:, 0] == pytest.approx(b[:, 0], rel=1e-12)
    for key in ("tensile_failures", "shear_failures", "steps", "solid_solves", "low_rank_events"):
        assert summary[key] == first[key], key  # what came before the stop is counted
    for key in ("first_crack_pressure_MPa", "first_crack_time_s", "peak_pressure_MPa"):
        assert summary[key] == pytest.approx(first[key], rel=1e-12), key
    assert summary["first_crack"]["point_m"] == pytest.approx(first["first_crack"]["point_m"])
    assert summary["initial_failures"] == first["initial_failures"]
    assert summary["max_mass_error"] < 1e-9
    # the session before the stop, to its last checkpoint, is the case's cost too
    assert first["earlier_sessions_wall_time_s"] == 0.0
    assert summary["earlier_sessions_wall_time_s"] == pytest.approx(data["wall_s"])
    assert 0.0 < data["wall_s"] < first["wall_time_s"]
    # the joints' frames before the stop are kept and the series goes on at the same times
    frames = read_pvd(out / "joints.pvd")
    assert frames[: len([f for f in frames_before if f[0] <= data["t"]])] == [
        f for f in frames_before if f[0] <= data["t"]
    ]
    assert [t for t, _ in frames] == pytest.approx(
        [t for t, _ in read_pvd(straight_out / "joints.pvd")]
    )
    assert json.loads((out / "run.json").read_text())["scene"] == "borehole_pumping"


def test_a_checkpoint_written_on_one_rank_resumes_on_every_rank_count(straight, shared_tmp_path):
    first, straight_out = straight
    world = MPI.COMM_WORLD
    out = shared_tmp_path / f"alone_{world.rank}"  # each rank stops a run of its own
    scene = _stopped(out, MPI.COMM_SELF)
    world.barrier()
    summary = run_scene(scene, shared_tmp_path / "alone_0", resume=True)
    a, b = _rows(straight_out / "history.csv"), _rows(shared_tmp_path / "alone_0" / "history.csv")
    # one rank's sums against two ranks': 1.1e-12 measured, in the steps before the stop
    assert b[:, 1] == pytest.approx(a[:, 1], rel=1e-11)
    assert summary["tensile_failures"] == first["tensile_failures"]
    assert summary["ranks"] == world.size


def test_a_resume_refuses_what_it_cannot_go_on_from(shared_tmp_path):
    out = shared_tmp_path / "refused"
    scene = _stopped(out)
    before = {name: (out / name).read_text() for name in ("history.csv", "checkpoint.json")}
    finer = load_scene(PUMPING, overrides=SHORT)  # the default resolution: another mesh
    with pytest.raises(SceneError, match="another mesh"):
        run_scene(finer, out, resume=True, force=True)
    # a coupled (not seepage) run's checkpoint is not one to go on from, nor the reverse
    coupled = load_scene(SCENES / "borehole_plate.toml", "coarse")
    with pytest.raises(SceneError, match="is a pumped seepage run's"):
        run_scene(coupled, out, resume=True, force=True)
    assert {name: (out / name).read_text() for name in before} == before
    if MPI.COMM_WORLD.rank == 0:
        data = json.loads(before["checkpoint.json"])
        data.pop("kind")
        (out / "checkpoint.json").write_text(json.dumps(data))
    MPI.COMM_WORLD.barrier()
    with pytest.raises(SceneError, match="not a pumped seepage run's checkpoint"):
        run_scene(scene, out, resume=True)
    if MPI.COMM_WORLD.rank == 0:  # cut short: read on rank 0, refused on every rank
        (out / "checkpoint.json").write_text(before["checkpoint.json"][:1000])
    MPI.COMM_WORLD.barrier()
    with pytest.raises(SceneError, match=r"checkpoint\.json cannot be read: .*--force"):
        run_scene(scene, out, resume=True)
    if MPI.COMM_WORLD.rank == 0:  # a history shorter than the checkpoint's steps
        lines = before["history.csv"].splitlines(keepends=True)
        (out / "checkpoint.json").write_text(before["checkpoint.json"])
        (out / "history.csv").write_text("".join(lines[:2]))
    MPI.COMM_WORLD.barrier()
    with pytest.raises(SceneError, match=r"history\.csv holds 1 steps"):
        run_scene(scene, out, resume=True)


def test_checkpoints_are_spaced_by_what_writing_them_costs(shared_tmp_path, monkeypatch):
    monkeypatch.setattr(pumped_checkpoint, "SPACING", 10.0)
    writer = CheckpointFile(shared_tmp_path / "c.json", "mesh", {"a": 1}, MPI.COMM_WORLD)
    built = []

    def build():
        time.sleep(0.05)  # a write that costs 50 ms: the next is due 0.5 s later
        built.append(len(built))
        return {"steps": len(built)}

    writer.offer(build)
    writer.offer(build)  # at once: not due
    assert built == [0] and writer.written == 1
    time.sleep(0.6)
    writer.offer(build)
    assert built == [0, 1]
    data = json.loads((shared_tmp_path / "c.json").read_text())
    wall = data.pop("wall_s")
    assert data == {"steps": 2, "kind": "seepage_pumping", "mesh": "mesh", "workflow": {"a": 1}}
    assert 0.6 < wall < 5.0  # the session's wall time at the write (none before it)


def test_hfcdem_run_resume_says_the_time_before_the_resume(shared_tmp_path, capsys):
    out = shared_tmp_path / "cli"
    _stopped(out)
    sets = [f"--set={k}={json.dumps(v)}" for k, v in SHORT.items()]
    argv = ["run", str(PUMPING), "--resolution", "coarse", "-o", str(out), "--resume", *sets]
    assert main(argv) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    if MPI.COMM_WORLD.rank == 0:  # the CLI speaks on rank 0
        last = printed[-1]
        assert re.search(r" s \(and \d+\.\d s before the resume\); results in ", last), last
