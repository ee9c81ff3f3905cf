"""Verification meshes: the plates and the block that the CDEM tests and benchmarks check.

These meshers predate the scene files and keep their verified set-ups: a
borehole plate with structured wall rings, a crack plate, a half plate with a
fracture path split into facets of an exact length (KGD) and a quarter block
with a penny crack.  Their facet groups are ``outer`` (the whole outer
boundary), ``symmetry_x``/``symmetry_y``, ``wellbore_wall``, ``crack`` and
``path``; the scene meshers of :mod:`hfcdem.mesh.plates` name the outer edges
one by one and call the path ``fracture_path``.  The tests' numbers were
verified on these meshes, so they stay until a scene mesher builds the same
mesh.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from mpi4py import MPI

from hfcdem.mesh.grading import add_grading, use_gradings
from hfcdem.mesh.tagged import TaggedMesh, mesh_from_gmsh


@dataclass(frozen=True)
class BoreholePlate:
    """A 2D plate around a borehole centred at the origin (plane strain).

    ``quarter`` keeps x >= 0, y >= 0 with the symmetry lines tagged; otherwise the
    full square ``[-half_width, half_width]^2`` minus the hole.  ``ring_layers``
    > 0 meshes that many structured layers of size ``size_at_wall`` around the
    wall, so radial facets (the planes a breakdown fracture starts on) exist at
    every angle step, including along the axes.  ``growth`` is the element size
    increase per metre of distance from the wall.
    """

    radius: float
    half_width: float
    size_at_wall: float
    size_far: float
    quarter: bool = True
    ring_layers: int = 0
    growth: float = 0.25

    def __post_init__(self) -> None:
        _check_lengths(self, "radius", "half_width", "size_at_wall", "size_far")
        if self.half_width <= 2.0 * self.radius:
            raise ValueError(
                f"half_width ({self.half_width} m) must exceed twice the radius ({self.radius} m)"
            )
        if self.size_at_wall > self.radius:
            raise ValueError(
                f"size_at_wall ({self.size_at_wall} m) must not exceed the radius ({self.radius} m)"
            )
        if self.size_far < self.size_at_wall:
            raise ValueError("size_far must be at least size_at_wall")
        if not 0 <= self.ring_layers <= 200:
            raise ValueError(f"ring_layers must be in [0, 200], got {self.ring_layers!r}")
        if self.radius + self.ring_layers * self.size_at_wall >= self.half_width:
            raise ValueError("the structured ring around the wall must fit inside the plate")
        _check_growth(self.growth)

    def _ring_sectors(self, occ: Any, b: float) -> list[int]:
        """Quarter-annulus surfaces between the wall and radius ``b``."""
        a = self.radius
        centre = occ.addPoint(0.0, 0.0, 0.0)
        angles = [0.0, 0.5 * np.pi] if self.quarter else [0.0, 0.5 * np.pi, np.pi, 1.5 * np.pi]
        inner = [occ.addPoint(a * np.cos(t), a * np.sin(t), 0.0) for t in angles]
        outer = [occ.addPoint(b * np.cos(t), b * np.sin(t), 0.0) for t in angles]
        radial = [occ.addLine(i, o) for i, o in zip(inner, outer, strict=True)]
        sectors = []
        count = 1 if self.quarter else 4
        for k in range(count):
            k1 = (k + 1) % len(angles)
            arc_in = occ.addCircleArc(inner[k], centre, inner[k1])
            arc_out = occ.addCircleArc(outer[k], centre, outer[k1])
            loop = occ.addCurveLoop([radial[k], arc_out, -radial[k1], -arc_in])
            sectors.append(occ.addPlaneSurface([loop]))
        return sectors

    def build(self, model: Any) -> None:
        """Create the Gmsh geometry, groups and mesh of the plate."""
        occ = model.occ
        w, a = self.half_width, self.radius
        b = a + self.ring_layers * self.size_at_wall
        if self.quarter:
            plate = occ.addRectangle(0.0, 0.0, 0.0, w, w)
        else:
            plate = occ.addRectangle(-w, -w, 0.0, 2.0 * w, 2.0 * w)
        hole = occ.addDisk(0.0, 0.0, 0.0, b, b)
        occ.cut([(2, plate)], [(2, hole)])
        if self.ring_layers:
            self._ring_sectors(occ, b)
            occ.removeAllDuplicates()
        occ.synchronize()
        surfaces = [t for _, t in model.getEntities(2)]
        model.addPhysicalGroup(2, surfaces, name="rock")

        groups: dict[str, list[int]] = {}
        tol = max(1e-6 * w, 1e-6)  # OCC pads bounding boxes by about 1e-7
        boundary = {c for _, c in model.getBoundary([(2, t) for t in surfaces], oriented=False)}
        for curve in sorted(boundary):
            x0, y0, _, x1, y1, _ = model.getBoundingBox(1, curve)
            if (
                model.getType(1, curve) in ("Circle", "Ellipse")
                and max(abs(x0), abs(x1), abs(y0), abs(y1)) < a + tol
            ):
                key = "wellbore_wall"
            elif abs(x0) < tol and abs(x1) < tol:
                key = "symmetry_x"
            elif abs(y0) < tol and abs(y1) < tol:
                key = "symmetry_y"
            else:
                key = "outer"
            groups.setdefault(key, []).append(curve)

        if self.ring_layers:
            # structured layers: arcs divided evenly, radial lines into ring_layers
            for _, curve in model.getEntities(1):
                x0, y0, _, x1, y1, _ = model.getBoundingBox(1, curve)
                if max(abs(x0), abs(x1), abs(y0), abs(y1)) > b + tol:
                    continue
                if model.getType(1, curve) in ("Circle", "Ellipse"):
                    # same count on inner and outer arcs (transfinite needs it)
                    n = max(2, int(np.ceil(0.5 * np.pi * a / self.size_at_wall)))
                    model.mesh.setTransfiniteCurve(curve, n + 1)
                else:
                    model.mesh.setTransfiniteCurve(curve, self.ring_layers + 1)
            for _, surf in model.getEntities(2):
                x0, y0, _, x1, y1, _ = model.getBoundingBox(2, surf)
                if max(abs(x0), abs(x1), abs(y0), abs(y1)) <= b + tol:
                    model.mesh.setTransfiniteSurface(surf)
        wall = groups["wellbore_wall"]
        _grade_and_mesh(
            model, 1, groups, wall, self.size_at_wall, self.size_far, self.growth, flat=b - a
        )


def create_borehole_plate(plate: BoreholePlate, comm: MPI.Comm = MPI.COMM_WORLD) -> TaggedMesh:
    """Mesh ``plate`` on rank 0 and distribute it over ``comm``."""
    return mesh_from_gmsh(plate.build, comm, gdim=2, name="borehole_plate")


def _add_groups(model: Any, dim: int, groups: Mapping[str, list[int]]) -> None:
    """Create one named physical group per entry (the names become the tags)."""
    for key, tags in sorted(groups.items()):
        model.addPhysicalGroup(dim, tags, name=key)


def _check_lengths(obj: Any, *keys: str) -> None:
    """Raise ValueError naming the first field that is not a positive finite length."""
    for key in keys:
        value = getattr(obj, key)
        if not np.isfinite(value) or value <= 0.0:
            raise ValueError(f"{key} must be a positive length in m, got {value!r}")


def _grade_and_mesh(
    model: Any,
    dim: int,
    groups: Mapping[str, list[int]],
    refined: list[int],
    size_min: float,
    size_max: float,
    growth: float,
    flat: float = 0.0,
) -> None:
    """Name the boundary ``groups``, grade the size from ``refined`` and mesh the model.

    The size is ``size_min`` within ``flat`` of the refined entities and grows at
    ``growth`` per metre beyond, up to ``size_max``.
    """
    _add_groups(model, dim, groups)
    reach = (size_max - size_min) / growth
    grading = add_grading(model, dim, refined, size_min, size_max, flat + reach, 400)
    use_gradings(model, [grading])
    model.mesh.generate(dim + 1)


def _check_growth(growth: float) -> None:
    if not 0.01 <= growth <= 2.0:
        raise ValueError(f"growth must be in [0.01, 2] (size per distance), got {growth!r}")


@dataclass(frozen=True)
class CrackPlate:
    """A 2D plate ``[-half_width, half_width]^2`` with a central crack on y = 0.

    The crack (facet group ``"crack"``) runs from ``-half_length`` to
    ``half_length``; it is embedded, so its facets are interior facets that the
    CDEM solid treats as a pre-existing open interface.  ``half_model`` keeps
    x >= 0 with ``"symmetry_x"`` tagged.  The element size grows from
    ``size_at_crack`` along the crack to ``size_far`` over ``grading`` metres.
    """

    half_length: float
    half_width: float
    size_at_crack: float
    size_far: float
    half_model: bool = True
    growth: float = 0.25

    def __post_init__(self) -> None:
        _check_lengths(self, "half_length", "half_width", "size_at_crack", "size_far")
        if self.half_width <= self.half_length:
            raise ValueError("half_width must exceed the crack half_length")
        if self.size_at_crack > self.half_length / 2:
            raise ValueError("size_at_crack must resolve the crack: at most half_length / 2")
        if self.size_far < self.size_at_crack:
            raise ValueError("size_far must be at least size_at_crack")
        _check_growth(self.growth)

    def build(self, model: Any) -> None:
        """Create the Gmsh geometry, groups and mesh of the plate."""
        occ = model.occ
        w, a = self.half_width, self.half_length
        x0 = 0.0 if self.half_model else -w
        plate = occ.addRectangle(x0, -w, 0.0, w - x0, 2.0 * w)
        p0 = occ.addPoint(0.0 if self.half_model else -a, 0.0, 0.0)
        p1 = occ.addPoint(a, 0.0, 0.0)
        crack = occ.addLine(p0, p1)
        occ.fragment([(2, plate)], [(1, crack)])
        occ.synchronize()
        surfaces = [t for _, t in model.getEntities(2)]
        model.addPhysicalGroup(2, surfaces, name="rock")
        tol = 1e-7 + 1e-9 * w
        groups: dict[str, list[int]] = {}
        for _, curve in model.getEntities(1):
            bx0, by0, _, bx1, by1, _ = model.getBoundingBox(1, curve)
            if abs(by0) < tol and abs(by1) < tol and bx1 <= a + tol:
                key = "crack"
            elif self.half_model and abs(bx0) < tol and abs(bx1) < tol:
                key = "symmetry_x"
            else:
                key = "outer"
            groups.setdefault(key, []).append(curve)
        _grade_and_mesh(
            model, 1, groups, groups["crack"], self.size_at_crack, self.size_far, self.growth
        )


def create_crack_plate(plate: CrackPlate, comm: MPI.Comm = MPI.COMM_WORLD) -> TaggedMesh:
    """Mesh ``plate`` on rank 0 and distribute it over ``comm``."""
    return mesh_from_gmsh(plate.build, comm, gdim=2, name="crack_plate")


@dataclass(frozen=True)
class PathPlate:
    """A 2D half plate ``[0, half_width] x [-half_width, half_width]`` with a fracture path.

    The path runs along y = 0 from the symmetry line x = 0 (``"symmetry_x"``) to
    ``path_length``, split into facets of exactly ``size_on_path``: the first
    ``crack_facets`` form the pre-existing ``"crack"``, the rest the ``"path"``
    group that a fracture may open along (a KGD fracture's plane).  The point
    (0, 0) is a mesh vertex: the injection point.  The element size grows from
    the path at ``growth`` per metre up to ``size_far``; the outer edges are
    ``"outer"``.
    """

    path_length: float
    half_width: float
    size_on_path: float
    size_far: float
    crack_facets: int = 1
    growth: float = 0.3

    def __post_init__(self) -> None:
        _check_lengths(self, "path_length", "half_width", "size_on_path", "size_far")
        if self.half_width <= self.path_length:
            raise ValueError(
                f"half_width ({self.half_width} m) must exceed path_length ({self.path_length} m)"
            )
        segments = self.path_length / self.size_on_path
        if abs(segments - round(segments)) > 1e-6 * segments or round(segments) < 2:
            raise ValueError(
                f"path_length ({self.path_length} m) must be a whole number (>= 2) of "
                f"size_on_path ({self.size_on_path} m)"
            )
        if not 1 <= self.crack_facets < round(segments):
            raise ValueError(f"crack_facets must be in [1, {round(segments) - 1}]")
        if self.size_far < self.size_on_path:
            raise ValueError("size_far must be at least size_on_path")
        _check_growth(self.growth)

    def build(self, model: Any) -> None:
        """Create the Gmsh geometry, groups and mesh of the plate."""
        occ = model.occ
        w, h = self.half_width, self.size_on_path
        a = self.crack_facets * h
        plate = occ.addRectangle(0.0, -w, 0.0, w, 2.0 * w)
        pts = [occ.addPoint(x, 0.0, 0.0) for x in (0.0, a, self.path_length)]
        lines = [occ.addLine(pts[0], pts[1]), occ.addLine(pts[1], pts[2])]
        occ.fragment([(2, plate)], [(1, c) for c in lines])
        occ.synchronize()
        model.addPhysicalGroup(2, [t for _, t in model.getEntities(2)], name="rock")
        tol = 1e-7 + 1e-9 * w
        groups: dict[str, list[int]] = {}
        path_curves = []
        for _, curve in model.getEntities(1):
            bx0, by0, _, bx1, by1, _ = model.getBoundingBox(1, curve)
            if abs(by0) < tol and abs(by1) < tol and bx1 <= self.path_length + tol:
                key = "crack" if bx1 <= a + tol else "path"
                n = round((bx1 - bx0) / h)
                model.mesh.setTransfiniteCurve(curve, n + 1)
                path_curves.append(curve)
            elif abs(bx0) < tol and abs(bx1) < tol:
                key = "symmetry_x"
            else:
                key = "outer"
            groups.setdefault(key, []).append(curve)
        _grade_and_mesh(model, 1, groups, path_curves, h, self.size_far, self.growth)


def create_path_plate(plate: PathPlate, comm: MPI.Comm = MPI.COMM_WORLD) -> TaggedMesh:
    """Mesh ``plate`` on rank 0 and distribute it over ``comm``."""
    return mesh_from_gmsh(plate.build, comm, gdim=2, name="path_plate")


@dataclass(frozen=True)
class PennyBlock:
    """A quarter block ``[0, w] x [0, w] x [-w, w]`` with a penny crack of ``radius`` at z = 0.

    The crack (facet group ``"crack"``) is an embedded quarter disk centred on
    the z axis; ``"symmetry_x"`` and ``"symmetry_y"`` are the cut planes, the
    rest of the boundary is ``"outer"``.
    """

    radius: float
    half_width: float
    size_at_crack: float
    size_far: float
    growth: float = 0.3

    def __post_init__(self) -> None:
        _check_lengths(self, "radius", "half_width", "size_at_crack", "size_far")
        if self.half_width <= 2.0 * self.radius:
            raise ValueError("half_width must exceed twice the crack radius")
        if self.size_at_crack > self.radius / 2:
            raise ValueError("size_at_crack must resolve the crack: at most radius / 2")
        if self.size_far < self.size_at_crack:
            raise ValueError("size_far must be at least size_at_crack")

    def build(self, model: Any) -> None:
        """Create the Gmsh geometry, groups and mesh of the block."""
        occ = model.occ
        w, a = self.half_width, self.radius
        box = occ.addBox(0.0, 0.0, -w, w, w, 2.0 * w)
        disk = occ.addDisk(0.0, 0.0, 0.0, a, a)
        square = occ.addRectangle(0.0, 0.0, 0.0, a, a)
        quarter, _ = occ.intersect([(2, disk)], [(2, square)])
        occ.fragment([(3, box)], quarter)
        occ.synchronize()
        model.addPhysicalGroup(3, [t for _, t in model.getEntities(3)], name="rock")
        tol = 1e-7 + 1e-9 * w
        groups: dict[str, list[int]] = {}
        for _, surf in model.getEntities(2):
            x0, y0, z0, x1, y1, z1 = model.getBoundingBox(2, surf)
            if abs(z0) < tol and abs(z1) < tol and max(x1, y1) <= a + tol:
                key = "crack"
            elif abs(x0) < tol and abs(x1) < tol:
                key = "symmetry_x"
            elif abs(y0) < tol and abs(y1) < tol:
                key = "symmetry_y"
            else:
                key = "outer"
            groups.setdefault(key, []).append(surf)
        _grade_and_mesh(
            model, 2, groups, groups["crack"], self.size_at_crack, self.size_far, self.growth
        )


def create_penny_block(block: PennyBlock, comm: MPI.Comm = MPI.COMM_WORLD) -> TaggedMesh:
    """Mesh ``block`` on rank 0 and distribute it over ``comm``."""
    return mesh_from_gmsh(block.build, comm, gdim=3, name="penny_block")


__all__ = [
    "BoreholePlate",
    "CrackPlate",
    "PathPlate",
    "PennyBlock",
    "create_borehole_plate",
    "create_crack_plate",
    "create_path_plate",
    "create_penny_block",
]
