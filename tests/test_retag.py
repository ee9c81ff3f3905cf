"""A form compiled once and retagged equals one compiled for the new tags."""

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI

from hfcdem.solid.retag import TaggedForm

comm = MPI.COMM_WORLD


def interior_tags(mesh: dolfinx.mesh.Mesh, seed: int) -> dolfinx.mesh.MeshTags:
    """Tag the local facets 1 or 2 by a pattern that moves with ``seed`` (ghosts as owners)."""
    fdim = mesh.topology.dim - 1
    mesh.topology.create_entities(fdim)
    mesh.topology.create_connectivity(fdim, fdim + 1)
    imap = mesh.topology.index_map(fdim)
    n = imap.size_local + imap.num_ghosts
    mids = dolfinx.mesh.compute_midpoints(mesh, fdim, np.arange(n, dtype=np.int32))
    values = 1 + (np.floor(7.0 * mids[:, 0] + 3.0 * mids[:, 1] + seed) % 2).astype(np.int32)
    return dolfinx.mesh.meshtags(mesh, fdim, np.arange(n, dtype=np.int32), values)


def build(mesh, V, dS):
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    k = dolfinx.fem.Constant(mesh, 3.0)
    f = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("DG", 0)))
    f.x.array[:] = 1.0 + np.arange(f.x.array.size) % 5
    a = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    a += k * ufl.inner(ufl.jump(u), ufl.jump(v)) * dS(1)
    a += ufl.avg(f) * ufl.inner(ufl.jump(u), ufl.jump(v)) * dS(2)
    a += ufl.inner(u, v) * ufl.ds
    return a


def assembled(form) -> np.ndarray:
    A = dolfinx.fem.petsc.assemble_matrix(form)
    A.assemble()
    dense = A.convert("dense").getDenseArray().copy()
    A.destroy()
    return dense


def test_a_retagged_form_assembles_as_one_compiled_for_the_tags():
    mesh = dolfinx.mesh.create_unit_square(
        comm, 4, 3, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    V = dolfinx.fem.functionspace(mesh, ("DG", 1))
    first = interior_tags(mesh, 0)
    tagged = TaggedForm(build(mesh, V, ufl.Measure("dS", domain=mesh, subdomain_data=first)))
    for seed in (0, 1, 5):
        tags = interior_tags(mesh, seed)
        fresh = dolfinx.fem.form(
            build(mesh, V, ufl.Measure("dS", domain=mesh, subdomain_data=tags))
        )
        want, got = assembled(fresh), assembled(tagged.form(tags))
        gap = comm.allreduce(float(np.abs(got - want).max()), op=MPI.MAX)
        assert gap < 1e-13 * comm.allreduce(float(np.abs(want).max()), op=MPI.MAX)
    # the tags matter: another pattern assembles another matrix
    other = assembled(tagged.form(interior_tags(mesh, 1)))
    base = assembled(tagged.form(first))
    assert comm.allreduce(float(np.abs(other - base).max()), op=MPI.MAX) > 0.1
