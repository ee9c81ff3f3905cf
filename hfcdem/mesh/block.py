"""Gmsh models of perforated rock blocks: a wellbore and lofted tunnels cut from a block.

Each tunnel is lofted (OCC ``addThruSections``, ruled) through circles at its
stations, so it is a stack of conical frustums.  It starts a little inside the
wellbore, on the backward extension of its first segment
(:func:`hfcdem.config.parts.tunnel_extension`), so the boolean cut is robust; the
part of the tunnel outside the wellbore is then the frustum stack plus a thin
*sliver* between the curved wellbore wall and the plane of station 0.  The
analytic references here (:func:`expected_measures`) include the sliver and
also report the plain frustum values.

Tag names (the API; integer values are not):

=====================  =====  ===================================================
name                   dim    what
=====================  =====  ===================================================
rock                   cells  rock outside the fracturable zone (all rock if none)
fracturable            cells  rock inside the fracturable zone, if one is given;
                              every cell carries exactly one of the two tags
wellbore_wall          facet  the wellbore's wall
perforation_K_wall     facet  lateral wall of perforation K (K from 1, scene order)
perforation_K_tip      facet  flat end face of perforation K
outer_xmin ... zmax    facet  faces of the block
symmetry_x, _y, _z     facet  mirror planes x = 0, ... (half or quarter models)
=====================  =====  ===================================================

Perforations that a symmetry plane drops (their mirror image is kept) have no
tags; the others keep their scene numbers.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gmsh
import numpy as np

from hfcdem.config.geometry import PerforatedBlock
from hfcdem.config.parts import (
    AXES,
    Profile,
    SlabZone,
    SphereZone,
    TunnelZone,
    axis_index,
    axis_vector,
    tunnel_extension,
)
from hfcdem.mesh.frames import (
    Residual,
    TunnelFrame,
    kept_corners,
    plane_residual,
    slab_box,
    tunnel_frame,
)
from hfcdem.mesh.grading import add_grading, use_gradings

# ---------------------------------------------------------------------------
# Analytic measures
# ---------------------------------------------------------------------------


def _integrate(f: Callable[[np.ndarray], np.ndarray], a: float, b: float, n: int = 20001) -> float:
    x = np.linspace(a, b, n)
    y = f(x)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


@dataclass(frozen=True)
class SliverMeasures:
    """The part of a tunnel's backward extension outside the wellbore, and the hole it makes.

    ``volume`` and ``wall_area`` lie between the wellbore wall and station 0;
    ``hole_area`` is the area the tunnel removes from the wellbore wall;
    ``plane_area`` is the sliver's section in the plane through the tunnel axis
    normal to the wellbore axis.
    """

    volume: float
    wall_area: float
    hole_area: float
    plane_area: float


def sliver_measures(profile: Profile, wellbore_radius: float) -> SliverMeasures:
    """Integrate the sliver numerically (1D quadratures; error far below 1e-6 relative)."""
    big_r = wellbore_radius
    delta, _ = tunnel_extension(profile, big_r)
    slope = (profile.radii[1] - profile.radii[0]) / profile.stations[1]

    def tau(a: np.ndarray) -> np.ndarray:
        # |t| beyond which a point at station a (< 0) is outside the wellbore
        return np.sqrt(np.clip(big_r**2 - (big_r + a) ** 2, 0.0, None))

    def rho(a: np.ndarray) -> np.ndarray:
        return np.asarray(profile.radius_at(a))

    def section(a: np.ndarray) -> np.ndarray:
        # area of the disc of radius rho with |t| >= tau: two circular segments
        r, s = rho(a), tau(a)
        c = np.clip(s / r, 0.0, 1.0)
        return 2.0 * r**2 * (np.arccos(c) - c * np.sqrt(1.0 - c**2))

    def arc(a: np.ndarray) -> np.ndarray:
        r, s = rho(a), tau(a)
        c = np.clip(s / r, 0.0, 1.0)
        return r * math.sqrt(1.0 + slope**2) * (2.0 * np.pi - 4.0 * np.arcsin(c))

    def plane(a: np.ndarray) -> np.ndarray:
        return 2.0 * np.clip(rho(a) - tau(a), 0.0, None)

    r0 = float(profile.radii[0])
    r_hole = min(r0 + slope * 0.0, big_r)  # the hole's extent in t is about r0

    def hole(t: np.ndarray) -> np.ndarray:
        a = np.sqrt(np.clip(big_r**2 - t**2, 0.0, None)) - big_r
        half = np.sqrt(np.clip(rho(a) ** 2 - t**2, 0.0, None))
        return 2.0 * half * big_r / np.sqrt(np.clip(big_r**2 - t**2, 1e-300, None))

    t_max = min(1.5 * r_hole + 1e-12, big_r * (1.0 - 1e-12))
    return SliverMeasures(
        volume=_integrate(section, -delta, 0.0),
        wall_area=_integrate(arc, -delta, 0.0),
        hole_area=2.0 * _integrate(hole, 0.0, t_max),
        plane_area=_integrate(plane, -delta, 0.0),
    )


@dataclass(frozen=True)
class TunnelMeasures:
    """Analytic volume and areas of one whole tunnel outside the wellbore."""

    frustum_volume: float
    frustum_wall_area: float
    sliver: SliverMeasures
    tip_area: float
    axial_section: float  # section in the plane of the tunnel and wellbore axes (a >= 0)

    @property
    def volume(self) -> float:
        """Cavity volume outside the wellbore: frustums + sliver."""
        return self.frustum_volume + self.sliver.volume

    @property
    def wall_area(self) -> float:
        """Lateral wall outside the wellbore: frustums + sliver."""
        return self.frustum_wall_area + self.sliver.wall_area


def tunnel_measures(profile: Profile, wellbore_radius: float) -> TunnelMeasures:
    """Volume, wall and tip area of a tunnel (frustums through its sections, plus the sliver)."""
    from hfcdem.analytic import frustum_lateral_area, frustum_volume

    r = profile.radii
    lengths = np.diff(profile.stations)
    return TunnelMeasures(
        frustum_volume=frustum_volume(profile.diameters, profile.stations),
        frustum_wall_area=frustum_lateral_area(profile.diameters, profile.stations),
        sliver=sliver_measures(profile, wellbore_radius),
        tip_area=float(np.pi * r[-1] ** 2),
        axial_section=float(np.sum((r[:-1] + r[1:]) * lengths)),
    )


def expected_measures(geom: PerforatedBlock) -> dict[str, Any]:
    """Analytic volumes and facet-group areas of the modelled part of ``geom``.

    Returns ``{"volume": rock volume, "cavity": cavity volume, "areas": {tag:
    area}, "perforations": {K: {...}}}``; all for the kept part of the model.
    """
    lo, hi = kept_corners(geom.block.half, geom.symmetry)
    ext = hi - lo
    big_r = geom.wellbore.radius
    wi = axis_index(geom.wellbore.axis)
    others = [a for a in geom.symmetry if a != geom.wellbore.axis]
    wb_len = float(ext[wi])
    wb_share = 0.5 ** len(others)  # of the wellbore's cross-section
    wellbore_volume = np.pi * big_r**2 * wb_len * wb_share
    wall = 2.0 * np.pi * big_r * wb_len * wb_share
    perfs: dict[int, dict[str, float]] = {}
    cavity = wellbore_volume
    areas: dict[str, float] = {}
    for k, perf in enumerate(geom.perforations):
        frac = geom.kept_fraction(k)
        if frac == 0.0:
            continue
        m = tunnel_measures(perf.profile, big_r)
        perfs[k + 1] = {
            "fraction": frac,
            "volume": frac * m.volume,
            "frustum_volume": frac * m.frustum_volume,
            "sliver_volume": frac * m.sliver.volume,
            "wall_area": frac * m.wall_area,
            "frustum_wall_area": frac * m.frustum_wall_area,
            "tip_area": frac * m.tip_area,
            "hole_area": frac * m.sliver.hole_area,
        }
        cavity += frac * m.volume
        wall -= frac * m.sliver.hole_area
        areas[f"perforation_{k + 1}_wall"] = frac * m.wall_area
        areas[f"perforation_{k + 1}_tip"] = frac * m.tip_area
    areas["wellbore_wall"] = wall
    for i, axis in enumerate(AXES):
        face = float(np.prod([ext[j] for j in range(3) if j != i]))
        outer = face - (np.pi * big_r**2 * wb_share if i == wi else 0.0)
        areas[f"outer_{axis}max"] = outer
        if axis in geom.symmetry:
            areas[f"symmetry_{axis}"] = _symmetry_face(geom, axis, face)
        else:
            areas[f"outer_{axis}min"] = outer
    return {
        "volume": float(np.prod(ext)) - cavity,
        "cavity": cavity,
        "wellbore_volume": wellbore_volume,
        "areas": areas,
        "perforations": perfs,
    }


def _symmetry_face(geom: PerforatedBlock, axis: str, face: float) -> float:
    """Area of the rock on the mirror plane ``axis`` = 0."""
    big_r = geom.wellbore.radius
    wi = axis_index(geom.wellbore.axis)
    others = [a for a in geom.symmetry if a != axis]
    share = 0.5 ** len(others)
    if axis == geom.wellbore.axis:
        area = face - np.pi * big_r**2 * share  # the plane crosses the wellbore
    else:
        full_len = 2.0 * geom.block.half[wi]
        area = face - 2.0 * big_r * full_len * share  # the plane contains the wellbore axis
    for k, perf in enumerate(geom.perforations):
        if geom.relation(k, axis) != "cut":
            continue
        m = tunnel_measures(perf.profile, big_r)
        section = m.axial_section
        if axis == geom.wellbore.axis:
            section += m.sliver.plane_area
        area -= section * geom.kept_fraction(k, skip=axis)
    return float(area)


# ---------------------------------------------------------------------------
# Gmsh model
# ---------------------------------------------------------------------------


def _add_tunnel(occ: Any, frame: TunnelFrame) -> tuple[int, int]:
    """Loft the tunnel through circles; return the volume's (dim, tag)."""
    profile = frame.profile
    stations = [-frame.delta, *profile.stations[1:]]
    radii = [frame.inner_radius, *profile.radii[1:]]
    wires = []
    for s, r in zip(stations, radii, strict=True):
        c = frame.start + s * frame.d
        circle = occ.addCircle(*c, float(r), zAxis=list(frame.d), xAxis=list(frame.w))
        wires.append(occ.addCurveLoop([circle]))
    out = occ.addThruSections(wires, makeSolid=True, makeRuled=True)
    volumes = [e for e in out if e[0] == 3]
    if len(volumes) != 1:
        raise RuntimeError(f"lofting a tunnel gave {len(volumes)} volumes")
    return volumes[0]


def _add_zone(occ: Any, geom: PerforatedBlock) -> tuple[int, int] | None:
    zone = geom.fracturable
    if zone is None:
        return None
    if isinstance(zone, SphereZone):
        return (3, occ.addSphere(*zone.centre, zone.radius))
    if isinstance(zone, TunnelZone):
        frame = tunnel_frame(geom, zone.perforation - 1)
        assert zone.beyond_tip is not None
        reach = geom.wellbore.radius + frame.profile.length + zone.beyond_tip
        return (3, occ.addCylinder(*frame.origin, *(reach * frame.d), zone.radius))
    assert isinstance(zone, SlabZone)
    corner, size = slab_box(zone, geom.block.half)
    return (3, occ.addBox(*corner, *size))


def _sample_surface(model: Any, tag: int) -> np.ndarray:
    """Points on a (trimmed) surface, from a grid in its parameter space."""
    lo, hi = model.getParametrizationBounds(2, tag)
    for n in (6, 24):
        frac = (np.arange(n) + 0.5) / n
        pts = []
        for u in lo[0] + frac * (hi[0] - lo[0]):
            for v in lo[1] + frac * (hi[1] - lo[1]):
                if model.isInside(2, tag, [u, v], parametric=True):
                    pts.append(model.getValue(2, tag, [u, v]))
        if len(pts) >= 3:
            return np.asarray(pts)
    # a face too thin for the grid: points on its boundary curves
    pts = []
    for _, curve in model.getBoundary([(2, tag)], oriented=False):
        clo, chi = model.getParametrizationBounds(1, abs(curve))
        for f in (0.25, 0.5, 0.75):
            pts.append(model.getValue(1, abs(curve), [clo[0] + f * (chi[0] - clo[0])]))
    return np.asarray(pts)


def face_candidates(geom: PerforatedBlock) -> list[tuple[str, int, Residual]]:
    """(tag name, segment, distance of points to that analytic surface) for every face kind."""
    lo, hi = kept_corners(geom.block.half, geom.symmetry)
    out: list[tuple[str, int, Residual]] = []
    for i, axis in enumerate(AXES):
        out.append((f"outer_{axis}max", -1, plane_residual(i, float(hi[i]))))
        name = f"symmetry_{axis}" if axis in geom.symmetry else f"outer_{axis}min"
        out.append((name, -1, plane_residual(i, float(lo[i]))))
    w = axis_vector(geom.wellbore.axis)
    big_r = geom.wellbore.radius

    def wellbore(p: np.ndarray) -> np.ndarray:
        radial = p - np.outer(p @ w, w)
        return np.abs(np.linalg.norm(radial, axis=1) - big_r)

    out.append(("wellbore_wall", -1, wellbore))
    for k in range(len(geom.perforations)):
        if geom.kept_fraction(k) == 0.0:
            continue
        frame = tunnel_frame(geom, k)
        length = frame.profile.length
        tol = 1e-6 * length

        def wall(p: np.ndarray, f: TunnelFrame = frame, tol: float = tol) -> np.ndarray:
            a, rho = f.local(p)
            res = np.abs(rho - f.profile.radius_at(a))
            return np.where((a < -f.delta - tol) | (a > f.profile.length + tol), np.inf, res)

        def tip(p: np.ndarray, f: TunnelFrame = frame, tol: float = tol) -> np.ndarray:
            a, rho = f.local(p)
            res = np.abs(a - f.profile.length)
            return np.where(rho > f.profile.radii[-1] + tol, np.inf, res)

        out.append((f"perforation_{k + 1}_wall", k, wall))
        out.append((f"perforation_{k + 1}_tip", k, tip))
    return out


def classify_faces(
    model: Any, geom: PerforatedBlock, faces: list[int]
) -> dict[str, list[tuple[int, int]]]:
    """Name every boundary face by the analytic surface its points lie on.

    Returns ``{tag name: [(face, segment), ...]}``; ``segment`` is the tunnel
    segment (from 0) of a perforation wall face, -1 otherwise.
    """
    candidates = face_candidates(geom)
    scale = float(np.max(geom.block.size))
    tol = 1e-5 * scale
    groups: dict[str, list[tuple[int, int]]] = {}
    for face in faces:
        pts = _sample_surface(model, face)
        worst = [float(np.max(res(pts))) for _, _, res in candidates]
        best = int(np.argmin(worst))
        name, k, _ = candidates[best]
        if worst[best] > tol:
            raise RuntimeError(
                f"cannot tell which wall face {face} belongs to (closest: {name}, "
                f"off by {worst[best]:.3g} m)"
            )
        segment = -1
        if name.endswith("_wall") and k >= 0:
            frame = tunnel_frame(geom, k)
            a, _ = frame.local(pts)
            segment = int(
                np.clip(
                    np.searchsorted(frame.profile.stations, np.median(a)) - 1,
                    0,
                    len(frame.profile.stations) - 2,
                )
            )
        groups.setdefault(name, []).append((face, segment))
    return groups


def _threshold(model: Any, faces: list[int], start: float, geom: PerforatedBlock) -> int:
    extent = max(
        float(np.max(np.subtract(model.getBoundingBox(2, f)[3:], model.getBoundingBox(2, f)[:3])))
        for f in faces
    )
    return add_grading(
        model,
        2,
        faces,
        start,
        geom.mesh.size_far,
        max(geom.mesh.growth_distance(start), 1e-9),
        int(np.clip(np.ceil(2.0 * extent / start), 20, 200)),
    )


def _set_sizes(model: Any, geom: PerforatedBlock, groups: dict[str, list[tuple[int, int]]]) -> None:
    """Distance + Threshold fields: fine on the tunnel walls, graded to the far field."""
    thresholds = []
    for name, entries in groups.items():
        if name.startswith("perforation_"):
            k = int(name.split("_")[1]) - 1
            profile = geom.perforations[k].profile
            by_start: dict[float, list[int]] = {}
            for face, segment in entries:
                if name.endswith("_tip"):
                    d = profile.diameters[-1]
                else:
                    d = min(profile.diameters[segment], profile.diameters[segment + 1])
                by_start.setdefault(geom.mesh.wall_size(d), []).append(face)
            for start, faces in sorted(by_start.items()):
                thresholds.append(_threshold(model, faces, start, geom))
        elif name == "wellbore_wall":
            faces = [f for f, _ in entries]
            thresholds.append(_threshold(model, faces, geom.wellbore_size, geom))
    use_gradings(model, thresholds, geom.mesh.size_far)
    gmsh.option.setNumber("Mesh.Algorithm3D", geom.mesh.ALGORITHMS[geom.mesh.algorithm])


def element_quality(model: Any, dim: int) -> dict[str, Any]:
    """Minimum and median Gmsh quality (minSICN: 1 regular, <= 0 inverted) of the cells."""
    etype = 4 if dim == 3 else 2
    tags, _ = model.mesh.getElementsByType(etype)
    q = np.asarray(model.mesh.getElementQualities(tags, "minSICN"))
    return {"measure": "minSICN", "min": float(q.min()), "median": float(np.median(q))}


def build_perforated_block(geom: PerforatedBlock, model: Any) -> dict[str, Any]:
    """Create the geometry, physical groups and 3D mesh of ``geom`` in the Gmsh ``model``.

    Returns build facts for the mesh report (element quality, face counts).
    """
    gmsh.option.setNumber("General.NumThreads", 1)  # reproducible meshes
    occ = model.occ
    lo, hi = kept_corners(geom.block.half, geom.symmetry)
    box = occ.addBox(*lo, *(hi - lo))
    w = axis_vector(geom.wellbore.axis)
    wi = axis_index(geom.wellbore.axis)
    reach = 1.1 * geom.block.half[wi]
    wellbore = occ.addCylinder(*(-reach * w), *(2.0 * reach * w), geom.wellbore.radius)
    tools = [(3, wellbore)]
    for k in range(len(geom.perforations)):
        if geom.kept_fraction(k) > 0.0:
            tools.append(_add_tunnel(occ, tunnel_frame(geom, k)))
    rock, _ = occ.cut([(3, box)], tools)
    if len(rock) != 1:
        raise RuntimeError(f"cutting the cavity out of the block left {len(rock)} pieces")
    cells = {"rock": [rock[0][1]]}
    zone = _add_zone(occ, geom)
    if zone is not None:
        _, children = occ.fragment(rock, [zone])
        of_rock = {tag for _, tag in children[0]}
        of_zone = {tag for _, tag in children[1]}
        occ.remove([(3, t) for t in sorted(of_zone - of_rock)], recursive=True)
        cells = {"rock": sorted(of_rock - of_zone), "fracturable": sorted(of_rock & of_zone)}
        if not cells["fracturable"]:
            raise RuntimeError("the fracturable zone does not meet the rock")
    occ.synchronize()

    volumes = [(3, t) for tags in cells.values() for t in tags]
    seen: dict[int, int] = {}
    for v in volumes:
        for _, face in model.getBoundary([v], oriented=False):
            seen[abs(face)] = seen.get(abs(face), 0) + 1
    outer = sorted(f for f, n in seen.items() if n == 1)  # faces between volumes are inside
    groups = classify_faces(model, geom, outer)

    for name, tags in cells.items():
        if tags:
            model.addPhysicalGroup(3, tags, name=name)
    for name in sorted(groups):
        model.addPhysicalGroup(2, sorted(f for f, _ in groups[name]), name=name)

    _set_sizes(model, geom, groups)
    model.mesh.generate(3)
    return {
        "quality": element_quality(model, 3),
        "faces": {name: len(v) for name, v in sorted(groups.items())},
    }


__all__ = [
    "SliverMeasures",
    "TunnelMeasures",
    "build_perforated_block",
    "classify_faces",
    "element_quality",
    "expected_measures",
    "sliver_measures",
    "tunnel_measures",
]
