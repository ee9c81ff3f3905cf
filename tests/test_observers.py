"""The mesh fingerprint behind --resume: the same on any rank count, different on another mesh."""

from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.workflows.observers import mesh_fingerprint

KGD = "meshes/scenes/kgd_strip.toml"


def test_the_mesh_fingerprint_does_not_depend_on_the_rank_count(comm):
    scene = load_scene(KGD, "coarse")
    world = mesh_fingerprint(create_scene_mesh(scene, comm).tmesh)
    alone = mesh_fingerprint(create_scene_mesh(scene, MPI.COMM_SELF).tmesh)
    assert world == alone
    assert len(set(comm.allgather(world))) == 1
    finer = mesh_fingerprint(create_scene_mesh(load_scene(KGD), comm).tmesh)
    assert finer != world


def test_the_progress_line_times_a_resumed_run_from_where_it_began():
    from types import SimpleNamespace

    from hfcdem.coupling.records import StepRecord
    from hfcdem.workflows.observers import ProgressLine

    said: list[str] = []
    line = ProgressLine(said.append, t_end=9.0)
    # resumed at 6 s, its clock at 500 s (the first session's and the set-up's)
    line.start(SimpleNamespace(t=6.0, wall_time=lambda: 500.0))
    row = {k: str(v) for k, v in dict.fromkeys(StepRecord.__dataclass_fields__, 0).items()}
    rec = StepRecord.from_row({**row, "time": "7", "dt": "1", "wall_time": "530"})
    line.step(None, rec)
    # 30 s for the first second since the resume: 60 s for the 2 s left (the mean since
    # the clock's start would say 530 / 7 * 2 = 151 s)
    assert said[-1].endswith("wall   530.0 s  eta   60 s")
