"""The 2D plates in the x-y plane (plane strain), as validated dataclasses.

:class:`CrackPlate` (a central pre-existing crack), :class:`KGDStrip` (an initial
crack and a fracture path, injection at the origin) and :class:`BoreholeSquare`
(a borehole at the centre).  Each checks its zone, symmetry and sizing and
estimates its cell count; :mod:`hfcdem.mesh.plates` meshes them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from hfcdem.config.fingerprint import fingerprinted
from hfcdem.config.parts import (
    MAX_CELLS,
    Crack,
    FracturableZone,
    MeshSizing,
    Plate,
    SlabZone,
    SphereZone,
    TunnelZone,
    Vector,
    Wellbore,
    check_symmetry_axes,
    estimate_cells,
    refuse_mesh_options,
    show_length,
)
from hfcdem.config.tables import SceneError


def _check_plate_zone(zone: FracturableZone | None, plate: Plate) -> None:
    if zone is None:
        return
    if isinstance(zone, TunnelZone):
        raise SceneError("fracturable.shape", "a 2D plate takes 'sphere' (a disc) or 'slab'")
    if isinstance(zone, SlabZone) and zone.axis == "z":
        raise SceneError("fracturable.axis", "a 2D slab is normal to 'x' or 'y'")
    if isinstance(zone, SphereZone) and (
        zone.centre[2] != 0.0 or np.any(np.abs(zone.centre[:2]) >= plate.half[:2])
    ):
        raise SceneError("fracturable.centre", "must lie inside the plate, with z = 0")


def _check_plate_symmetry(geom: Any, forbidden: dict[str, str]) -> None:
    for axis in geom.symmetry:
        if axis in forbidden:
            raise SceneError("symmetry", f"{axis} = 0 is not allowed: {forbidden[axis]}")
        zone = geom.fracturable
        problem = zone.mirror_problem(axis) if isinstance(zone, SphereZone | SlabZone) else None
        if problem is not None:
            raise SceneError(
                "symmetry", f"{axis} = 0 is not a symmetry plane of this scene: {problem}"
            )


def _check_plate_mesh(geom: Any, finest_feature: float, what: str) -> None:
    if geom.mesh.algorithm != "delaunay":
        raise SceneError("mesh.algorithm", "a 2D plate is meshed by Gmsh's 2D mesher; remove it")
    if geom.mesh.size > finest_feature:
        raise SceneError(
            "mesh.size",
            f"{show_length(geom.mesh.size)} cannot resolve {what} ({show_length(finest_feature)})",
        )
    if geom.mesh.size_far > min(geom.plate.width, geom.plate.height):
        raise SceneError("mesh.size_far", "exceeds the plate")
    cells = geom.estimated_cells()
    if cells > MAX_CELLS:
        raise SceneError(
            "mesh.size",
            f"{show_length(geom.mesh.size)} would give about {cells:.2g} cells "
            f"(limit {MAX_CELLS:.0e})",
        )


_CRACK_ON_PLANE = (
    "the crack would lie on the symmetry line; the CDEM solid needs it as interior facets"
)


def _plate_symmetric_axes(
    zone: FracturableZone | None, allowed: tuple[str, ...]
) -> tuple[str, ...]:
    if not isinstance(zone, SphereZone | SlabZone):
        return allowed
    return tuple(a for a in allowed if zone.mirror_problem(a) is None)


def _estimate_plate_cells(geom: Any, start: float, line: float = 0.0, radius: float = 0.0) -> float:
    """Rough triangle count of a plate refined to ``start`` around a line or a hole.

    The refined wall is a straight line of ``line`` length or a circle of
    ``radius``; the curve at distance rho from it is 2 line + 2 pi (radius + rho) long.
    """
    frac = 0.5 ** len(geom.symmetry)

    def around(rho: np.ndarray) -> np.ndarray:
        return frac * (2.0 * line + 2.0 * np.pi * (radius + rho))

    area = geom.plate.width * geom.plate.height * frac
    return estimate_cells(geom.mesh, area, [(start, around)], 2)


@fingerprinted
@dataclass(frozen=True)
class CrackPlate:
    """A 2D plate with a central pre-existing crack along x (tag ``crack``)."""

    plate: Plate
    crack: Crack
    mesh: MeshSizing
    fracturable: FracturableZone | None = None
    symmetry: tuple[str, ...] = ()

    kind: ClassVar[str] = "crack_plate"
    dim: ClassVar[int] = 2

    def __post_init__(self) -> None:
        object.__setattr__(self, "symmetry", check_symmetry_axes(self.symmetry, ("x", "y")))
        if self.crack.length > 0.8 * self.plate.width:
            raise SceneError("crack.length", "must be at most 0.8 x the plate width")
        refuse_mesh_options(self.mesh, self.kind, ("wall_rings", "path_size"))
        _check_plate_zone(self.fracturable, self.plate)
        _check_plate_symmetry(self, {"y": _CRACK_ON_PLANE})
        _check_plate_mesh(self, 0.25 * self.crack.length, "a quarter of the crack")

    def symmetric_axes(self) -> tuple[str, ...]:
        """Planes the scene may be cut along (the crack line itself is never one)."""
        return _plate_symmetric_axes(self.fracturable, ("x",))

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        return _estimate_plate_cells(self, self.mesh.size, line=self.crack.length)


@fingerprinted
@dataclass(frozen=True)
class KGDStrip:
    """A 2D plate with an initial crack and a fracture path along x; injection at the origin."""

    plate: Plate
    crack: Crack
    mesh: MeshSizing
    fracturable: FracturableZone | None = None
    symmetry: tuple[str, ...] = ()

    kind: ClassVar[str] = "kgd_strip"
    dim: ClassVar[int] = 2
    injection_point: ClassVar[Vector] = (0.0, 0.0, 0.0)
    crack_direction: ClassVar[Vector] = (1.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "symmetry", check_symmetry_axes(self.symmetry, ("x", "y")))
        if self.crack.path_length is None:
            object.__setattr__(self, "crack", Crack(self.crack.length, self.crack.length))
        path = self.crack.path_length
        assert path is not None
        if path > 0.9 * self.plate.width:
            raise SceneError("crack.path_length", "must be at most 0.9 x the plate width")
        refuse_mesh_options(self.mesh, self.kind, ("wall_rings",))
        self._check_path_size(0.5 * self.crack.length, 0.5 * path)
        _check_plate_zone(self.fracturable, self.plate)
        _check_plate_symmetry(self, {"y": _CRACK_ON_PLANE})
        _check_plate_mesh(self, 0.5 * self.crack.length, "half the initial crack")

    def _check_path_size(self, half: float, path: float) -> None:
        """Refuse a ``mesh.path_size`` that does not split the crack and path into whole facets."""
        step = self.mesh.path_size
        if step is None:
            return
        for what, length, least in (("crack.length", half, 1), ("crack.path_length", path, 0)):
            if what == "crack.path_length":
                length -= half
            count = length / step
            if abs(count - round(count)) > 1e-6 * max(count, 1.0) or round(count) < least:
                raise SceneError(
                    "mesh.path_size",
                    f"{show_length(step)} must divide each wing of {what} into whole facets "
                    f"({show_length(length)} is {count:.6g} facets)",
                )

    @property
    def path_start(self) -> float:
        """Element size on the crack and the path (where the grading starts)."""
        return self.mesh.path_size if self.mesh.path_size is not None else self.mesh.size

    def symmetric_axes(self) -> tuple[str, ...]:
        """Planes the scene may be cut along."""
        return _plate_symmetric_axes(self.fracturable, ("x",))

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        path = self.crack.path_length or self.crack.length
        return _estimate_plate_cells(self, self.path_start, line=path)


@fingerprinted
@dataclass(frozen=True)
class BoreholeSquare:
    """A 2D plate with a circular borehole at its centre (tag ``wellbore_wall``)."""

    plate: Plate
    wellbore: Wellbore
    mesh: MeshSizing
    fracturable: FracturableZone | None = None
    symmetry: tuple[str, ...] = ()

    kind: ClassVar[str] = "borehole_plate"
    dim: ClassVar[int] = 2

    def __post_init__(self) -> None:
        object.__setattr__(self, "symmetry", check_symmetry_axes(self.symmetry, ("x", "y")))
        if self.wellbore.diameter > 0.5 * min(self.plate.width, self.plate.height):
            raise SceneError(
                "wellbore.diameter",
                f"{show_length(self.wellbore.diameter)} is too large: at most half the plate",
            )
        _check_plate_zone(self.fracturable, self.plate)
        _check_plate_symmetry(self, {})
        _check_plate_mesh(self, self.wellbore.diameter, "the borehole")
        refuse_mesh_options(self.mesh, self.kind, ("path_size",))
        self._check_rings()

    def _check_rings(self) -> None:
        if not self.mesh.wall_rings:
            return
        if self.fracturable is not None:
            raise SceneError(
                "mesh.wall_rings",
                "structured wall rings cannot be combined with a fracturable zone (the zone's "
                "edge would cut the rings); leave one of them out",
            )
        if self.ring_radius >= 0.9 * float(np.min(self.plate.half[:2])):
            raise SceneError(
                "mesh.wall_rings",
                f"{self.mesh.wall_rings} rings of {show_length(self.wall_size)} reach "
                f"{show_length(self.ring_radius)} from the centre; they must end inside 0.9 x "
                f"the half plate ({show_length(0.9 * float(np.min(self.plate.half[:2])))})",
            )

    @property
    def ring_radius(self) -> float:
        """Outer radius of the structured wall rings (the wall radius without rings)."""
        return self.wellbore.radius + self.mesh.wall_rings * self.wall_size

    @property
    def wall_size(self) -> float:
        """Element size on the borehole wall."""
        return self.mesh.wall_size(self.wellbore.diameter)

    def symmetric_axes(self) -> tuple[str, ...]:
        """Planes the scene may be cut along."""
        return _plate_symmetric_axes(self.fracturable, ("x", "y"))

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        return _estimate_plate_cells(self, self.wall_size, radius=self.wellbore.radius)


WINGS = ("point", "mirror")


@fingerprinted
@dataclass(frozen=True)
class AngledPathPlate:
    """A 2D plate with a central initial crack along x and a straight path from each end.

    The initial crack (tag ``crack``, total ``crack.length``) runs along x through
    the injection point at the origin; from each of its ends a straight fracture
    path (tag ``fracture_path``, ``path_length`` long each) leaves at
    ``path_angle`` (rad) to the x axis.  ``wings``: ``"point"`` (the left path is
    the right one turned by 180 degrees about the origin) or ``"mirror"`` (mirrored
    in x = 0).  ``corner_support``: the length of each edge held fixed at each
    corner (tag ``outer_corners``); the rest of the edges is free (tags
    ``edge_xmin`` ...).  0: every edge fixed (tags ``outer_xmin`` ...).
    ``slot_width`` > 0 makes the initial crack an open slot of that width (a
    cavity, tag ``wellbore_wall``: one storage node loaded by its pressure, the
    fluid injected into it) instead of a line of interior facets (tag ``crack``,
    fluid entering at the origin).  ``mesh.path_size`` (default ``mesh.size``) is
    the facet size along crack and paths.
    """

    plate: Plate
    crack: Crack
    mesh: MeshSizing
    path_length: float
    path_angle: float
    wings: str = "point"
    corner_support: float = 0.0
    slot_width: float = 0.0
    fracturable: FracturableZone | None = None
    symmetry: tuple[str, ...] = ()

    kind: ClassVar[str] = "angled_path_plate"
    dim: ClassVar[int] = 2
    injection_point: ClassVar[Vector] = (0.0, 0.0, 0.0)
    crack_direction: ClassVar[Vector] = (1.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.symmetry:
            raise SceneError("symmetry", "an angled_path_plate is modelled whole: give 'none'")
        if self.fracturable is not None:
            raise SceneError(
                "fracturable", "an angled_path_plate breaks along its paths only; remove it"
            )
        if self.wings not in WINGS:
            raise SceneError("crack.wings", f"expected one of {', '.join(WINGS)}: {self.wings!r}")
        if not 0.0 <= self.path_angle < 0.5 * np.pi:
            raise SceneError(
                "crack.path_angle", f"expected 0 to 90 deg, got {np.degrees(self.path_angle):g} deg"
            )
        if not self.path_length > 0.0:
            raise SceneError("crack.path_length", "must be a positive length")
        refuse_mesh_options(self.mesh, self.kind, ("wall_rings",))
        end = self.path_end
        margin = self.path_start
        half = self.plate.half
        if abs(end[0]) > half[0] - margin or abs(end[1]) > half[1] - margin:
            raise SceneError(
                "crack.path_length",
                f"{show_length(self.path_length)} at {np.degrees(self.path_angle):g} deg ends at "
                f"({show_length(end[0])}, {show_length(end[1])}): it must end a facet "
                f"({show_length(margin)}) inside the plate",
            )
        limit = 0.5 * float(min(self.plate.width, self.plate.height))
        if not 0.0 <= self.corner_support < limit:
            raise SceneError(
                "support.corners",
                f"expected 0 to half the shorter side ({show_length(limit)}), "
                f"got {show_length(self.corner_support)}",
            )
        if not 0.0 <= self.slot_width <= 0.25 * self.crack.length:
            raise SceneError(
                "crack.width",
                f"expected 0 (a line) to a quarter of the crack length, "
                f"got {show_length(self.slot_width)}",
            )
        _check_plate_mesh(self, 0.5 * self.crack.length, "half the initial crack")

    @property
    def path_start(self) -> float:
        """Element size on the crack and the paths (where the grading starts)."""
        return self.mesh.path_size if self.mesh.path_size is not None else self.mesh.size

    @property
    def direction(self) -> np.ndarray:
        """Unit vector of the right path (x > 0)."""
        return np.array([np.cos(self.path_angle), np.sin(self.path_angle)])

    @property
    def path_end(self) -> np.ndarray:
        """End of the right path (x, y)."""
        return np.array([0.5 * self.crack.length, 0.0]) + self.path_length * self.direction

    def wing(self, side: int) -> tuple[np.ndarray, np.ndarray]:
        """Start (the crack end) and unit direction of the path on ``side`` (+1 right, -1 left)."""
        start = np.array([side * 0.5 * self.crack.length, 0.0])
        d = self.direction
        if side < 0:
            d = -d if self.wings == "point" else np.array([-d[0], d[1]])
        return start, d

    def symmetric_axes(self) -> tuple[str, ...]:
        """None: the plate is modelled whole."""
        return ()

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        line = self.crack.length + 2.0 * self.path_length
        return _estimate_plate_cells(self, self.path_start, line=line)


__all__ = ["AngledPathPlate", "BoreholeSquare", "CrackPlate", "KGDStrip"]
