"""Gmsh models of 2D plates (plane strain, x-y plane) for the verification scenes.

* :class:`~hfcdem.config.plates.CrackPlate`: a plate with a central pre-existing crack
  along x (seed cdem-perforation-breakdown Table 1: 1 m square, 0.2 m crack).
  The crack is an internal line of the mesh: the triangles on its two sides
  share its facets (nothing is duplicated); the CDEM solid treats them as a
  pre-existing crack through interior-facet integrals ``dS(crack)``.
* :class:`~hfcdem.config.plates.KGDStrip`: a plate with an initial crack (``crack``)
  and, beyond it, the line the fracture is expected to follow
  (``fracture_path``), both internal lines; the injection point, the origin,
  is a mesh vertex.
* :class:`~hfcdem.config.plates.BoreholeSquare`: a square with a borehole at its
  centre (seed pfc2d sec. 3.2: 1000 mm square, 60 mm borehole).

Tag names (the API):

=================  =====  ==============================================
name               dim    what
=================  =====  ==============================================
rock               cells  rock outside the fracturable zone (all if none)
fracturable        cells  rock inside the fracturable zone, if given
crack              facet  pre-existing crack (interior facets)
fracture_path      facet  KGD: expected path beyond the crack (interior)
wellbore_wall      facet  borehole wall
outer_xmin ...     facet  plate edges (outer_xmin/xmax/ymin/ymax)
symmetry_x, _y     facet  mirror lines x = 0, y = 0 (the model keeps >= 0)
=================  =====  ==============================================
"""

from __future__ import annotations

from typing import Any

import gmsh
import numpy as np

from hfcdem.config.parts import SlabZone, SphereZone
from hfcdem.config.plates import AngledPathPlate, BoreholeSquare, CrackPlate, KGDStrip
from hfcdem.mesh.angled import angled_measures, angled_residuals, build_angled_plate
from hfcdem.mesh.block import element_quality
from hfcdem.mesh.frames import Residual, kept_corners, plane_residual, slab_box
from hfcdem.mesh.grading import add_grading, use_gradings

Plate2D = CrackPlate | KGDStrip | BoreholeSquare | AngledPathPlate


def _crack_lines(geom: Plate2D) -> dict[str, list[tuple[float, float]]]:
    """x-intervals on y = 0 of the crack and fracture-path lines (kept part)."""
    if isinstance(geom, BoreholeSquare):
        return {}
    half = 0.5 * geom.crack.length
    lo_x = 0.0 if "x" in geom.symmetry else -half
    # split at the origin so that it is a vertex (the KGD injection point)
    crack = [(lo_x, 0.0), (0.0, half)] if lo_x < 0.0 else [(0.0, half)]
    lines = {"crack": crack}
    if isinstance(geom, KGDStrip):
        path = 0.5 * (geom.crack.path_length or geom.crack.length)
        if path > half:
            lines["fracture_path"] = [(half, path)] + ([] if lo_x == 0.0 else [(-path, -half)])
    return lines


def expected_measures(geom: Plate2D) -> dict[str, Any]:
    """Analytic area and line lengths of the modelled part of ``geom``."""
    if isinstance(geom, AngledPathPlate):
        return angled_measures(geom)
    lo, hi = kept_corners(geom.plate.half[:2], geom.symmetry)
    ext = hi - lo
    lengths: dict[str, float] = {}
    hole = 0.0
    share = 0.5 ** len(geom.symmetry)
    if isinstance(geom, BoreholeSquare):
        big_r = geom.wellbore.radius
        hole = np.pi * big_r**2 * share
        lengths["wellbore_wall"] = 2.0 * np.pi * big_r * share
    for name, pieces in _crack_lines(geom).items():
        lengths[name] = float(sum(b - a for a, b in pieces))
    for i, axis in enumerate("xy"):
        other = float(ext[1 - i])
        lengths[f"outer_{axis}max"] = other
        if axis in geom.symmetry:
            cut = 0.0
            if isinstance(geom, BoreholeSquare):
                cut = geom.wellbore.radius * (1.0 if "xy"[1 - i] in geom.symmetry else 2.0)
            lengths[f"symmetry_{axis}"] = other - cut
        else:
            lengths[f"outer_{axis}min"] = other
    return {"volume": float(np.prod(ext)) - hole, "cavity": hole, "areas": lengths}


def _add_zone(occ: Any, geom: Plate2D) -> tuple[int, int] | None:
    zone = geom.fracturable
    if zone is None:
        return None
    if isinstance(zone, SphereZone):
        return (2, occ.addDisk(zone.centre[0], zone.centre[1], 0.0, zone.radius, zone.radius))
    assert isinstance(zone, SlabZone)
    corner, size = slab_box(zone, geom.plate.half[:2])
    return (2, occ.addRectangle(corner[0], corner[1], 0.0, size[0], size[1]))


def curve_candidates(geom: Plate2D) -> list[tuple[str, Residual]]:
    if isinstance(geom, AngledPathPlate):
        return angled_residuals(geom)
    lo, hi = kept_corners(geom.plate.half[:2], geom.symmetry)
    out: list[tuple[str, Residual]] = []
    for i, axis in enumerate("xy"):
        out.append((f"outer_{axis}max", plane_residual(i, float(hi[i]))))
        name = f"symmetry_{axis}" if axis in geom.symmetry else f"outer_{axis}min"
        out.append((name, plane_residual(i, float(lo[i]))))
    if isinstance(geom, BoreholeSquare):
        big_r = geom.wellbore.radius
        out.append(("wellbore_wall", lambda p: np.abs(np.linalg.norm(p[:, :2], axis=1) - big_r)))
    for name, pieces in _crack_lines(geom).items():

        def on_line(p: np.ndarray, pieces: list[tuple[float, float]] = pieces) -> np.ndarray:
            inside = np.zeros(len(p), dtype=bool)
            for a, b in pieces:
                inside |= (p[:, 0] >= a - 1e-9) & (p[:, 0] <= b + 1e-9)
            return np.where(inside, np.abs(p[:, 1]), np.inf)

        out.append((name, on_line))
    return out


def _sample_curve(model: Any, tag: int) -> np.ndarray:
    lo, hi = model.getParametrizationBounds(1, tag)
    params = lo[0] + (np.arange(7) + 0.5) / 7 * (hi[0] - lo[0])
    return np.asarray([model.getValue(1, tag, [u]) for u in params])


def _ring_sectors(occ: Any, geom: BoreholeSquare) -> None:
    """Quarter-annulus surfaces between the wall and the ring radius, in the kept part.

    Each spans 90 degrees between the axes, so its radial edges lie on the axes
    and on the symmetry lines.
    """
    a, b = geom.wellbore.radius, geom.ring_radius
    lo, _ = kept_corners(geom.plate.half[:2], geom.symmetry)
    quarters = [k for k in range(4) if _quarter_kept(k, lo)]
    angles = sorted({q * 0.5 * np.pi for k in quarters for q in (k, (k + 1) % 4)})
    centre = occ.addPoint(0.0, 0.0, 0.0)
    inner = {t: occ.addPoint(a * np.cos(t), a * np.sin(t), 0.0) for t in angles}
    outer = {t: occ.addPoint(b * np.cos(t), b * np.sin(t), 0.0) for t in angles}
    radial = {t: occ.addLine(inner[t], outer[t]) for t in angles}
    for k in quarters:
        t0, t1 = k * 0.5 * np.pi, ((k + 1) % 4) * 0.5 * np.pi
        arc_in = occ.addCircleArc(inner[t0], centre, inner[t1])
        arc_out = occ.addCircleArc(outer[t0], centre, outer[t1])
        loop = occ.addCurveLoop([radial[t0], arc_out, -radial[t1], -arc_in])
        occ.addPlaneSurface([loop])


def _quarter_kept(k: int, lo: np.ndarray) -> bool:
    """Whether quadrant ``k`` (0: x, y > 0; counter-clockwise) lies in the kept part."""
    sx, sy = (1, 1) if k == 0 else (-1, 1) if k == 1 else (-1, -1) if k == 2 else (1, -1)
    return (sx > 0 or lo[0] < 0.0) and (sy > 0 or lo[1] < 0.0)


def _structure_rings(model: Any, geom: BoreholeSquare, tol: float) -> None:
    """Transfinite ring sectors: arcs divided evenly, radial edges into ``wall_rings``."""
    a, b = geom.wellbore.radius, geom.ring_radius
    arcs = max(2, int(np.ceil(0.5 * np.pi * a / geom.wall_size)))  # per 90 degrees

    def inside(dim: int, tag: int) -> bool:
        x0, y0, _, x1, y1, _ = model.getBoundingBox(dim, tag)
        return max(abs(x0), abs(x1), abs(y0), abs(y1)) <= b + tol

    for _, curve in model.getEntities(1):
        if inside(1, curve):
            circle = model.getType(1, curve) in ("Circle", "Ellipse")
            count = arcs if circle else geom.mesh.wall_rings
            model.mesh.setTransfiniteCurve(curve, count + 1)
    for _, surf in model.getEntities(2):
        if inside(2, surf):
            model.mesh.setTransfiniteSurface(surf)


def _exact_path(model: Any, geom: KGDStrip, groups: dict[str, list[int]]) -> None:
    """Split the crack and path curves into facets of exactly ``mesh.path_size``."""
    step = geom.mesh.path_size
    assert step is not None
    for name in ("crack", "fracture_path"):
        for curve in groups.get(name, []):
            x0, _, _, x1, _, _ = model.getBoundingBox(1, curve)
            model.mesh.setTransfiniteCurve(curve, round((x1 - x0) / step) + 1)


def _plate_entities(geom: Plate2D, occ: Any) -> dict[str, list[int]]:
    """Create the plate's surfaces and lines in Gmsh; return the cell groups' surfaces."""
    lo, hi = kept_corners(geom.plate.half[:2], geom.symmetry)
    plate = [(2, occ.addRectangle(lo[0], lo[1], 0.0, *(hi - lo)))]
    if isinstance(geom, BoreholeSquare):
        hole = geom.ring_radius
        plate, _ = occ.cut(plate, [(2, occ.addDisk(0.0, 0.0, 0.0, hole, hole))])
        if geom.mesh.wall_rings:
            _ring_sectors(occ, geom)
            occ.removeAllDuplicates()
            return {"rock": []}  # every surface, once synchronised
    tools = []
    for pieces in _crack_lines(geom).values():
        for a, b in pieces:
            p0, p1 = occ.addPoint(a, 0.0, 0.0), occ.addPoint(b, 0.0, 0.0)
            tools.append((1, occ.addLine(p0, p1)))
    zone = _add_zone(occ, geom)
    cells = {"rock": [t for _, t in plate]}
    if tools or zone is not None:
        _, children = occ.fragment(plate, tools + ([zone] if zone is not None else []))
        of_plate = {t for c in children[: len(plate)] for d, t in c if d == 2}
        if zone is not None:
            of_zone = {t for d, t in children[-1] if d == 2}
            occ.remove([(2, t) for t in sorted(of_zone - of_plate)], recursive=True)
            cells = {"rock": sorted(of_plate - of_zone), "fracturable": sorted(of_plate & of_zone)}
            if not cells["fracturable"]:
                raise RuntimeError("the fracturable zone does not meet the plate")
        else:
            cells = {"rock": sorted(of_plate)}
    return cells


def _name_curves(geom: Plate2D, model: Any) -> dict[str, list[int]]:
    """Sort the model's curves into the named facet groups (inner curves stay unnamed)."""
    candidates = curve_candidates(geom)
    tol = 1e-6 * float(max(geom.plate.width, geom.plate.height))
    groups: dict[str, list[int]] = {}
    for _, curve in model.getEntities(1):
        pts = _sample_curve(model, curve)
        worst = [float(np.max(res(pts))) for _, res in candidates]
        best = int(np.argmin(worst))
        if worst[best] <= tol:
            groups.setdefault(candidates[best][0], []).append(curve)
        elif len(model.getAdjacencies(1, curve)[0]) < 2:
            raise RuntimeError(f"cannot tell which edge curve {curve} is")
        # else: a curve inside the plate (zone edge, ring edge)
    return groups


def build_plate(geom: Plate2D, model: Any) -> dict[str, Any]:
    """Create the geometry, physical groups and 2D mesh of ``geom`` in the Gmsh ``model``."""
    if isinstance(geom, AngledPathPlate):
        return build_angled_plate(geom, model)
    gmsh.option.setNumber("General.NumThreads", 1)
    cells = _plate_entities(geom, model.occ)
    model.occ.synchronize()
    if not cells["rock"]:
        cells["rock"] = [t for _, t in model.getEntities(2)]
    groups = _name_curves(geom, model)
    for name, tags in cells.items():
        if tags:
            model.addPhysicalGroup(2, tags, name=name)
    for name in sorted(groups):
        model.addPhysicalGroup(1, sorted(groups[name]), name=name)

    flat = 0.0
    if isinstance(geom, BoreholeSquare):
        start = geom.wall_size
        if geom.mesh.wall_rings:
            flat = geom.ring_radius - geom.wellbore.radius
            # OCC pads bounding boxes by about 1e-7
            _structure_rings(model, geom, max(1e-6 * float(geom.plate.half[0]), 1e-6))
    else:
        start = geom.path_start if isinstance(geom, KGDStrip) else geom.mesh.size
        if isinstance(geom, KGDStrip) and geom.mesh.path_size is not None:
            _exact_path(model, geom, groups)
    _grade(model, geom, groups, start, flat)
    model.mesh.generate(2)
    return {
        "quality": element_quality(model, 2),
        "faces": {name: len(v) for name, v in sorted(groups.items())},
    }


def _grade(
    model: Any, geom: Plate2D, groups: dict[str, list[int]], start: float, flat: float
) -> None:
    """Size ``start`` within ``flat`` of the crack, path or wall, growing to ``size_far``."""
    refined = [c for n in ("crack", "fracture_path", "wellbore_wall") for c in groups.get(n, [])]
    sizing = geom.mesh
    dist_max = flat + max(sizing.growth_distance(start), 1e-9)
    if sizing.size_integration == "exact":
        grading = add_grading(model, 1, refined, start, sizing.size_far, dist_max, 400)
        use_gradings(model, [grading])
        return
    lo, hi = kept_corners(geom.plate.half[:2], geom.symmetry)
    sampling = int(np.clip(np.ceil(2.0 * float(max(hi - lo)) / start), 50, 2000))
    grading = add_grading(model, 1, refined, start, sizing.size_far, dist_max, sampling)
    use_gradings(model, [grading], sizing.size_far)


__all__ = [
    "Plate2D",
    "build_plate",
    "expected_measures",
]
