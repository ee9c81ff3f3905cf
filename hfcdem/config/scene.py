"""Scenes read from TOML into frozen, validated dataclasses (SI units inside).

Only the *geometry* of a scene exists so far; the sections later issues will
fill (``rock``, ``stress``, ``fluid``, ``injection``, ``solver``, ``output``)
are accepted and ignored, any other top-level key is an error.  Every
dimensional value carries its unit (``"33.44 mm"``, ``"2 m"``, ``"60 deg"``;
:mod:`hfcdem.config.units`), and every error names the field by its dotted path
(``geometry.perforations[0].diameters[2]``) and the expected range, before Gmsh
runs.

Conventions (3D scenes)
-----------------------
* x points along SH, y along Sh, z up (along Sv).  The block is centred at the
  origin.
* The wellbore runs through the block centre along ``wellbore.axis`` (default
  ``"y"``: horizontal, along Sh, as in the paper's 2 m cube, so that a
  perforation along SH is perpendicular to it; the lab specimen uses ``"z"``).
* A perforation leaves the wellbore radially.  Its direction is given by
  ``azimuth`` (from +x towards +y in the horizontal plane) and ``inclination``
  (from the horizontal towards +z), or by a ``direction`` vector, then turned
  by ``phase`` about the wellbore axis (right-handed).  ``entry`` is the
  position of its axis along the wellbore axis, from the block centre.
* Sections are circles of diameters ``d1..dn`` at stations ``0, l1,
  l1+l2, ...`` measured along the perforation axis from the wellbore wall.
* ``symmetry`` lists mirror planes through the block centre (``"x"`` is the
  plane x = 0, ...); the model keeps the positive side.  ``"auto"`` picks every
  plane the scene is symmetric about, ``"none"`` (default) keeps it whole.

2D scenes lie in the x-y plane (plane strain): a crack plate (crack along x
through the centre), a KGD strip (initial crack and fracture path along x,
injection at the origin) and a borehole in a square.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

from hfcdem.config import catalogue
from hfcdem.config.units import FieldError, join_path, parse_quantity

Vector = tuple[float, float, float]
AXES = ("x", "y", "z")
RESERVED_SECTIONS = ("rock", "stress", "fluid", "injection", "load", "solver", "output")
MAX_CELLS = 2.0e7  # estimated cell counts above this are refused as absurd

MM = 1e-3


class SceneError(FieldError):
    """A scene is invalid; ``path`` names the offending field."""


def axis_index(axis: str) -> int:
    """Return 0, 1, 2 for ``"x"``, ``"y"``, ``"z"``."""
    return AXES.index(axis)


def axis_vector(axis: str) -> np.ndarray:
    """Return the unit vector along ``axis``."""
    v = np.zeros(3)
    v[axis_index(axis)] = 1.0
    return v


def show_length(value: float) -> str:
    """Format a length for messages: mm below 1 m, m above."""
    return f"{value / MM:.6g} mm" if abs(value) < 1.0 else f"{value:.6g} m"


def _check_length(path: str, value: float, low: float, high: float, what: str) -> None:
    if not isinstance(value, int | float) or isinstance(value, bool) or not math.isfinite(value):
        raise SceneError(path, f"expected {what} in m, got {value!r}")
    if value <= 0.0:
        raise SceneError(path, f"{what} must be positive, got {show_length(value)}")
    if not low <= value <= high:
        raise SceneError(
            path,
            f"{show_length(value)} is outside the plausible range {show_length(low)} to "
            f"{show_length(high)} for {what} (a unit slip?)",
        )


def _check_vector(path: str, value: Sequence[float]) -> Vector:
    if len(value) != 3 or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value
    ):
        raise SceneError(path, f"expected three finite numbers, got {value!r}")
    return (float(value[0]), float(value[1]), float(value[2]))


def _check_axis(path: str, axis: str) -> None:
    if axis not in AXES:
        raise SceneError(path, f"expected one of 'x', 'y', 'z', got {axis!r}")


# ---------------------------------------------------------------------------
# Perforation tunnels
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Profile:
    """Cross-sections of a perforation tunnel: ``diameters`` at ``stations`` from the wall (m)."""

    diameters: tuple[float, ...]
    stations: tuple[float, ...]
    name: str = "custom"
    assumed: bool = False
    source: str = ""

    MIN_DIAMETER: ClassVar[float] = 0.1 * MM
    MAX_DIAMETER: ClassVar[float] = 0.5
    MAX_LENGTH: ClassVar[float] = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "diameters", tuple(self.diameters))
        object.__setattr__(self, "stations", tuple(self.stations))
        if len(self.diameters) < 2:
            raise SceneError("diameters", f"needs at least two sections, got {len(self.diameters)}")
        if len(self.stations) != len(self.diameters):
            raise SceneError(
                "stations",
                f"expected {len(self.diameters)} stations (one per diameter), "
                f"got {len(self.stations)}",
            )
        for i, d in enumerate(self.diameters):
            _check_length(
                f"diameters[{i}]", d, self.MIN_DIAMETER, self.MAX_DIAMETER, "a perforation diameter"
            )
        if self.stations[0] != 0.0:
            raise SceneError("stations[0]", "the first section must be at the wellbore wall (0 m)")
        for i in range(1, len(self.stations)):
            if not self.stations[i] > self.stations[i - 1]:
                raise SceneError(
                    f"stations[{i}]",
                    f"stations must increase, got {show_length(self.stations[i])} after "
                    f"{show_length(self.stations[i - 1])}",
                )
        _check_length("stations", self.length, 1.0 * MM, self.MAX_LENGTH, "a perforation length")

    @classmethod
    def from_lengths(
        cls, diameters: Sequence[float], lengths: Sequence[float], **kwargs: Any
    ) -> Profile:
        """Build a profile from segment lengths ``l1..l(n-1)`` instead of stations."""
        if len(lengths) != len(diameters) - 1:
            raise SceneError(
                "lengths",
                f"expected {len(diameters) - 1} segment lengths for {len(diameters)} diameters, "
                f"got {len(lengths)}",
            )
        for i, length in enumerate(lengths):
            _check_length(f"lengths[{i}]", length, 0.1 * MM, cls.MAX_LENGTH, "a segment length")
        stations = np.concatenate([[0.0], np.cumsum(lengths)])
        return cls(tuple(diameters), tuple(float(s) for s in stations), **kwargs)

    @property
    def length(self) -> float:
        """Length from the wellbore wall to the tip (m)."""
        return self.stations[-1]

    @property
    def radii(self) -> np.ndarray:
        """Section radii (m)."""
        return 0.5 * np.asarray(self.diameters)

    @property
    def max_radius(self) -> float:
        """Largest section radius (m)."""
        return float(np.max(self.radii))

    def radius_at(self, station: np.ndarray | float) -> np.ndarray:
        """Radius at ``station`` (linear between sections; the first segment extrapolated)."""
        s = np.asarray(station, dtype=float)
        r = np.interp(s, self.stations, self.radii)
        # the tunnel starts inside the wellbore as the backward extension of segment 1
        slope = (self.radii[1] - self.radii[0]) / (self.stations[1] - self.stations[0])
        return np.where(s < 0.0, self.radii[0] + slope * s, r)


def tunnel_extension(profile: Profile, wellbore_radius: float) -> tuple[float, float]:
    """Return ``(delta, radius)`` of the section that starts the tunnel inside the wellbore.

    The loft starts at station ``-delta``, on the backward extension of the first
    segment, far enough in that the whole circle lies inside the wellbore: the
    boolean cut then never sees a tangent contact, and the wall has no seam at
    the wellbore wall (a seam there pinches into sliver faces).
    """
    big_r = wellbore_radius
    delta = 0.0
    for _ in range(50):
        r = float(profile.radius_at(-delta))
        if r <= 0.0 or r >= big_r:
            break
        new = big_r - math.sqrt(big_r**2 - r**2) + 0.25 * r
        if abs(new - delta) < 1e-12 * big_r:
            break
        delta = new
    r = float(profile.radius_at(-delta))
    return delta, r


@dataclass(frozen=True)
class Perforation:
    """A perforation tunnel: its profile, unit ``direction`` and ``entry`` along the wellbore."""

    profile: Profile
    direction: Vector = (1.0, 0.0, 0.0)
    entry: float = 0.0

    def __post_init__(self) -> None:
        d = np.asarray(_check_vector("direction", self.direction))
        norm = float(np.linalg.norm(d))
        if norm < 1e-12:
            raise SceneError("direction", "must not be the zero vector")
        object.__setattr__(self, "direction", tuple(float(v) for v in d / norm))
        if not math.isfinite(self.entry):
            raise SceneError("entry", f"expected a finite length, got {self.entry!r}")

    def start(self, wellbore: Wellbore) -> np.ndarray:
        """Point where the axis meets the wellbore wall (station 0)."""
        w = axis_vector(wellbore.axis)
        return self.entry * w + wellbore.radius * np.asarray(self.direction)

    def tip(self, wellbore: Wellbore) -> np.ndarray:
        """Centre of the tip section."""
        return self.start(wellbore) + self.profile.length * np.asarray(self.direction)


# ---------------------------------------------------------------------------
# Block, wellbore, fracturable zones, mesh sizing
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Block:
    """A rectangular rock block centred at the origin; ``size`` = edge lengths (m)."""

    size: Vector

    def __post_init__(self) -> None:
        size = _check_vector("size", self.size)
        for i, edge in enumerate(size):
            _check_length(f"size[{i}]", edge, 1.0 * MM, 1000.0, "a block edge")
        object.__setattr__(self, "size", size)

    @property
    def half(self) -> np.ndarray:
        """Half edge lengths."""
        return 0.5 * np.asarray(self.size)


@dataclass(frozen=True)
class Wellbore:
    """A circular wellbore through the block centre along ``axis``."""

    diameter: float
    axis: str = "y"

    def __post_init__(self) -> None:
        _check_length("diameter", self.diameter, 1.0 * MM, 2.0, "a wellbore diameter")
        _check_axis("axis", self.axis)

    @property
    def radius(self) -> float:
        """Wellbore radius (m)."""
        return 0.5 * self.diameter


@dataclass(frozen=True)
class SphereZone:
    """Fracturable zone: a ball (a disc in 2D) of ``radius`` around ``centre``."""

    radius: float
    centre: Vector = (0.0, 0.0, 0.0)
    shape: ClassVar[str] = "sphere"

    def __post_init__(self) -> None:
        _check_length("radius", self.radius, 1e-5, 1000.0, "a zone radius")
        object.__setattr__(self, "centre", _check_vector("centre", self.centre))

    def mirror_problem(self, axis: str) -> str | None:
        """Why the zone is not symmetric about the plane ``axis`` = 0 (None if it is)."""
        if abs(self.centre[axis_index(axis)]) > 1e-12:
            return "the fracturable sphere is not centred on it"
        return None


@dataclass(frozen=True)
class TunnelZone:
    """Fracturable zone: a cylinder of ``radius`` around a perforation's axis.

    It runs from the wellbore axis to ``beyond_tip`` past the tip (default: the
    radius), so the root of the tunnel, where fractures start, is inside.
    ``perforation`` counts from 1.
    """

    radius: float
    perforation: int = 1
    beyond_tip: float | None = None
    shape: ClassVar[str] = "tunnel"

    def __post_init__(self) -> None:
        _check_length("radius", self.radius, 1e-5, 1000.0, "a zone radius")
        if isinstance(self.perforation, bool) or not isinstance(self.perforation, int):
            raise SceneError(
                "perforation", f"expected a perforation number, got {self.perforation!r}"
            )
        if self.beyond_tip is None:
            object.__setattr__(self, "beyond_tip", self.radius)
        elif not math.isfinite(self.beyond_tip) or self.beyond_tip < 0.0:
            raise SceneError("beyond_tip", f"expected a length >= 0, got {self.beyond_tip!r}")


@dataclass(frozen=True)
class SlabZone:
    """Fracturable zone: the slab ``|x[axis] - offset| <= thickness / 2``."""

    axis: str
    thickness: float
    offset: float = 0.0
    shape: ClassVar[str] = "slab"

    def __post_init__(self) -> None:
        _check_axis("axis", self.axis)
        _check_length("thickness", self.thickness, 1e-5, 1000.0, "a slab thickness")
        if not math.isfinite(self.offset):
            raise SceneError("offset", f"expected a finite length, got {self.offset!r}")

    def mirror_problem(self, axis: str) -> str | None:
        """Why the zone is not symmetric about the plane ``axis`` = 0 (None if it is)."""
        if axis == self.axis and abs(self.offset) > 1e-12:
            return "the fracturable slab is off the plane"
        return None


FracturableZone = SphereZone | TunnelZone | SlabZone


@dataclass(frozen=True)
class MeshSizing:
    """Element sizes: ``size`` at the perforation (the knob), growing to ``size_far``.

    Sizes grow linearly with the distance from the refined walls at ``grading``
    (size increase per unit distance).  Curved walls get at least
    ``circle_elements`` elements around a circle, which caps the size on thin
    tunnels.  ``wellbore_size`` defaults to ``pi D / 20`` (clamped to
    ``[size, size_far]``).  ``algorithm`` is Gmsh's 3D mesher: ``"delaunay"``
    (fast) or ``"hxt"`` (about twice as slow on one core, fewer cells for the
    same sizes and better worst elements: minimum minSICN about 0.3).
    """

    size: float
    size_far: float
    grading: float = 0.3
    circle_elements: int = 32
    wellbore_size: float | None = None
    algorithm: str = "delaunay"

    ALGORITHMS: ClassVar[dict[str, int]] = {"delaunay": 1, "hxt": 10}  # Mesh.Algorithm3D

    def __post_init__(self) -> None:
        _check_length("size", self.size, 1e-6, 1000.0, "an element size")
        _check_length("size_far", self.size_far, 1e-6, 1000.0, "an element size")
        if self.size_far < self.size:
            raise SceneError(
                "size_far",
                f"{show_length(self.size_far)} must be at least size ({show_length(self.size)})",
            )
        if not (isinstance(self.grading, int | float) and 0.02 <= self.grading <= 2.0):
            raise SceneError("grading", f"expected a number in [0.02, 2], got {self.grading!r}")
        if (
            isinstance(self.circle_elements, bool)
            or not isinstance(self.circle_elements, int)
            or not 6 <= self.circle_elements <= 512
        ):
            raise SceneError(
                "circle_elements", f"expected an integer in [6, 512], got {self.circle_elements!r}"
            )
        if self.wellbore_size is not None:
            _check_length("wellbore_size", self.wellbore_size, 1e-6, 1000.0, "an element size")
        if self.algorithm not in self.ALGORITHMS:
            raise SceneError(
                "algorithm",
                f"expected one of {', '.join(map(repr, self.ALGORITHMS))}, got {self.algorithm!r}",
            )

    def wall_size(self, diameter: float) -> float:
        """Size on a circular wall of ``diameter``: ``size`` capped to resolve the circle."""
        return min(self.size, math.pi * diameter / self.circle_elements)

    def grown(self, start: float, distance: np.ndarray) -> np.ndarray:
        """Size at ``distance`` from a wall meshed at ``start``."""
        return np.minimum(self.size_far, start + self.grading * np.asarray(distance))

    def growth_distance(self, start: float) -> float:
        """Distance over which the size grows from ``start`` to ``size_far``."""
        return max(self.size_far - start, 0.0) / self.grading


def _estimate_cells(
    sizing: MeshSizing,
    volume: float,
    refined: Sequence[tuple[float, Callable[[np.ndarray], np.ndarray]]],
    dim: int,
) -> float:
    """Rough cell count: sum over refined walls of the integral of area(rho) / h(rho)^dim.

    ``refined`` holds (wall size, measure of the offset surface at distance rho).
    Regular tetrahedra fill h^3 / 8.5, triangles 0.43 h^2.
    """
    per = 8.5 if dim == 3 else 2.3
    total = per * volume / sizing.size_far**dim
    for start, measure in refined:
        rho = np.linspace(0.0, sizing.growth_distance(start), 400)
        integrand = measure(rho) / sizing.grown(start, rho) ** dim
        total += per * float(np.sum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(rho)))
    return total


def _segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> float:
    """Shortest distance between the segments p0-p1 and q0-q1."""
    u, v, w0 = p1 - p0, q1 - q0, p0 - q0
    a, b, c, d, e = u @ u, u @ v, v @ v, u @ w0, v @ w0
    den = a * c - b * b
    s = np.clip((b * e - c * d) / den, 0.0, 1.0) if den > 1e-14 * a * c else 0.0
    t = np.clip((b * s + e) / c, 0.0, 1.0)
    s = np.clip((b * t - d) / a, 0.0, 1.0)
    return float(np.linalg.norm(w0 + s * u - t * v))


def _check_symmetry_axes(symmetry: Sequence[str], allowed: Sequence[str]) -> tuple[str, ...]:
    axes = tuple(symmetry)
    for i, axis in enumerate(axes):
        if axis not in allowed:
            raise SceneError(
                f"symmetry[{i}]", f"expected one of {', '.join(map(repr, allowed))}, got {axis!r}"
            )
    if len(set(axes)) != len(axes):
        raise SceneError("symmetry", f"lists a plane twice: {list(axes)}")
    return tuple(sorted(axes))


# ---------------------------------------------------------------------------
# Geometries
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class PerforatedBlock:
    """A rock block with a wellbore and perforation tunnels (3D)."""

    block: Block
    wellbore: Wellbore
    perforations: tuple[Perforation, ...]
    mesh: MeshSizing
    fracturable: FracturableZone | None = None
    symmetry: tuple[str, ...] = ()

    kind: ClassVar[str] = "perforated_block"
    dim: ClassVar[int] = 3

    def __post_init__(self) -> None:
        object.__setattr__(self, "perforations", tuple(self.perforations))
        object.__setattr__(self, "symmetry", _check_symmetry_axes(self.symmetry, AXES))
        self._check_wellbore()
        for k, perf in enumerate(self.perforations):
            self._check_perforation(k, perf)
        self._check_crossings()
        self._check_zone()
        self._check_mesh()
        for axis in self.symmetry:
            problem = self.mirror_problem(axis)
            if problem is not None:
                raise SceneError(
                    "symmetry", f"{axis} = 0 is not a symmetry plane of this scene: {problem}"
                )

    # -- validation -------------------------------------------------------------

    def _check_wellbore(self) -> None:
        w = axis_index(self.wellbore.axis)
        across = min(e for i, e in enumerate(self.block.size) if i != w)
        if self.wellbore.diameter > 0.5 * across:
            raise SceneError(
                "wellbore.diameter",
                f"{show_length(self.wellbore.diameter)} is too large for the block: at most half "
                f"the block edge across the wellbore ({show_length(0.5 * across)})",
            )

    def _check_perforation(self, k: int, perf: Perforation) -> None:
        path = f"perforations[{k}]"
        w = axis_vector(self.wellbore.axis)
        d = np.asarray(perf.direction)
        if abs(d @ w) > 1e-9:
            raise SceneError(
                f"{path}.direction",
                f"must be perpendicular to the wellbore axis {self.wellbore.axis} "
                f"(perforations leave the wellbore radially); got {np.round(d, 4).tolist()}",
            )
        big_r = self.wellbore.radius
        profile = perf.profile
        if profile.radii[0] > 0.8 * big_r:
            raise SceneError(
                f"{path}.diameters[0]",
                f"the entrance diameter {show_length(profile.diameters[0])} must be at most 0.8 x "
                f"the wellbore diameter ({show_length(0.8 * self.wellbore.diameter)})",
            )
        delta, r_in = tunnel_extension(profile, big_r)
        if not (0.5 * profile.radii[0] <= r_in < big_r and delta < big_r):
            raise SceneError(
                f"{path}.lengths[0]",
                "the first segment changes diameter too fast to start the tunnel inside the "
                "wellbore; add a section near the wall",
            )
        half = self.block.half
        clearance = profile.max_radius
        start = perf.start(self.wellbore)
        for i, (s, r) in enumerate(zip(profile.stations, profile.radii, strict=True)):
            centre = start + s * d
            reach = np.abs(centre) + r * np.sqrt(np.clip(1.0 - d**2, 0.0, None))
            over = reach + clearance - half
            j = int(np.argmax(over))
            if over[j] > 0.0:
                where = "tip" if i == len(profile.stations) - 1 else f"section {i + 1}"
                raise SceneError(
                    path,
                    f"the tunnel leaves the block: its {where} reaches {show_length(reach[j])} "
                    f"from the centre along {AXES[j]}, the block ends at {show_length(half[j])} "
                    f"and a clearance of {show_length(clearance)} is kept; shorten the tunnel "
                    "or enlarge the block",
                )

    def _check_crossings(self) -> None:
        for k, pk in enumerate(self.perforations):
            for j in range(k):
                pj = self.perforations[j]
                gap = _segment_distance(
                    pk.start(self.wellbore),
                    pk.tip(self.wellbore),
                    pj.start(self.wellbore),
                    pj.tip(self.wellbore),
                )
                need = pk.profile.max_radius + pj.profile.max_radius
                if gap <= need:
                    raise SceneError(
                        f"perforations[{k}]",
                        f"intersects perforation {j + 1}: their axes come within "
                        f"{show_length(gap)}, their radii add up to {show_length(need)}",
                    )

    def _check_zone(self) -> None:
        zone = self.fracturable
        if isinstance(zone, TunnelZone):
            n = len(self.perforations)
            if not 1 <= zone.perforation <= n:
                raise SceneError(
                    "fracturable.perforation", f"expected 1..{n}, got {zone.perforation}"
                )
            r_max = self.perforations[zone.perforation - 1].profile.max_radius
            if zone.radius <= r_max:
                raise SceneError(
                    "fracturable.radius",
                    f"{show_length(zone.radius)} lies inside the tunnel (largest radius "
                    f"{show_length(r_max)}); it must exceed it",
                )
        elif isinstance(zone, SphereZone):
            if np.any(np.abs(zone.centre) >= self.block.half):
                raise SceneError("fracturable.centre", "must lie inside the block")
        elif isinstance(zone, SlabZone):
            if abs(zone.offset) >= self.block.half[axis_index(zone.axis)]:
                raise SceneError("fracturable.offset", "the slab must cross the block")

    def _check_mesh(self) -> None:
        if not self.perforations:
            return
        thinnest = min(min(p.profile.diameters) for p in self.perforations)
        if self.mesh.size > thinnest:
            raise SceneError(
                "mesh.size",
                f"{show_length(self.mesh.size)} is coarser than the thinnest tunnel section "
                f"({show_length(thinnest)}); use at most that",
            )
        if self.mesh.size_far > float(np.min(self.block.size)):
            raise SceneError(
                "mesh.size_far",
                f"{show_length(self.mesh.size_far)} exceeds the smallest block edge "
                f"({show_length(float(np.min(self.block.size)))})",
            )
        cells = self.estimated_cells()
        if cells > MAX_CELLS:
            raise SceneError(
                "mesh.size",
                f"{show_length(self.mesh.size)} would give about {cells:.2g} cells (limit "
                f"{MAX_CELLS:.0e}); use a larger size, grading or size_far",
            )

    # -- symmetry ---------------------------------------------------------------

    def _mirror(self, perf: Perforation, axis: str) -> tuple[np.ndarray, float]:
        i = axis_index(axis)
        d = np.asarray(perf.direction).copy()
        d[i] = -d[i]
        entry = -perf.entry if axis == self.wellbore.axis else perf.entry
        return d, entry

    def mirror_problem(self, axis: str) -> str | None:
        """Why the scene is not symmetric about the plane ``axis`` = 0 (None if it is)."""
        for k, perf in enumerate(self.perforations):
            d, entry = self._mirror(perf, axis)
            if not any(
                q.profile.diameters == perf.profile.diameters
                and np.allclose(q.profile.stations, perf.profile.stations)
                and np.allclose(q.direction, d, atol=1e-9)
                and abs(q.entry - entry) < 1e-9
                for q in self.perforations
            ):
                return f"perforation {k + 1} has no mirror image"
        zone = self.fracturable
        if isinstance(zone, TunnelZone):
            if self.relation(zone.perforation - 1, axis) != "cut":
                return "the fracturable tunnel zone's perforation does not lie in the plane"
        elif zone is not None:
            return zone.mirror_problem(axis)
        return None

    def symmetric_axes(self) -> tuple[str, ...]:
        """Every plane through the centre the scene is symmetric about."""
        return tuple(a for a in AXES if self.mirror_problem(a) is None)

    def relation(self, k: int, axis: str) -> str:
        """How perforation ``k`` (from 0) meets the plane ``axis`` = 0: cut, kept or dropped."""
        perf = self.perforations[k]
        d, entry = self._mirror(perf, axis)
        if np.allclose(d, perf.direction, atol=1e-9) and abs(entry - perf.entry) < 1e-9:
            return "cut"
        middle = 0.5 * (perf.start(self.wellbore) + perf.tip(self.wellbore))
        return "kept" if middle[axis_index(axis)] > 0.0 else "dropped"

    def kept_fraction(self, k: int) -> float:
        """Share of perforation ``k`` (from 0) in the model: 1, 1/2, 1/4, or 0 if dropped."""
        fraction = 1.0
        for axis in self.symmetry:
            rel = self.relation(k, axis)
            fraction *= {"cut": 0.5, "kept": 1.0, "dropped": 0.0}[rel]
        return fraction

    @property
    def model_fraction(self) -> float:
        """Share of the full block kept by the symmetry planes."""
        return 0.5 ** len(self.symmetry)

    # -- sizes ------------------------------------------------------------------

    @property
    def wellbore_size(self) -> float:
        """Element size on the wellbore wall away from the perforations."""
        if self.mesh.wellbore_size is not None:
            return self.mesh.wellbore_size
        natural = math.pi * self.wellbore.diameter / 20.0
        return min(self.mesh.size_far, max(self.mesh.size, natural))

    def estimated_cells(self) -> float:
        """Rough number of tetrahedra the sizing gives (for refusing absurd sizes early)."""
        refined: list[tuple[float, Callable[[np.ndarray], np.ndarray]]] = []
        for k, perf in enumerate(self.perforations):
            frac = self.kept_fraction(k) if self.symmetry else 1.0
            if frac == 0.0:
                continue
            r = float(np.mean(perf.profile.radii))
            length = perf.profile.length

            def tube(
                rho: np.ndarray, r: float = r, length: float = length, frac: float = frac
            ) -> np.ndarray:
                return frac * (2.0 * np.pi * (r + rho) * length + 2.0 * np.pi * (r + rho) ** 2)

            refined.append((self.mesh.wall_size(min(perf.profile.diameters)), tube))
        big_r = self.wellbore.radius
        length_w = self.block.size[axis_index(self.wellbore.axis)]
        frac_w = self.model_fraction

        def wellbore(rho: np.ndarray) -> np.ndarray:
            return frac_w * 2.0 * np.pi * (big_r + rho) * length_w

        refined.append((self.wellbore_size, wellbore))
        volume = float(np.prod(self.block.size)) * self.model_fraction
        return _estimate_cells(self.mesh, volume, refined, 3)


@dataclass(frozen=True)
class Plate:
    """A rectangular 2D plate centred at the origin."""

    width: float
    height: float

    def __post_init__(self) -> None:
        _check_length("width", self.width, 1.0 * MM, 1.0e4, "a plate width")
        _check_length("height", self.height, 1.0 * MM, 1.0e4, "a plate height")

    @property
    def half(self) -> np.ndarray:
        """Half sizes (x, y, 0)."""
        return np.array([0.5 * self.width, 0.5 * self.height, 0.0])


@dataclass(frozen=True)
class Crack:
    """A straight crack along x through the origin (total ``length``).

    ``path_length`` (KGD strip only) is the total length of the line along which
    the fracture is expected to run; it is embedded in the mesh and tagged.
    """

    length: float
    path_length: float | None = None

    def __post_init__(self) -> None:
        _check_length("length", self.length, 1e-5, 1.0e4, "a crack length")
        if self.path_length is not None:
            _check_length("path_length", self.path_length, 1e-5, 1.0e4, "a path length")
            if self.path_length < self.length:
                raise SceneError(
                    "path_length",
                    f"{show_length(self.path_length)} must be at least the crack length "
                    f"({show_length(self.length)})",
                )


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


def _plate_fraction(symmetry: tuple[str, ...]) -> float:
    return 0.5 ** len(symmetry)


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
        object.__setattr__(self, "symmetry", _check_symmetry_axes(self.symmetry, ("x", "y")))
        if self.crack.length > 0.8 * self.plate.width:
            raise SceneError("crack.length", "must be at most 0.8 x the plate width")
        _check_plate_zone(self.fracturable, self.plate)
        _check_plate_symmetry(self, {"y": _CRACK_ON_PLANE})
        _check_plate_mesh(self, 0.25 * self.crack.length, "a quarter of the crack")

    def symmetric_axes(self) -> tuple[str, ...]:
        """Planes the scene may be cut along (the crack line itself is never one)."""
        return _plate_symmetric_axes(self.fracturable, ("x",))

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        frac = _plate_fraction(self.symmetry)
        a = self.crack.length

        def around(rho: np.ndarray) -> np.ndarray:
            return frac * (2.0 * a + 2.0 * np.pi * rho)

        area = self.plate.width * self.plate.height * frac
        return _estimate_cells(self.mesh, area, [(self.mesh.size, around)], 2)


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

    def __post_init__(self) -> None:
        object.__setattr__(self, "symmetry", _check_symmetry_axes(self.symmetry, ("x", "y")))
        if self.crack.path_length is None:
            object.__setattr__(self, "crack", Crack(self.crack.length, self.crack.length))
        path = self.crack.path_length
        assert path is not None
        if path > 0.9 * self.plate.width:
            raise SceneError("crack.path_length", "must be at most 0.9 x the plate width")
        _check_plate_zone(self.fracturable, self.plate)
        _check_plate_symmetry(self, {"y": _CRACK_ON_PLANE})
        _check_plate_mesh(self, 0.5 * self.crack.length, "half the initial crack")

    def symmetric_axes(self) -> tuple[str, ...]:
        """Planes the scene may be cut along."""
        return _plate_symmetric_axes(self.fracturable, ("x",))

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        frac = _plate_fraction(self.symmetry)
        path = self.crack.path_length or self.crack.length

        def around(rho: np.ndarray) -> np.ndarray:
            return frac * (2.0 * path + 2.0 * np.pi * rho)

        area = self.plate.width * self.plate.height * frac
        return _estimate_cells(self.mesh, area, [(self.mesh.size, around)], 2)


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
        object.__setattr__(self, "symmetry", _check_symmetry_axes(self.symmetry, ("x", "y")))
        if self.wellbore.diameter > 0.5 * min(self.plate.width, self.plate.height):
            raise SceneError(
                "wellbore.diameter",
                f"{show_length(self.wellbore.diameter)} is too large: at most half the plate",
            )
        _check_plate_zone(self.fracturable, self.plate)
        _check_plate_symmetry(self, {})
        _check_plate_mesh(self, self.wellbore.diameter, "the borehole")

    @property
    def wall_size(self) -> float:
        """Element size on the borehole wall."""
        return self.mesh.wall_size(self.wellbore.diameter)

    def symmetric_axes(self) -> tuple[str, ...]:
        """Planes the scene may be cut along."""
        return _plate_symmetric_axes(self.fracturable, ("x", "y"))

    def estimated_cells(self) -> float:
        """Rough number of triangles."""
        frac = _plate_fraction(self.symmetry)
        big_r = self.wellbore.radius

        def around(rho: np.ndarray) -> np.ndarray:
            return frac * 2.0 * np.pi * (big_r + rho)

        area = self.plate.width * self.plate.height * frac
        return _estimate_cells(self.mesh, area, [(self.wall_size, around)], 2)


Geometry = PerforatedBlock | CrackPlate | KGDStrip | BoreholeSquare


@dataclass(frozen=True)
class Scene:
    """A named scene: its geometry and, when the file states them, its physics."""

    name: str
    geometry: Geometry
    description: str = ""
    catalogue: str | None = None
    resolution: str = "default"
    source: str | None = None
    ignored_sections: tuple[str, ...] = field(default=())
    physics: Any = None  # hfcdem.config.physics.Physics when the file has physics sections

    def __post_init__(self) -> None:
        if not self.name or not all(c.isalnum() or c in "-_." for c in self.name):
            raise SceneError(
                "name", f"expected letters, digits, '-', '_' or '.', got {self.name!r}"
            )

    @property
    def assumed_profiles(self) -> tuple[str, ...]:
        """Names of the assumed (not from the paper's tables) profiles in the scene."""
        geom = self.geometry
        if not isinstance(geom, PerforatedBlock):
            return ()
        return tuple(sorted({p.profile.name for p in geom.perforations if p.profile.assumed}))


# ---------------------------------------------------------------------------
# TOML reading
# ---------------------------------------------------------------------------

_MISSING: Any = object()
T = TypeVar("T")


class TomlTable:
    """One TOML table being read: typed getters that name fields, and unknown-key checks."""

    def __init__(self, data: Any, path: str) -> None:
        if not isinstance(data, Mapping):
            raise SceneError(path, f"expected a table, got {data!r}")
        self.data = dict(data)
        self.path = path
        self.used: set[str] = set()

    def sub(self, key: str) -> str:
        return join_path(self.path, key)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = _MISSING, expected: str = "a value") -> Any:
        self.used.add(key)
        if key in self.data:
            return self.data[key]
        if default is _MISSING:
            raise SceneError(self.sub(key), f"missing; expected {expected}")
        return default

    def quantity(self, key: str, dimension: str, default: Any = _MISSING) -> Any:
        from hfcdem.config.units import EXAMPLES

        value = self.raw(key, default, f"a {dimension} such as '{EXAMPLES[dimension]}'")
        if value is default and default is not _MISSING:
            return default
        return parse_quantity(value, dimension, self.sub(key))

    def quantities(self, key: str, dimension: str, default: Any = _MISSING) -> Any:
        value = self.raw(key, default, f"a list of {dimension}s")
        if value is default and default is not _MISSING:
            return default
        if not isinstance(value, list):
            raise SceneError(self.sub(key), f"expected a list of {dimension}s, got {value!r}")
        return tuple(
            parse_quantity(v, dimension, f"{self.sub(key)}[{i}]") for i, v in enumerate(value)
        )

    def number(self, key: str, default: Any = _MISSING, integer: bool = False) -> Any:
        what = "an integer" if integer else "a number"
        value = self.raw(key, default, what)
        if value is default and default is not _MISSING:
            return default
        ok = isinstance(value, int) if integer else isinstance(value, int | float)
        if isinstance(value, bool) or not ok:
            raise SceneError(self.sub(key), f"expected {what} (no unit), got {value!r}")
        return value

    def string(self, key: str, default: Any = _MISSING, choices: Sequence[str] = ()) -> Any:
        value = self.raw(key, default, "a string")
        if value is default and default is not _MISSING:
            return default
        if not isinstance(value, str):
            raise SceneError(self.sub(key), f"expected a string, got {value!r}")
        if choices and value not in choices:
            raise SceneError(
                self.sub(key), f"expected one of {', '.join(map(repr, choices))}, got {value!r}"
            )
        return value

    def table(self, key: str) -> TomlTable | None:
        value = self.raw(key, None)
        return None if value is None else TomlTable(value, self.sub(key))

    def tables(self, key: str) -> list[TomlTable]:
        value = self.raw(key, [])
        if not isinstance(value, list):
            raise SceneError(self.sub(key), f"expected an array of tables, got {value!r}")
        return [TomlTable(v, f"{self.sub(key)}[{i}]") for i, v in enumerate(value)]

    def finish(self, extra: Sequence[str] = ()) -> None:
        unknown = sorted(set(self.data) - self.used - set(extra))
        if unknown:
            known = ", ".join(sorted(self.used | set(extra)))
            raise SceneError(self.sub(unknown[0]), f"unknown key; this table takes: {known}")


def _build(path: str, make: Callable[..., T], *args: Any, **kwargs: Any) -> T:
    """Call ``make`` and prefix the field path of any validation error with ``path``."""
    try:
        return make(*args, **kwargs)
    except FieldError as exc:
        raise exc.within(path) from None


_REPLACED_WHOLE = ("fracturable",)  # a zone of another shape shares no keys


def _merge(base: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    """Deep-merge ``over`` onto ``base``: tables merge, anything else is replaced."""
    out = dict(base)
    for key, value in over.items():
        if key in _REPLACED_WHOLE:
            out[key] = value
        elif isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


_PROFILE_KEYS = ("profile", "diameters", "lengths", "diameter", "length")
_DIRECTION_KEYS = ("azimuth", "inclination", "direction", "phase")


def _read_profile(t: TomlTable) -> Profile:
    name = t.string("profile", None, catalogue.profile_names())
    explicit = [k for k in ("diameters", "lengths", "diameter", "length") if t.has(k)]
    if any(k in explicit for k in ("diameter", "length")) and any(
        k in explicit for k in ("diameters", "lengths")
    ):
        raise SceneError(t.path, "give either diameters and lengths, or diameter and length")
    base = catalogue.lookup_profile(name) if name else None
    if base is None and not explicit:
        raise SceneError(
            t.path,
            "give a profile (one of " + ", ".join(catalogue.profile_names()) + ") or "
            "diameters and lengths",
        )
    if t.has("diameter") or t.has("length"):
        d = t.quantity("diameter", "length")
        length = t.quantity("length", "length")
        return _build(t.path, Profile.from_lengths, (d, d), (length,), name="cylinder")
    if base is not None:
        d_default = tuple(v * MM for v in base["diameters_mm"])
        l_default = tuple(v * MM for v in base["lengths_mm"])
    else:
        d_default = l_default = _MISSING
    diameters = t.quantities("diameters", "length", d_default)
    lengths = t.quantities("lengths", "length", l_default)
    changed = base is not None and bool(explicit)
    assumed = bool(base and base["assumed"]) and not {"diameters", "lengths"} <= set(explicit)
    label = (name or "custom") + (" (modified)" if changed else "")
    source = "user sections" if base is None else base["source"]
    if changed:
        source = f"{source}; {' and '.join(explicit)} given in the scene"
    return _build(
        t.path,
        Profile.from_lengths,
        diameters,
        lengths,
        name=label,
        assumed=assumed,
        source=source,
    )


def _read_direction(t: TomlTable, wellbore: Wellbore, phase_offset: float = 0.0) -> Vector:
    if t.has("direction") and (t.has("azimuth") or t.has("inclination")):
        raise SceneError(t.path, "give either direction or azimuth/inclination, not both")
    if t.has("direction"):
        raw = t.raw("direction")
        if not isinstance(raw, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in raw
        ):
            raise SceneError(t.sub("direction"), f"expected three numbers, got {raw!r}")
        v = np.asarray(_build(t.sub("direction"), _check_vector, "", raw))
    else:
        az = t.quantity("azimuth", "angle", 0.0)
        inc = t.quantity("inclination", "angle", 0.0)
        v = np.array([math.cos(inc) * math.cos(az), math.cos(inc) * math.sin(az), math.sin(inc)])
    phase = t.quantity("phase", "angle", 0.0) + phase_offset
    return _rotate(v, axis_vector(wellbore.axis), phase)


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> Vector:
    """Rodrigues rotation of ``v`` by ``angle`` about the unit ``axis``."""
    c, s = math.cos(angle), math.sin(angle)
    out = v * c + np.cross(axis, v) * s + axis * (axis @ v) * (1.0 - c)
    out[np.abs(out) < 1e-15] = 0.0
    return (float(out[0]), float(out[1]), float(out[2]))


def _read_perforation(t: TomlTable, wellbore: Wellbore) -> Perforation:
    profile = _read_profile(t)
    direction = _read_direction(t, wellbore)
    entry = t.quantity("entry", "length", 0.0)
    t.finish()
    return _build(t.path, Perforation, profile, direction, entry)


def _read_cluster(t: TomlTable, wellbore: Wellbore) -> list[Perforation]:
    count = t.number("count", integer=True)
    if not 1 <= count <= 100:
        raise SceneError(t.sub("count"), f"expected 1..100 perforations, got {count}")
    spacing = t.quantity("spacing", "length", 0.0)
    if spacing < 0.0:
        raise SceneError(t.sub("spacing"), f"must not be negative, got {show_length(spacing)}")
    phasing = t.quantity("phasing", "angle", 0.0)
    first = t.quantity("first_phase", "angle", 0.0)
    centre = t.quantity("entry", "length", 0.0)
    if t.has("phase"):
        raise SceneError(t.sub("phase"), "a cluster takes first_phase and phasing")
    profile = _read_profile(t)
    out = []
    for k in range(count):
        direction = _read_direction(t, wellbore, first + k * phasing)
        entry = centre + (k - 0.5 * (count - 1)) * spacing
        out.append(_build(t.path, Perforation, profile, direction, entry))
    t.finish(extra=("phase",))
    return out


def _read_zone(t: TomlTable | None) -> FracturableZone | None:
    if t is None:
        return None
    shape = t.string("shape", choices=("sphere", "tunnel", "slab"))
    zone: FracturableZone
    if shape == "sphere":
        centre = t.quantities("centre", "length", (0.0, 0.0, 0.0))
        zone = _build(t.path, SphereZone, t.quantity("radius", "length"), centre)
    elif shape == "tunnel":
        zone = _build(
            t.path,
            TunnelZone,
            t.quantity("radius", "length"),
            t.number("perforation", 1, integer=True),
            t.quantity("beyond_tip", "length", None),
        )
    else:
        zone = _build(
            t.path,
            SlabZone,
            t.string("axis", choices=AXES),
            t.quantity("thickness", "length"),
            t.quantity("offset", "length", 0.0),
        )
    t.finish()
    return zone


_MESH_KEYS = (
    "size",
    "size_far",
    "grading",
    "circle_elements",
    "wellbore_size",
    "algorithm",
    "resolutions",
)


def _read_mesh(
    t: TomlTable | None, path: str, resolution: str | None, size: float | None
) -> tuple[MeshSizing, str]:
    if t is None:
        raise SceneError(join_path(path, "mesh"), "missing; expected a table with at least size")
    chosen = "default"
    if resolution is not None and resolution != "default":
        named = t.data.get("resolutions", {})
        if not isinstance(named, Mapping) or resolution not in named:
            have = ", ".join(["default", *sorted(named)]) if isinstance(named, Mapping) else ""
            raise SceneError(
                t.sub("resolutions"), f"no resolution named {resolution!r}; this scene has: {have}"
            )
        override = named[resolution]
        if not isinstance(override, Mapping):
            raise SceneError(t.sub(f"resolutions.{resolution}"), "expected a table")
        bad = sorted(set(override) - set(_MESH_KEYS[:-1]))
        if bad:
            raise SceneError(t.sub(f"resolutions.{resolution}.{bad[0]}"), "unknown key")
        t = TomlTable({**t.data, **override}, t.path)
        chosen = resolution
    t.raw("resolutions", None)
    value = t.quantity("size", "length")
    if size is not None:
        value, chosen = size, f"{chosen}, size {show_length(size)}"
    kwargs: dict[str, Any] = {
        "size": value,
        "size_far": t.quantity("size_far", "length"),
        "grading": t.number("grading", 0.3),
        "circle_elements": t.number("circle_elements", 32, integer=True),
        "wellbore_size": t.quantity("wellbore_size", "length", None),
        "algorithm": t.string("algorithm", "delaunay"),
    }
    t.finish()
    return _build(t.path, MeshSizing, **kwargs), chosen


def _read_symmetry(t: TomlTable) -> str | tuple[str, ...]:
    value = t.raw("symmetry", "none")
    if value in ("none", "auto"):
        return str(value)
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise SceneError(
            t.sub("symmetry"), f"expected 'none', 'auto' or a list such as ['z'], got {value!r}"
        )
    return tuple(value)


_KIND_KEYS = {
    "perforated_block": ("block", "wellbore", "perforations", "cluster"),
    "crack_plate": ("plate", "crack"),
    "kgd_strip": ("plate", "crack"),
    "borehole_plate": ("plate", "wellbore"),
}


def parse_geometry(
    data: Mapping[str, Any],
    path: str = "geometry",
    resolution: str | None = None,
    size: float | None = None,
) -> tuple[Geometry, str | None, str]:
    """Read a ``[geometry]`` table; return (geometry, catalogue name, resolution used).

    ``catalogue = NAME`` starts from a preset (:mod:`hfcdem.config.catalogue`) that the
    other keys override (tables merge key by key; lists and the ``fracturable``
    table are replaced whole).
    ``resolution`` picks a named ``mesh.resolutions`` entry; ``size`` (m)
    overrides ``mesh.size``.
    """
    top = TomlTable(data, path)
    name = top.string("catalogue", None)
    if name is not None:
        if name not in catalogue.PRESETS:
            raise SceneError(
                top.sub("catalogue"),
                f"unknown entry {name!r}; the catalogue has: {', '.join(catalogue.preset_names())}",
            )
        preset = catalogue.lookup_preset(name)
        if "kind" in data and data["kind"] != preset["kind"]:
            raise SceneError(
                top.sub("kind"),
                f"catalogue entry {name!r} is a {preset['kind']}, not {data['kind']!r}",
            )
        merged = _merge(preset, {k: v for k, v in data.items() if k != "catalogue"})
        top = TomlTable({**merged, "catalogue": name}, path)
        top.used.add("catalogue")
    kind = top.string("kind", choices=tuple(_KIND_KEYS))
    symmetry = _read_symmetry(top)
    zone = _read_zone(top.table("fracturable"))
    sizing, chosen = _read_mesh(top.table("mesh"), path, resolution, size)
    axes = () if isinstance(symmetry, str) else symmetry
    geom: Geometry
    if kind == "perforated_block":
        geom = _read_block_scene(top, sizing, zone, axes)
    else:
        geom = _read_plate_scene(top, kind, sizing, zone, axes)
    if symmetry == "auto":
        geom = dataclasses.replace(geom, symmetry=geom.symmetric_axes())
    top.finish()
    return geom, name, chosen


def _read_block_scene(
    top: TomlTable, sizing: MeshSizing, zone: FracturableZone | None, axes: tuple[str, ...]
) -> PerforatedBlock:
    bt = top.table("block")
    if bt is None:
        raise SceneError(top.sub("block"), "missing; expected a table with size")
    raw = bt.raw("size", expected="a length such as '2 m' or a list of three")
    size = (
        bt.quantities("size", "length")
        if isinstance(raw, list)
        else (bt.quantity("size", "length"),) * 3
    )
    bt.finish()
    block = _build(bt.path, Block, size)
    wt = top.table("wellbore")
    if wt is None:
        raise SceneError(top.sub("wellbore"), "missing; expected a table with diameter")
    wellbore = _build(
        wt.path,
        Wellbore,
        wt.quantity("diameter", "length"),
        wt.string("axis", "y", AXES),
    )
    wt.finish()
    perforations = [_read_perforation(t, wellbore) for t in top.tables("perforations")]
    ct = top.table("cluster")
    if ct is not None:
        perforations += _read_cluster(ct, wellbore)
    return _build(
        top.path,
        PerforatedBlock,
        block,
        wellbore,
        tuple(perforations),
        sizing,
        zone,
        axes,
    )


def _read_plate_scene(
    top: TomlTable,
    kind: str,
    sizing: MeshSizing,
    zone: FracturableZone | None,
    axes: tuple[str, ...],
) -> Geometry:
    for key in ("block", "perforations", "cluster"):
        if top.has(key):
            raise SceneError(top.sub(key), f"not used by a {kind}")
    pt = top.table("plate")
    if pt is None:
        raise SceneError(top.sub("plate"), "missing; expected a table with width and height")
    plate = _build(pt.path, Plate, pt.quantity("width", "length"), pt.quantity("height", "length"))
    pt.finish()
    if kind == "borehole_plate":
        wt = top.table("wellbore")
        if wt is None:
            raise SceneError(top.sub("wellbore"), "missing; expected a table with diameter")
        wellbore = _build(wt.path, Wellbore, wt.quantity("diameter", "length"), "z")
        wt.finish()
        return _build(top.path, BoreholeSquare, plate, wellbore, sizing, zone, axes)
    ct = top.table("crack")
    if ct is None:
        raise SceneError(top.sub("crack"), "missing; expected a table with length")
    length = ct.quantity("length", "length")
    path_length = ct.quantity("path_length", "length", None) if kind == "kgd_strip" else None
    ct.finish()
    crack = _build(ct.path, Crack, length, path_length)
    if kind == "crack_plate":
        return _build(top.path, CrackPlate, plate, crack, sizing, zone, axes)
    return _build(top.path, KGDStrip, plate, crack, sizing, zone, axes)


def parse_scene(
    data: Mapping[str, Any],
    default_name: str = "scene",
    resolution: str | None = None,
    size: float | None = None,
    source: str | None = None,
) -> Scene:
    """Build a :class:`Scene` from a parsed TOML document; any invalid field raises SceneError."""
    try:
        return _parse_scene(data, default_name, resolution, size, source)
    except SceneError:
        raise
    except FieldError as exc:  # unit errors are scene errors too
        raise SceneError(exc.path, exc.reason) from None


def _parse_scene(
    data: Mapping[str, Any],
    default_name: str,
    resolution: str | None,
    size: float | None,
    source: str | None,
) -> Scene:
    top = TomlTable(data, "")
    name = top.string("name", default_name)
    description = top.string("description", "")
    gt = top.table("geometry")
    if gt is None:
        raise SceneError("geometry", "missing; every scene needs a [geometry] table")
    geometry, preset, chosen = parse_geometry(gt.data, "geometry", resolution, size)
    from hfcdem.config.physics import PHYSICS_SECTIONS, parse_physics

    # [output] alone (a geometry-only scene) does not ask for physics: it is ignored
    wanted = any(k in data for k in PHYSICS_SECTIONS if k != "output")
    physics = parse_physics(data) if wanted else None
    ignored = tuple(
        k for k in RESERVED_SECTIONS if k in data and (k not in PHYSICS_SECTIONS or not wanted)
    )
    top.finish(extra=RESERVED_SECTIONS)
    return _build(
        "",
        Scene,
        name=name,
        geometry=geometry,
        description=description,
        catalogue=preset,
        resolution=chosen,
        source=source,
        ignored_sections=ignored,
        physics=physics,
    )


def set_field(doc: dict[str, Any], dotted: str, value: Any) -> None:
    """Set ``dotted`` in a scene document; a number indexes an array (``perforations.0``)."""
    keys = dotted.split(".")
    node: Any = doc
    for depth, key in enumerate(keys):
        last = depth == len(keys) - 1
        if isinstance(node, list):
            if not (key.isdigit() and int(key) < len(node)):
                raise SceneError(dotted, f"{key!r}: expected an index below {len(node)}")
            if last:
                node[int(key)] = value
            else:
                node = node[int(key)]
            continue
        if not isinstance(node, dict):
            raise SceneError(dotted, f"{keys[depth - 1]!r} is not a table in the scene")
        if last:
            node[key] = value
        else:
            node = node.setdefault(key, {})


def load_scene(
    path: str | Path,
    resolution: str | None = None,
    size: float | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> Scene:
    """Read and validate the scene file ``path`` (TOML).

    ``overrides`` maps dotted keys to values that replace the file's
    (``{"injection.duration": "120 s"}``), validated like the file.
    """
    p = Path(path)
    try:
        with p.open("rb") as fh:
            data = tomllib.load(fh)
    except OSError as exc:
        raise SceneError("", f"cannot read scene file {p}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("", f"{p} is not valid TOML: {exc}") from None
    for key, value in (overrides or {}).items():
        set_field(data, key, value)
    try:
        return parse_scene(data, p.stem, resolution, size, str(p))
    except FieldError as exc:
        raise SceneError(f"{p.name}: {exc.path}" if exc.path else p.name, exc.reason) from None


__all__ = [
    "AXES",
    "MAX_CELLS",
    "MM",
    "RESERVED_SECTIONS",
    "Block",
    "BoreholeSquare",
    "Crack",
    "CrackPlate",
    "FracturableZone",
    "Geometry",
    "KGDStrip",
    "MeshSizing",
    "PerforatedBlock",
    "Perforation",
    "Plate",
    "Profile",
    "Scene",
    "SceneError",
    "SlabZone",
    "SphereZone",
    "T",
    "TunnelZone",
    "Vector",
    "Wellbore",
    "axis_index",
    "axis_vector",
    "load_scene",
    "parse_geometry",
    "parse_scene",
    "set_field",
    "show_length",
    "tunnel_extension",
]
