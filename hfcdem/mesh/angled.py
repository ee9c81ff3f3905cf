"""Gmsh model of an :class:`~hfcdem.config.plates.AngledPathPlate` (plane strain, x-y plane).

A plate centred at the origin with an initial crack along x through the
injection point (split there, so the origin is a vertex), or an open slot
of the crack's length and width (a hole: the cavity), and a straight fracture
path from each crack end (the middle of each slot end) at the path angle.
Crack and paths are internal lines: the triangles on their two sides share
their facets.  With a
corner support, each edge is split a given length from each corner: those
pieces are held fixed (``outer_corners``), the rest is free (``edge_xmin`` ...);
without one every edge is fixed (``outer_xmin`` ...).

Tag names (the API):

=================  =====  ==============================================
name               dim    what
=================  =====  ==============================================
rock               cells  the plate
crack              facet  initial crack (interior facets; no slot)
wellbore_wall      facet  the slot's wall (with a slot)
fracture_path      facet  the two paths (interior facets)
outer_corners      facet  fixed edge pieces at the corners (corner support)
edge_xmin ...      facet  free rest of the edges (corner support)
outer_xmin ...     facet  the edges, fixed (no corner support)
=================  =====  ==============================================
"""

from __future__ import annotations

from typing import Any

import gmsh
import numpy as np

from hfcdem.config.plates import AngledPathPlate
from hfcdem.mesh.block import element_quality
from hfcdem.mesh.grading import add_grading, use_gradings


def _segments(geom: AngledPathPlate) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    """Return the internal lines as (start, end) points: crack halves and the two paths."""
    paths = []
    for side in (-1, 1):
        start, d = geom.wing(side)
        paths.append((start, start + geom.path_length * d))
    if geom.slot_width > 0.0:
        return {"fracture_path": paths}
    half = 0.5 * geom.crack.length
    origin = np.zeros(2)
    crack = [(np.array([-half, 0.0]), origin), (origin, np.array([half, 0.0]))]
    return {"crack": crack, "fracture_path": paths}


def _slot(geom: AngledPathPlate) -> list[np.ndarray]:
    """Return the slot's corners, counter-clockwise, its ends split where the paths start."""
    a, b = 0.5 * geom.crack.length, 0.5 * geom.slot_width
    return [np.array(v) for v in ((-a, -b), (a, -b), (a, 0.0), (a, b), (-a, b), (-a, 0.0))]


def _slot_pieces(geom: AngledPathPlate) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    if geom.slot_width == 0.0:
        return {}
    loop = _slot(geom)
    return {"wellbore_wall": [(p, loop[(k + 1) % len(loop)]) for k, p in enumerate(loop)]}


def _edge_pieces(geom: AngledPathPlate) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    """Return the plate's edges, split at the corner supports, by tag name."""
    hx, hy = float(geom.plate.half[0]), float(geom.plate.half[1])
    c = geom.corner_support
    edges = {
        "xmin": (np.array([-hx, -hy]), np.array([-hx, hy])),
        "xmax": (np.array([hx, -hy]), np.array([hx, hy])),
        "ymin": (np.array([-hx, -hy]), np.array([hx, -hy])),
        "ymax": (np.array([-hx, hy]), np.array([hx, hy])),
    }
    out: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for name, (a, b) in edges.items():
        if c == 0.0:
            out[f"outer_{name}"] = [(a, b)]
            continue
        t = (b - a) / np.linalg.norm(b - a)
        out.setdefault("outer_corners", []).extend([(a, a + c * t), (b - c * t, b)])
        out[f"edge_{name}"] = [(a + c * t, b - c * t)]
    return out


def _distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of points ``p`` (N x 2) from the segment a-b."""
    ab = b - a
    s = np.clip(((p - a) @ ab) / float(ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + s[:, None] * ab), axis=1)


def _classify(geom: AngledPathPlate, model: Any) -> dict[str, list[int]]:
    """Sort the model's curves into the named facet groups."""
    named = _segments(geom) | _edge_pieces(geom) | _slot_pieces(geom)
    tol = 1e-6 * float(max(geom.plate.width, geom.plate.height))
    groups: dict[str, list[int]] = {}
    for _, curve in model.getEntities(1):
        lo, hi = model.getParametrizationBounds(1, curve)
        params = lo[0] + (np.arange(7) + 0.5) / 7 * (hi[0] - lo[0])
        pts = np.asarray([model.getValue(1, curve, [u]) for u in params])[:, :2]
        found = [
            name
            for name, pieces in named.items()
            if np.all(np.min([_distance(pts, a, b) for a, b in pieces], axis=0) <= tol)
        ]
        if len(found) != 1:
            raise RuntimeError(f"cannot tell which line curve {curve} is (matches {found})")
        groups.setdefault(found[0], []).append(curve)
    return groups


def build_angled_plate(geom: AngledPathPlate, model: Any) -> dict[str, Any]:
    """Create the geometry, physical groups and 2D mesh of ``geom`` in the Gmsh ``model``."""
    gmsh.option.setNumber("General.NumThreads", 1)
    occ = model.occ
    pieces = [p for group in _edge_pieces(geom).values() for p in group]
    # the boundary as a loop of its pieces, counter-clockwise from (-hx, -hy)
    hx, hy = float(geom.plate.half[0]), float(geom.plate.half[1])
    corners = [np.array(v) for v in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]
    stops: list[np.ndarray] = []
    for k, a in enumerate(corners):
        b = corners[(k + 1) % 4]
        inner = sorted(
            {float(np.linalg.norm(q - a)) for piece in pieces for q in piece if _on(q, a, b)}
        )
        t = (b - a) / np.linalg.norm(b - a)
        stops += [a + s * t for s in inner if 0.0 <= s < np.linalg.norm(b - a) - 1e-12]
    points = [occ.addPoint(float(p[0]), float(p[1]), 0.0) for p in stops]
    lines = [occ.addLine(points[k], points[(k + 1) % len(points)]) for k in range(len(points))]
    loops = [occ.addCurveLoop(lines)]
    if geom.slot_width > 0.0:
        corner = [occ.addPoint(float(p[0]), float(p[1]), 0.0) for p in _slot(geom)]
        sides = [occ.addLine(corner[k], corner[(k + 1) % 6]) for k in range(6)]
        loops.append(occ.addCurveLoop(sides))
    surface = occ.addPlaneSurface(loops)
    tools = []
    for segs in _segments(geom).values():
        for a, b in segs:
            p0 = occ.addPoint(float(a[0]), float(a[1]), 0.0)
            p1 = occ.addPoint(float(b[0]), float(b[1]), 0.0)
            tools.append((1, occ.addLine(p0, p1)))
    occ.fragment([(2, surface)], tools)
    occ.synchronize()
    groups = _classify(geom, model)
    model.addPhysicalGroup(2, [t for _, t in model.getEntities(2)], name="rock")
    for name in sorted(groups):
        model.addPhysicalGroup(1, sorted(groups[name]), name=name)
    step = geom.path_start
    refined = groups.get("crack", []) + groups["fracture_path"]
    for curve in refined:
        x0, y0, _, x1, y1, _ = model.getBoundingBox(1, curve)
        length = float(np.hypot(x1 - x0, y1 - y0))
        model.mesh.setTransfiniteCurve(curve, max(1, round(length / step)) + 1)
    sizing = geom.mesh
    dist_max = max(sizing.growth_distance(step), 1e-9)
    sampling = int(np.clip(np.ceil(4.0 * max(hx, hy) / step), 50, 2000))
    refined += groups.get("wellbore_wall", [])
    grading = add_grading(model, 1, refined, step, sizing.size_far, dist_max, sampling)
    use_gradings(model, [grading], sizing.size_far)
    model.mesh.generate(2)
    return {
        "quality": element_quality(model, 2),
        "faces": {name: len(v) for name, v in sorted(groups.items())},
    }


def _on(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether point ``q`` lies on the segment a-b."""
    return bool(_distance(q[None, :], a, b)[0] <= 1e-12 * max(1.0, float(np.abs(b - a).max())))


def angled_residuals(geom: AngledPathPlate) -> list[tuple[str, Any]]:
    """(name, residual) per facet group: a point's distance from the group's lines."""
    named = _segments(geom) | _edge_pieces(geom) | _slot_pieces(geom)

    def residual(pieces: list[tuple[np.ndarray, np.ndarray]]) -> Any:
        def distance(p: np.ndarray) -> np.ndarray:
            return np.min([_distance(p[:, :2], a, b) for a, b in pieces], axis=0)

        return distance

    return [(name, residual(pieces)) for name, pieces in named.items()]


def angled_measures(geom: AngledPathPlate) -> dict[str, Any]:
    """Analytic area and line lengths of ``geom`` (for the mesh report)."""
    named = _segments(geom) | _edge_pieces(geom) | _slot_pieces(geom)
    lengths = {
        name: float(sum(np.linalg.norm(b - a) for a, b in segs)) for name, segs in named.items()
    }
    slot = geom.crack.length * geom.slot_width
    area = float(geom.plate.width * geom.plate.height) - slot
    return {"volume": area, "cavity": slot, "areas": lengths}


__all__ = ["angled_measures", "angled_residuals", "build_angled_plate"]
