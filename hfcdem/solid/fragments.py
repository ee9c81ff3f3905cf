"""Blocks cut loose from the rock: cells held to the rest only through broken faces.

A fragment is a set of cells joined to each other by intact interfaces or glued
facets, and to nothing else.  The rock mass is the fragment that holds a glued
cell (outside the fracturable zone) or a cell on a fixed face; with neither, the
largest.  Any other fragment is loose: held by contact and friction alone, it
has no static equilibrium once the loads on it outgrow its friction (a wedge at
the tunnel wall slides out along its broken faces, by metres in a
small-displacement solid).

A loose fragment that touches the cavity wall, or touches debris, is debris: the fluid
surrounds it, so its broken faces take the cavity pressure and are held open
(:meth:`~hfcdem.solid.cdem.CDEMSolid.release_facets`).  Under one pressure on
every face it is in equilibrium, and the rock behind it carries that pressure as
a new piece of wall.  Every function here is collective and gives the same
answer on every rank.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from mpi4py import MPI
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState


def _global_cells(solid: CDEMSolid, local: np.ndarray) -> np.ndarray:
    imap = solid.mesh.topology.index_map(solid.mesh.topology.dim)
    flat = np.asarray(local, dtype=np.int32).reshape(-1)
    return imap.local_to_global(flat).astype(np.int64).reshape(np.shape(local))


def _gather(comm: MPI.Comm, rows: np.ndarray) -> np.ndarray:
    return np.concatenate(comm.allgather(np.ascontiguousarray(rows, dtype=np.int64)), axis=0)


def _cells_of(solid: CDEMSolid, facets: np.ndarray) -> np.ndarray:
    """Local cells on either side of local ``facets`` (one or two each)."""
    tdim = solid.mesh.topology.dim
    solid.mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = solid.mesh.topology.connectivity(tdim - 1, tdim)
    offsets, links = f2c.offsets, f2c.array
    facets = np.asarray(facets, dtype=np.int64)
    first = links[offsets[facets]]
    two = offsets[facets + 1] - offsets[facets] == 2
    return np.concatenate([first, links[offsets[facets[two]] + 1]])


def _components(nodes: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the unique node ids and the component of each, from undirected ``edges``."""
    ids, inverse = np.unique(np.concatenate([nodes, edges.reshape(-1)]), return_inverse=True)
    e = inverse[nodes.size :].reshape(-1, 2)
    graph = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(ids.size, ids.size))
    return ids, connected_components(graph, directed=False)[1]


def cells_on(solid: CDEMSolid, names: Sequence[str]) -> np.ndarray:
    """Global indices of the cells with a face in the facet groups ``names`` (sorted)."""
    facets = [solid.tmesh.facets(name) for name in names]
    local = _cells_of(solid, np.concatenate(facets) if facets else np.zeros(0, np.int64))
    return np.unique(_gather(solid.comm, _global_cells(solid, local)))


class Fragments:
    """The pieces the broken interfaces of ``solid`` cut it into; ``walls`` bound the cavity."""

    def __init__(self, solid: CDEMSolid, walls: Sequence[str]) -> None:
        self.solid = solid
        glued = _global_cells(solid, _cells_of(solid, solid.glue_facets))
        held = np.union1d(
            np.unique(_gather(solid.comm, glued)), cells_on(solid, solid.fixed_groups)
        )
        own = solid.owned
        self._pairs = _global_cells(solid, solid.cells[own]).reshape(-1, 2)
        self._nodes = _gather(solid.comm, self._pairs.reshape(-1))
        zone = np.unique(self._nodes)
        self.anchored = np.intersect1d(held, zone)  # only cells with interfaces matter
        self.wall_cells = np.intersect1d(cells_on(solid, walls), zone)
        self._groups_cells: dict[tuple[str, ...], np.ndarray] = {}  # the mesh never changes

    def _intact_pairs(self) -> np.ndarray:
        own = self.solid.owned
        intact = self.solid.state[own] == FacetState.INTACT
        return _gather(self.solid.comm, self._pairs[intact].reshape(-1)).reshape(-1, 2)

    def loose_cells(self) -> np.ndarray:
        """Global indices of the cells in loose fragments (sorted; empty when none)."""
        ids, label = _components(self._nodes, self._intact_pairs())
        if ids.size == 0:
            return ids
        held = np.isin(ids, self.anchored)
        if held.any():
            rock = np.unique(label[held])
        else:  # no glue and no fixed face: the largest piece is the rock
            rock = np.array([np.argmax(np.bincount(label))])
        return ids[~np.isin(label, rock)]

    def loose_cells_on(self, groups: Sequence[str], loose: np.ndarray | None = None) -> np.ndarray:
        """Global indices of the loose cells with a face in the facet groups ``groups`` (sorted).

        ``loose``: the :meth:`loose_cells` of the current states, when the
        caller has them (they are found again otherwise).
        """
        if not groups:
            return np.zeros(0, dtype=np.int64)
        key = tuple(groups)
        if key not in self._groups_cells:
            self._groups_cells[key] = cells_on(self.solid, groups)  # collective, once
        loose = self.loose_cells() if loose is None else loose
        return np.intersect1d(loose, self._groups_cells[key])

    def debris(self, loose: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """Broken local facets around debris, not yet released, and the debris' cell count.

        Debris: the loose fragments with a cell on the cavity walls, and the loose
        fragments that touch debris (through broken faces): the fluid fills the
        gaps of a pile of loose blocks at the wall, and a block next to debris
        whose faces take the cavity pressure has lost its support there.
        ``loose``: the :meth:`loose_cells` of the current states, when the
        caller has them.
        """
        solid, none = self.solid, (np.zeros(0, dtype=np.int64), 0)
        loose = self.loose_cells() if loose is None else loose
        on_wall = np.intersect1d(loose, self.wall_cells)
        if on_wall.size == 0:
            return none
        pairs = self._nodes.reshape(-1, 2)  # every interface, intact or broken
        ids, label = _components(loose, pairs[np.all(np.isin(pairs, loose), axis=1)])
        debris = ids[np.isin(label, label[np.isin(ids, on_wall)])]
        around = np.any(np.isin(_global_cells(solid, solid.cells), debris), axis=1)
        chosen = np.flatnonzero(around & (solid.state != FacetState.INTACT) & ~solid.released)
        return chosen, int(debris.size)


__all__ = ["Fragments", "cells_on"]
