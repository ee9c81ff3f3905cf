"""A CDEM solid on a 4 x 2 rectangle mesh (16 triangles) for fast coupling tests.

Not a test module: imported by test_condense, test_groups, test_checkpoint,
test_events, test_fields and test_cdem (``tag_sides``); ``unit_block`` by
test_reduction and test_band.  The vertical facets
on x = 1 can be broken into a two-facet crack.
"""

import dolfinx
import numpy as np
from mpi4py import MPI

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid


def tag_sides(mesh: dolfinx.mesh.Mesh, x_right: float) -> TaggedMesh:
    """Tag the edges x = 0 'left' and x = ``x_right`` 'right', every cell 'rock'."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    left = dolfinx.mesh.locate_entities_boundary(mesh, 1, lambda p: np.isclose(p[0], 0.0))
    right = dolfinx.mesh.locate_entities_boundary(mesh, 1, lambda p: np.isclose(p[0], x_right))
    facets = np.concatenate([left, right]).astype(np.int32)
    values = np.concatenate([np.full(len(left), 1), np.full(len(right), 2)]).astype(np.int32)
    order = np.argsort(facets)
    ftags = dolfinx.mesh.meshtags(mesh, 1, facets[order], values[order])
    cells = np.arange(mesh.topology.index_map(2).size_local, dtype=np.int32)
    ctags = dolfinx.mesh.meshtags(mesh, 2, cells, np.ones_like(cells))
    return TaggedMesh(mesh, ctags, ftags, {"rock": 1}, {"left": 1, "right": 2})


def unit_block(dim: int, comm: MPI.Comm = MPI.COMM_WORLD) -> TaggedMesh:
    """Unit square (cube) with its faces x = 0 'left', x = 1 'right' and y = 0 'bottom'."""
    if dim == 2:
        mesh = dolfinx.mesh.create_unit_square(comm, 8, 6)
    else:
        mesh = dolfinx.mesh.create_unit_cube(comm, 4, 3, 3)
    fdim = dim - 1
    sides = {"left": (0, 0.0), "right": (0, 1.0), "bottom": (1, 0.0)}
    idx, vals = [], []
    for tag, (axis, at) in enumerate(sides.values(), start=1):
        found = dolfinx.mesh.locate_entities_boundary(
            mesh, fdim, lambda x, a=axis, v=at: np.isclose(x[a], v)
        )
        idx.append(found)
        vals.append(np.full(len(found), tag, dtype=np.int32))
    idx_all, vals_all = np.concatenate(idx), np.concatenate(vals)
    idx_all, first = np.unique(idx_all, return_index=True)  # an edge facet keeps one group
    facet_tags = dolfinx.mesh.meshtags(mesh, fdim, idx_all, vals_all[first])
    cmap = mesh.topology.index_map(dim)
    cells = np.arange(cmap.size_local + cmap.num_ghosts, dtype=np.int32)
    cell_tags = dolfinx.mesh.meshtags(mesh, dim, cells, np.ones_like(cells))
    names = {name: k for k, name in enumerate(sides, start=1)}
    return TaggedMesh(mesh, cell_tags, facet_tags, {"rock": 1}, names)


def tiny_solid(
    comm: MPI.Comm = MPI.COMM_WORLD, stress: float = 1e6, mode: str = "full"
) -> CDEMSolid:
    """Rock in [0, 2] x [0, 1]: wall 'left' (x = 0), 'right' (x = 2) fixed."""
    mesh = dolfinx.mesh.create_rectangle(
        comm, [[0.0, 0.0], [2.0, 1.0]], [4, 2], ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    tmesh = tag_sides(mesh, 2.0)
    return CDEMSolid(
        tmesh,
        ElasticMaterial(10e9, 0.25),
        InSituStress(stress, 0.5 * stress),
        InterfaceModel(alpha=100, tensile_strength=1e6),
        fixed=("right",),
        mode=mode,
    )


def crack_facets(solid: CDEMSolid) -> np.ndarray:
    """Local interface facets on the line x = 1 (two facets, owned or ghost)."""
    return np.flatnonzero(np.isclose(solid.midpoints[:, 0], 1.0))


def break_crack(solid: CDEMSolid) -> None:
    """Break the two facets on x = 1 in tension (collective; they start open)."""
    mine = crack_facets(solid)
    mine = mine[solid.owned[mine]]
    solid.break_facets(mine, np.ones(len(mine), dtype=np.int8), 0.0)
