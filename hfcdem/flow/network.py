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

    def index(self) -> dict[tuple[int, ...], int]:
        """Map from a facet key (sorted vertex ids) to its position."""
        return {tuple(int(v) for v in k): i for i, k in enumerate(self.keys)}

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
    e_star: list[int], e_fac: list[int], star_cavity: list[bool], num_facets: int
) -> tuple[list[int], list[int], list[int], np.ndarray]:
    """Connect the entries of each star (a shared vertex or edge) to each other.

    A star on the cavity wall joins each entry to the cavity; any other joins
    every pair of its entries (a junction as a zero-volume node).
    """
    members: list[list[int]] = [[] for _ in star_cavity]
    for e, s in enumerate(e_star):
        members[s].append(e)
    pa, pb, ps = [], [], []
    touches = np.zeros(num_facets, dtype=bool)
    for s, mem in enumerate(members):
        if star_cavity[s]:
            for e in mem:
                pa.append(e)
                pb.append(CAVITY)
                ps.append(s)
                touches[e_fac[e]] = True
        else:
            for i in range(len(mem)):
                for j in range(i + 1, len(mem)):
                    pa.append(mem[i])
                    pb.append(mem[j])
                    ps.append(s)
    return pa, pb, ps, touches


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

    cav = set(int(v) for v in np.unique(gather_rows(comm, np.asarray(cavity_vertices, np.int64))))
    stars: dict[tuple[int, ...], int] = {}
    star_point: list[np.ndarray] = []
    star_cross: list[float] = []
    star_cavity: list[bool] = []
    e_fac, e_star, e_geom = [], [], []
    local_pairs: list[tuple[int, ...]] = [(0,), (1,)] if nv == 2 else [(0, 1), (1, 2), (0, 2)]
    centroid = all_x.mean(axis=1) if len(all_x) else np.zeros((0, 3))
    for f in range(len(all_keys)):
        for loc in local_pairs:
            key = tuple(int(all_keys[f, i]) for i in loc)
            s = stars.get(key)
            if s is None:
                s = stars[key] = len(star_point)
                pts = all_x[f, list(loc)]
                star_point.append(pts.mean(axis=0))
                star_cross.append(1.0 if nv == 2 else float(np.linalg.norm(pts[1] - pts[0])))
                star_cavity.append(all(k in cav for k in key))
            dist = max(float(np.linalg.norm(centroid[f] - star_point[s])), 1e-300)
            e_fac.append(f)
            e_star.append(s)
            e_geom.append(star_cross[s] / dist)
    entry_facet = np.asarray(e_fac, dtype=np.int64)
    entry_star = np.asarray(e_star, dtype=np.int64)
    pa, pb, ps, touches = _pairs(e_star, e_fac, star_cavity, len(all_keys))
    net = Network(
        keys=all_keys,
        area=all_area,
        centroid=centroid,
        pair_a=np.asarray(pa, dtype=np.int64),
        pair_b=np.asarray(pb, dtype=np.int64),
        pair_star=np.asarray(ps, dtype=np.int64),
        entry_facet=entry_facet,
        entry_star=entry_star,
        entry_geometry=np.asarray(e_geom, dtype=float),
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
