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
