"""The fracture network as the fluid sees it: facets, their neighbours and the cavity.

Every broken or pre-existing interface facet is a fluid cell (cell-centred
finite volumes on the fracture surface).  Facets meet at *stars*: a vertex in 2D,
an edge in 3D.  Fluid passes between the members of a star through two-point
half-transmissibilities ``t = k c / d`` (``k = a^3 / 12 mu``, ``c`` the star's
cross-length, ``d`` the distance from the facet centroid to the star point).
A star of three or more facets is a junction: it is eliminated as a node of zero
volume, which connects every pair of members with ``t_i t_j / sum t`` (exact
for a zero-storage junction; two members give the harmonic mean).  A star on
the cavity wall (or at the injection point) connects each member to the cavity
with its own ``t``.

The network is small (fracture facets, not the mesh), so it is gathered on every
rank and ordered by global vertex ids: every rank holds the same arrays, in the
same order, whatever the number of ranks.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

CAVITY = -1  # the cavity's index in pair arrays


@dataclass(frozen=True)
class Network:
    """Fracture facets in a rank-independent order, with their star connections."""

    keys: np.ndarray  # (n, nv) sorted global vertex ids of each facet
    area: np.ndarray  # (n,) m^2 (m per metre in 2D)
    centroid: np.ndarray  # (n, 3)
    pair_a: np.ndarray  # (P,) first entry of each connection
    pair_b: np.ndarray  # (P,) second entry, or CAVITY
    pair_star: np.ndarray  # (P,) star of the connection
    entry_facet: np.ndarray  # (E,) facet of each (star, member) entry
    entry_star: np.ndarray  # (E,) star of each entry
    entry_geometry: np.ndarray  # (E,) cross-length / distance of each entry
    num_stars: int
    touches_cavity: np.ndarray  # (n,) facet connects to the cavity directly

    @property
    def pair_facets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Facets at the two ends of every connection: (first, second or 0, second is a facet).

        Cached: the flow residual asks for it at every Newton evaluation.
        """
        cached = self.__dict__.get("_pair_facets")
        if cached is None:
            inner = self.pair_b != CAVITY
            fa = self.entry_facet[self.pair_a]
            fb = np.where(inner, self.entry_facet[np.where(inner, self.pair_b, 0)], 0)
            cached = (fa, fb, inner)
            object.__setattr__(self, "_pair_facets", cached)
        return cached

    @property
    def size(self) -> int:
        """Number of fracture facets."""
        return len(self.area)

    def positions(self, keys: np.ndarray) -> np.ndarray:
        """Position of each row of ``keys`` (global vertex ids, any order) here; -1 if absent."""
        nv = self.keys.shape[1]
        rows = np.sort(np.asarray(keys, dtype=np.int64).reshape(-1, nv), axis=1)
        if not len(rows) or not self.size:
            return np.full(len(rows), -1, dtype=np.int64)
        radix = int(max(self.keys.max(), rows.max())) + 1
        if radix**nv >= 2**63:  # ids too large for one integer per key
            _, label = np.unique(np.vstack([self.keys, rows]), axis=0, return_inverse=True)
            label = label.reshape(-1)
            at = np.full(int(label.max()) + 1, -1, dtype=np.int64)
            at[label[: self.size]] = np.arange(self.size)
            return at[label[self.size :]]
        # the keys as mixed-radix integers: sorted here, since the keys are in lexicographic order
        weights = radix ** np.arange(nv - 1, -1, -1, dtype=np.int64)
        mine, asked = self.keys @ weights, rows @ weights
        found = np.minimum(np.searchsorted(mine, asked), self.size - 1)
        return np.where(mine[found] == asked, found, -1)

    def transmissibility(
        self, aperture: np.ndarray, conductivity: Callable[[np.ndarray], np.ndarray]
    ) -> np.ndarray:
        """Pair transmissibilities for per-facet apertures (n,) or (n, k).

        A star's conductivity uses the mean aperture of its members (the
        aperture at the shared vertex or edge), so a closing tip facet still
        passes fluid; members differ only by their distance to the star.
        """
        ap = aperture[self.entry_facet]
        total = np.zeros((self.num_stars, *ap.shape[1:]))
        np.add.at(total, self.entry_star, ap)
        count = np.bincount(self.entry_star, minlength=self.num_stars).astype(float)
        star_k = conductivity(total / _expand(np.maximum(count, 1.0), total))
        t = star_k[self.entry_star] * _expand(self.entry_geometry, ap)
        tsum = np.zeros_like(total)
        np.add.at(tsum, self.entry_star, t)
        ta = t[self.pair_a]
        inner = self.pair_b != CAVITY
        out = ta.copy()
        tb = t[self.pair_b[inner]]
        denom = tsum[self.pair_star[inner]]
        with np.errstate(divide="ignore", invalid="ignore"):
            out[inner] = np.where(denom > 0.0, ta[inner] * tb / np.where(denom > 0, denom, 1), 0.0)
        return out

    def components(self) -> np.ndarray:
        """Return the connected component of every facet (0: joined to the cavity)."""
        n = self.size
        parent = np.arange(n + 1)  # n is the cavity

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for a, b in zip(self.entry_facet[self.pair_a], self.pair_b, strict=True):
            other = n if b == CAVITY else int(self.entry_facet[b])
            ra, rb = find(int(a)), find(other)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
        roots = np.array([find(i) for i in range(n + 1)])
        cavity_root = roots[n]
        comp = np.where(roots[:n] == cavity_root, 0, roots[:n] + 1)
        return comp


def _expand(values: np.ndarray, like: np.ndarray) -> np.ndarray:
    return values.reshape(values.shape + (1,) * (like.ndim - 1))


def gather_rows(comm: MPI.Comm, rows: np.ndarray) -> np.ndarray:
    """Concatenate every rank's rows (same trailing shape) on every rank."""
    parts = comm.allgather(np.ascontiguousarray(rows))
    return np.concatenate(parts, axis=0)


def _pairs(
    e_star: np.ndarray, e_fac: np.ndarray, star_cavity: np.ndarray, num_facets: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Connect the entries of each star (a shared vertex or edge) to each other.

    A star on the cavity wall joins each entry to the cavity; any other joins
    every pair of its entries (a junction as a zero-volume node).  Pairs come
    star by star, and within a star in the order of their entries.
    """
    touches = np.zeros(num_facets, dtype=bool)
    on_wall = star_cavity[e_star]
    touches[e_fac[on_wall]] = True
    wall = np.flatnonzero(on_wall)
    pa, pb, ps = [wall], [np.full(len(wall), CAVITY, dtype=np.int64)], [e_star[wall]]
    # the entries grouped by star, each group in entry order
    order = np.argsort(e_star, kind="stable")
    count = np.bincount(e_star, minlength=len(star_cavity))
    start = np.cumsum(count) - count
    for m in np.unique(count[~star_cavity]):
        if m < 2:
            continue
        stars = np.flatnonzero((count == m) & ~star_cavity)
        members = order[start[stars][:, None] + np.arange(m)]
        i, j = np.triu_indices(int(m), 1)
        pa.append(members[:, i].reshape(-1))
        pb.append(members[:, j].reshape(-1))
        ps.append(np.repeat(stars, len(i)))
    a, b, s = (np.concatenate(x).astype(np.int64) for x in (pa, pb, ps))
    sort = np.lexsort((b, a, s))
    return a[sort], b[sort], s[sort], touches


def _stars(
    all_keys: np.ndarray, all_x: np.ndarray, cavity: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Give the stars (a facet's vertices in 2D, its edges in 3D) numbers as facets meet them.

    Returns each entry's facet and star (entries facet by facet, a facet's
    stars in a fixed local order), each star's point (its vertex or its edge's
    midpoint), cross-length (1 in 2D, the edge's length in 3D) and whether it
    lies on the cavity wall (every vertex of it there).
    """
    n, nv = all_keys.shape
    local = np.array([[0], [1]]) if nv == 2 else np.array([[0, 1], [1, 2], [0, 2]])
    width = local.shape[1]
    star_keys = all_keys[:, local].reshape(-1, width)
    points = all_x[:, local].reshape(-1, width, 3)
    e_fac = np.repeat(np.arange(n, dtype=np.int64), len(local))
    if not n:
        empty = np.zeros(0)
        return e_fac, e_fac.copy(), np.zeros((0, 3)), empty, empty.astype(bool)
    _, first, label = np.unique(star_keys, axis=0, return_index=True, return_inverse=True)
    met = np.argsort(first)  # the stars in the order the entries first meet them
    number = np.empty(len(met), dtype=np.int64)
    number[met] = np.arange(len(met))
    e_star = number[label.reshape(-1)]
    first_entry = first[met]
    ends = points[first_entry]
    star_point = ends.mean(axis=1)
    if nv == 2:
        cross = np.ones(len(met))
    else:
        cross = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    on_wall = np.asarray(np.isin(star_keys[first_entry], cavity).all(axis=1), dtype=bool)
    return e_fac, e_star, star_point, np.asarray(cross, dtype=float), on_wall


def build_network(
    comm: MPI.Comm,
    keys: np.ndarray,
    area: np.ndarray,
    vertex_coords: np.ndarray,
    cavity_vertices: np.ndarray,
) -> tuple[Network, np.ndarray]:
    """Gather the owned fracture facets of every rank into one ordered :class:`Network`.

    ``keys`` (F, nv) global vertex ids, ``area`` (F,), ``vertex_coords`` (F, nv, 3)
    of this rank's owned fracture facets; ``cavity_vertices`` the global ids of
    the vertices on the cavity wall or at the injection point (any rank).
    Returns the network and, for this rank's facets, their positions in it.
    """
    nv = keys.shape[1]
    skeys = np.sort(keys, axis=1).astype(np.int64)
    all_keys = gather_rows(comm, skeys.reshape(-1, nv))
    all_area = gather_rows(comm, np.asarray(area, dtype=float))
    all_x = gather_rows(comm, np.asarray(vertex_coords, dtype=float).reshape(-1, nv, 3))
    # vertex coordinates in the same (sorted id) order as the keys
    order_in_facet = np.argsort(gather_rows(comm, keys.astype(np.int64).reshape(-1, nv)), axis=1)
    all_x = np.take_along_axis(all_x, order_in_facet[:, :, None], axis=1)
    order = np.lexsort(all_keys.T[::-1]) if len(all_keys) else np.zeros(0, dtype=np.int64)
    all_keys, all_area, all_x = all_keys[order], all_area[order], all_x[order]
    # position of this rank's facets
    counts = comm.allgather(len(skeys))
    offset = sum(counts[: comm.rank])
    inverse = np.empty(len(order), dtype=np.int64)
    inverse[order] = np.arange(len(order))
    mine = inverse[offset : offset + len(skeys)]

    cavity = np.unique(gather_rows(comm, np.asarray(cavity_vertices, np.int64)))
    centroid = all_x.mean(axis=1) if len(all_x) else np.zeros((0, 3))
    e_fac, e_star, star_point, star_cross, star_cavity = _stars(all_keys, all_x, cavity)
    dist = np.maximum(np.linalg.norm(centroid[e_fac] - star_point[e_star], axis=1), 1e-300)
    pa, pb, ps, touches = _pairs(e_star, e_fac, star_cavity, len(all_keys))
    net = Network(
        keys=all_keys,
        area=all_area,
        centroid=centroid,
        pair_a=pa,
        pair_b=pb,
        pair_star=ps,
        entry_facet=e_fac,
        entry_star=e_star,
        entry_geometry=star_cross[e_star] / dist,
        num_stars=len(star_point),
        touches_cavity=touches,
    )
    return net, mine


__all__ = [
    "CAVITY",
    "Network",
    "build_network",
    "gather_rows",
]
