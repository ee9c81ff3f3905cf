"""The interface facets of a CDEM mesh: which facets they are, and their geometry.

Facets of the fracturable zone and pre-existing cracks are interfaces (springs or
cracks); every other interior facet is glued.  Each rank holds its owned and ghost
interfaces; ``owned`` marks the ones it decides for.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import dolfinx
import numpy as np

from hfcdem.mesh.tagged import TaggedMesh

ZoneMarker = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True, eq=False)
class InterfaceFacets:
    """Interface facets of this rank (owned and ghost) and their geometry."""

    facets: np.ndarray  # (F,) local facet indices carrying springs or cracks
    cells: np.ndarray  # (F, 2) the cells on either side; n+ points out of the first
    is_crack: np.ndarray  # (F,) pre-existing crack
    glue_facets: np.ndarray  # local indices of the other interior facets
    owned: np.ndarray  # (F,) owned by this rank
    vertex_coords: np.ndarray  # (F, nv, 3)
    midpoints: np.ndarray  # (F, 3)
    normals: np.ndarray  # (F, gdim) unit, out of the first cell
    areas: np.ndarray  # (F,) area (length in 2D)
    h: np.ndarray  # (F,) mean diameter of the two cells
    vertex_ids: np.ndarray  # (F, nv) global input ids of the vertices

    def __post_init__(self) -> None:
        count = len(self.facets)
        for name in ("cells", "is_crack", "owned", "vertex_coords", "midpoints", "normals"):
            if len(getattr(self, name)) != count:
                raise ValueError(f"{name} must have one row per interface facet ({count})")

    @property
    def num_facets(self) -> int:
        """Number of interface facets on this rank (owned and ghost)."""
        return len(self.facets)

    @classmethod
    def build(
        cls, tmesh: TaggedMesh, zone: ZoneMarker | str | None, cracks: Sequence[str]
    ) -> InterfaceFacets:
        """Classify the interior facets of ``tmesh`` and measure the interfaces.

        ``zone``: the fracturable zone as a cell group, a facet group (a prescribed
        path), a marker of cell midpoints, or None (everywhere).
        """
        topology, tdim = tmesh.mesh.topology, tmesh.mesh.topology.dim
        for d0, d1 in ((tdim - 1, tdim), (tdim, tdim - 1), (tdim - 1, 0)):
            topology.create_connectivity(d0, d1)
        facets, cells, is_crack, glue, owned = _classify(tmesh, zone, cracks)
        return cls(facets, cells, is_crack, glue, owned, *_geometry(tmesh.mesh, facets, cells))


def _zone_cells(tmesh: TaggedMesh, zone: ZoneMarker | str | None, num_cells: int) -> np.ndarray:
    """Cells of the fracturable zone (none for a facet group: its facets are the zone)."""
    mesh, tdim = tmesh.mesh, tmesh.mesh.topology.dim
    if zone is None:
        return np.ones(num_cells, dtype=bool)
    if isinstance(zone, str) and zone in tmesh.facet_names:
        # a facet group: springs on exactly those facets (a prescribed fracture path)
        return np.zeros(num_cells, dtype=bool)
    if isinstance(zone, str):
        if zone not in tmesh.cell_names:
            known = ", ".join(sorted(tmesh.cell_names) + sorted(tmesh.facet_names))
            raise KeyError(
                f"fracturable zone {zone!r} is not a cell or facet group; known: {known}"
            )
        in_zone_cell = np.zeros(num_cells, dtype=bool)
        in_zone_cell[tmesh.cell_tags.find(tmesh.cell_names[zone])] = True
        return in_zone_cell
    mids = dolfinx.mesh.compute_midpoints(mesh, tdim, np.arange(num_cells, dtype=np.int32))
    return np.asarray(zone(mids.T), dtype=bool)


def _classify(
    tmesh: TaggedMesh, zone: ZoneMarker | str | None, cracks: Sequence[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return interface facets, their cells, crack flags, glue facets and owned flags."""
    mesh, tdim = tmesh.mesh, tmesh.mesh.topology.dim
    fmap = mesh.topology.index_map(tdim - 1)
    num_local = fmap.size_local + fmap.num_ghosts
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    counts = np.diff(f2c.offsets)
    interior = np.flatnonzero(counts == 2).astype(np.int32)
    crack_mask = np.zeros(num_local, dtype=bool)
    for name in cracks:
        if name in tmesh.facet_names:
            crack_mask[tmesh.facets(name)] = True
    # crack facets must be interior: a crack on the boundary is just a loaded face
    crack_mask &= counts == 2

    cmap = mesh.topology.index_map(tdim)
    in_zone_cell = _zone_cells(tmesh, zone, cmap.size_local + cmap.num_ghosts)
    cells = f2c.array.reshape(-1)  # interior facets only are indexed below
    first = f2c.offsets[interior]
    c0, c1 = cells[first], cells[first + 1]
    zone_facet = in_zone_cell[c0] & in_zone_cell[c1]
    if isinstance(zone, str) and zone in tmesh.facet_names:
        path_mask = np.zeros(num_local, dtype=bool)
        path_mask[tmesh.facets(zone)] = True
        zone_facet = path_mask[interior]

    keep = zone_facet | crack_mask[interior]
    facets = interior[keep]
    pair = np.column_stack([c0[keep], c1[keep]]).astype(np.int32)
    return facets, pair, crack_mask[facets], interior[~keep], facets < fmap.size_local


def _geometry(mesh: dolfinx.mesh.Mesh, facets: np.ndarray, cells: np.ndarray) -> tuple:
    """Vertex coordinates, midpoints, normals, areas, cell sizes and vertex ids of facets."""
    tdim, gdim = mesh.topology.dim, mesh.geometry.dim
    # DOLFINx divides by the entity count: a rank without interfaces must not ask
    if len(facets):
        nodes = dolfinx.mesh.entities_to_geometry(mesh, tdim - 1, facets, False)
    else:
        nodes = np.zeros((0, tdim), dtype=np.int32)
    x = mesh.geometry.x[nodes][..., :gdim]  # (F, nverts, gdim)
    vertex_coords = mesh.geometry.x[nodes]
    midpoints = vertex_coords.mean(axis=1)
    if gdim == 2:
        t = x[:, 1] - x[:, 0]
        areas = np.linalg.norm(t, axis=1)
        normals = np.column_stack([t[:, 1], -t[:, 0]])
    else:
        cr = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        areas = 0.5 * np.linalg.norm(cr, axis=1)
        normals = cr
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    # orient n+ out of the first cell
    cmid = (
        dolfinx.mesh.compute_midpoints(mesh, tdim, cells[:, 0])[:, :gdim]
        if len(facets)
        else np.zeros((0, gdim))
    )
    flip = np.einsum("ij,ij->i", normals, midpoints[:, :gdim] - cmid) < 0.0
    normals[flip] *= -1.0
    hc = mesh.h(tdim, cells.reshape(-1)).reshape(-1, 2) if len(facets) else np.zeros((0, 2))
    inputs = mesh.geometry.input_global_indices
    vertex_ids = np.asarray(inputs)[nodes].astype(np.int64)
    return vertex_coords, midpoints, normals, areas, hc.mean(axis=1), vertex_ids


class FacetFunctions:
    """Per-facet values as Crouzeix-Raviart functions (exact at facet midpoints)."""

    def __init__(self, mesh: dolfinx.mesh.Mesh, facets: InterfaceFacets) -> None:
        self.mesh = mesh
        self.facets = facets
        self._cache: dict[tuple[int, ...], tuple[dolfinx.fem.FunctionSpace, np.ndarray]] = {}

    def dofs(self, shape: tuple[int, ...] = ()) -> np.ndarray:
        """Dofs of the Crouzeix-Raviart space of ``shape`` at this rank's interface facets."""
        return self._space(shape)[1]

    def function(self, values: np.ndarray, shape: tuple[int, ...] = ()) -> dolfinx.fem.Function:
        """Return per-facet ``values`` as a Crouzeix-Raviart function (collective)."""
        f = dolfinx.fem.Function(self._space(shape)[0])
        self.assign(f, values, shape)
        return f

    def assign(
        self, f: dolfinx.fem.Function, values: np.ndarray, shape: tuple[int, ...] = ()
    ) -> None:
        """Set per-facet ``values`` into ``f``, a function of :meth:`function` (collective)."""
        V, dofs = self._space(shape)
        bs = V.dofmap.index_map_bs
        f.x.array.reshape(-1, bs)[dofs] = np.asarray(values).reshape(len(dofs), bs)
        f.x.scatter_forward()

    @property
    def size(self) -> int:
        """Number of this rank's interface facets (the length of per-facet values)."""
        return len(self.facets.facets)

    def _space(self, shape: tuple[int, ...]) -> tuple[dolfinx.fem.FunctionSpace, np.ndarray]:
        if shape not in self._cache:
            V = dolfinx.fem.functionspace(self.mesh, ("CR", 1, shape) if shape else ("CR", 1))
            self._cache[shape] = (V, self._cr_dofs(V))
        return self._cache[shape]

    def _cr_dofs(self, V: dolfinx.fem.FunctionSpace) -> np.ndarray:
        tdim = self.mesh.topology.dim
        c2f = self.mesh.topology.connectivity(tdim, tdim - 1)
        c = self.facets.cells[:, 0]
        local = np.array(
            [
                int(np.flatnonzero(c2f.links(ci) == f)[0])
                for ci, f in zip(c, self.facets.facets, strict=True)
            ]
        )
        return np.array(
            [V.dofmap.cell_dofs(int(ci))[li] for ci, li in zip(c, local, strict=True)],
            dtype=np.int32,
        )


__all__ = ["FacetFunctions", "InterfaceFacets", "ZoneMarker"]
