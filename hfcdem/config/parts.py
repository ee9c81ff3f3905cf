"""The parts a scene geometry is made of: frozen dataclasses that validate their fields.

Profiles, perforations, the block, the wellbore, fracturable zones, mesh sizing,
plates and cracks, in SI units; each refuses an implausible value by the name
of its field.  :mod:`hfcdem.config.geometry` assembles them into the scene
geometries and checks how they fit together.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from hfcdem.config.fingerprint import fingerprinted
from hfcdem.config.tables import SceneError

Vector = tuple[float, float, float]
AXES = ("x", "y", "z")
MM = 1e-3


# axis helpers: validation needs them too (a perforation leaves the wellbore radially)
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


def check_length(path: str, value: float, low: float, high: float, what: str) -> None:
    """Refuse a length that is not a finite positive number within ``[low, high]``."""
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


def check_vector(path: str, value: Sequence[float]) -> Vector:
    """Return ``value`` as three floats, or refuse it."""
    if len(value) != 3 or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value
    ):
        raise SceneError(path, f"expected three finite numbers, got {value!r}")
    return (float(value[0]), float(value[1]), float(value[2]))


def check_axis(path: str, axis: str) -> None:
    """Refuse anything but ``"x"``, ``"y"``, ``"z"``."""
    if axis not in AXES:
        raise SceneError(path, f"expected one of 'x', 'y', 'z', got {axis!r}")


# ---------------------------------------------------------------------------
# Perforation tunnels
# ---------------------------------------------------------------------------


@fingerprinted
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
            check_length(
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
        check_length("stations", self.length, 1.0 * MM, self.MAX_LENGTH, "a perforation length")

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
            check_length(f"lengths[{i}]", length, 0.1 * MM, cls.MAX_LENGTH, "a segment length")
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

    Computed here, not in :mod:`hfcdem.mesh`: validation refuses a first
    segment too steep for this start, and the mesher must loft from the same one.
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


@fingerprinted
@dataclass(frozen=True)
class Perforation:
    """A perforation tunnel: its profile, unit ``direction`` and ``entry`` along the wellbore."""

    profile: Profile
    direction: Vector = (1.0, 0.0, 0.0)
    entry: float = 0.0

    def __post_init__(self) -> None:
        d = np.asarray(check_vector("direction", self.direction))
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


@fingerprinted
@dataclass(frozen=True)
class Block:
    """A rectangular rock block centred at the origin; ``size`` = edge lengths (m)."""

    size: Vector

    def __post_init__(self) -> None:
        size = check_vector("size", self.size)
        for i, edge in enumerate(size):
            check_length(f"size[{i}]", edge, 1.0 * MM, 1000.0, "a block edge")
        object.__setattr__(self, "size", size)

    @property
    def half(self) -> np.ndarray:
        """Half edge lengths."""
        return 0.5 * np.asarray(self.size)


@fingerprinted
@dataclass(frozen=True)
class Wellbore:
    """A circular wellbore through the block centre along ``axis``."""

    diameter: float
    axis: str = "y"

    def __post_init__(self) -> None:
        check_length("diameter", self.diameter, 1.0 * MM, 2.0, "a wellbore diameter")
        check_axis("axis", self.axis)

    @property
    def radius(self) -> float:
        """Wellbore radius (m)."""
        return 0.5 * self.diameter


@fingerprinted
@dataclass(frozen=True)
class SphereZone:
    """Fracturable zone: a ball (a disc in 2D) of ``radius`` around ``centre``."""

    radius: float
    centre: Vector = (0.0, 0.0, 0.0)
    shape: ClassVar[str] = "sphere"

    def __post_init__(self) -> None:
        check_length("radius", self.radius, 1e-5, 1000.0, "a zone radius")
        object.__setattr__(self, "centre", check_vector("centre", self.centre))

    def mirror_problem(self, axis: str) -> str | None:
        """Why the zone is not symmetric about the plane ``axis`` = 0 (None if it is)."""
        if abs(self.centre[axis_index(axis)]) > 1e-12:
            return "the fracturable sphere is not centred on it"
        return None


@fingerprinted
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
        check_length("radius", self.radius, 1e-5, 1000.0, "a zone radius")
        if isinstance(self.perforation, bool) or not isinstance(self.perforation, int):
            raise SceneError(
                "perforation", f"expected a perforation number, got {self.perforation!r}"
            )
        if self.beyond_tip is None:
            object.__setattr__(self, "beyond_tip", self.radius)
        elif not math.isfinite(self.beyond_tip) or self.beyond_tip < 0.0:
            raise SceneError("beyond_tip", f"expected a length >= 0, got {self.beyond_tip!r}")


@fingerprinted
@dataclass(frozen=True)
class SlabZone:
    """Fracturable zone: the slab ``|x[axis] - offset| <= thickness / 2``."""

    axis: str
    thickness: float
    offset: float = 0.0
    shape: ClassVar[str] = "slab"

    def __post_init__(self) -> None:
        check_axis("axis", self.axis)
        check_length("thickness", self.thickness, 1e-5, 1000.0, "a slab thickness")
        if not math.isfinite(self.offset):
            raise SceneError("offset", f"expected a finite length, got {self.offset!r}")

    def mirror_problem(self, axis: str) -> str | None:
        """Why the zone is not symmetric about the plane ``axis`` = 0 (None if it is)."""
        if axis == self.axis and abs(self.offset) > 1e-12:
            return "the fracturable slab is off the plane"
        return None


FracturableZone = SphereZone | TunnelZone | SlabZone


@fingerprinted
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

    Two options shape the verified 2D set-ups: ``wall_rings`` structured
    layers of the wall size around a borehole (radial facets at every angle
    step, including along the axes, where a breakdown starts) and
    ``path_size``, the exact facet length along a KGD strip's crack and path
    (the grading then starts from it).  ``size_integration`` is how Gmsh turns
    the sizes into a mesh: ``"fast"`` samples the distance from a refined wall
    at about two points per wall size across the model (50 to 2000 per curve)
    and integrates sizes along curves to 1e-4; ``"exact"`` samples 400 points
    per curve and keeps Gmsh's full precision (slower in 3D; the meshes of the
    CDEM and KGD verification tables).
    """

    size: float
    size_far: float
    grading: float = 0.3
    circle_elements: int = 32
    wellbore_size: float | None = None
    algorithm: str = "delaunay"
    wall_rings: int = 0
    path_size: float | None = None
    size_integration: str = "fast"

    ALGORITHMS: ClassVar[dict[str, int]] = {"delaunay": 1, "hxt": 10}  # Mesh.Algorithm3D
    SIZE_INTEGRATIONS: ClassVar[tuple[str, ...]] = ("fast", "exact")
    MAX_WALL_RINGS: ClassVar[int] = 200

    def __post_init__(self) -> None:
        check_length("size", self.size, 1e-6, 1000.0, "an element size")
        check_length("size_far", self.size_far, 1e-6, 1000.0, "an element size")
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
            check_length("wellbore_size", self.wellbore_size, 1e-6, 1000.0, "an element size")
        if self.algorithm not in self.ALGORITHMS:
            raise SceneError(
                "algorithm",
                f"expected one of {', '.join(map(repr, self.ALGORITHMS))}, got {self.algorithm!r}",
            )
        if (
            isinstance(self.wall_rings, bool)
            or not isinstance(self.wall_rings, int)
            or not 0 <= self.wall_rings <= self.MAX_WALL_RINGS
        ):
            raise SceneError(
                "wall_rings",
                f"expected an integer in [0, {self.MAX_WALL_RINGS}], got {self.wall_rings!r}",
            )
        if self.path_size is not None:
            check_length("path_size", self.path_size, 1e-6, 1000.0, "an element size")
        if self.size_integration not in self.SIZE_INTEGRATIONS:
            raise SceneError(
                "size_integration",
                f"expected one of {', '.join(map(repr, self.SIZE_INTEGRATIONS))}, "
                f"got {self.size_integration!r}",
            )

    # one size law for both the cell estimate (which refuses absurd sizes) and the mesher
    def wall_size(self, diameter: float) -> float:
        """Size on a circular wall of ``diameter``: ``size`` capped to resolve the circle."""
        return min(self.size, math.pi * diameter / self.circle_elements)

    def grown(self, start: float, distance: np.ndarray) -> np.ndarray:
        """Size at ``distance`` from a wall meshed at ``start``."""
        return np.minimum(self.size_far, start + self.grading * np.asarray(distance))

    def growth_distance(self, start: float) -> float:
        """Distance over which the size grows from ``start`` to ``size_far``."""
        return max(self.size_far - start, 0.0) / self.grading


@fingerprinted
@dataclass(frozen=True)
class Plate:
    """A rectangular 2D plate centred at the origin."""

    width: float
    height: float

    def __post_init__(self) -> None:
        check_length("width", self.width, 1.0 * MM, 1.0e4, "a plate width")
        check_length("height", self.height, 1.0 * MM, 1.0e4, "a plate height")

    @property
    def half(self) -> np.ndarray:
        """Half sizes (x, y, 0)."""
        return np.array([0.5 * self.width, 0.5 * self.height, 0.0])


@fingerprinted
@dataclass(frozen=True)
class Crack:
    """A straight crack along x through the origin (total ``length``).

    ``path_length`` (KGD strip only) is the total length of the line along which
    the fracture is expected to run; it is embedded in the mesh and tagged.
    """

    length: float
    path_length: float | None = None

    def __post_init__(self) -> None:
        check_length("length", self.length, 1e-5, 1.0e4, "a crack length")
        if self.path_length is not None:
            check_length("path_length", self.path_length, 1e-5, 1.0e4, "a path length")
            if self.path_length < self.length:
                raise SceneError(
                    "path_length",
                    f"{show_length(self.path_length)} must be at least the crack length "
                    f"({show_length(self.length)})",
                )


# --- shared by the block and the plates (hfcdem.config.geometry, hfcdem.config.plates)

MAX_CELLS = 2.0e7  # estimated cell counts above this are refused as absurd


def estimate_cells(
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


def check_symmetry_axes(symmetry: Sequence[str], allowed: Sequence[str]) -> tuple[str, ...]:
    """Return the symmetry planes sorted, refusing unknown or repeated ones."""
    axes = tuple(symmetry)
    for i, axis in enumerate(axes):
        if axis not in allowed:
            raise SceneError(
                f"symmetry[{i}]", f"expected one of {', '.join(map(repr, allowed))}, got {axis!r}"
            )
    if len(set(axes)) != len(axes):
        raise SceneError("symmetry", f"lists a plane twice: {list(axes)}")
    return tuple(sorted(axes))


def refuse_mesh_options(sizing: MeshSizing, kind: str, keys: Sequence[str]) -> None:
    """Refuse the MeshSizing options ``keys`` that a ``kind`` scene does not use."""
    unused = {
        "wall_rings": sizing.wall_rings != 0,
        "path_size": sizing.path_size is not None,
        "size_integration": sizing.size_integration != "fast",
    }
    owner = {
        "wall_rings": "a borehole_plate",
        "path_size": "a kgd_strip",
        "size_integration": "a 2D plate",
    }
    for key in keys:
        if unused[key]:
            raise SceneError(f"mesh.{key}", f"not used by a {kind}; only {owner[key]} takes it")


__all__ = [
    "AXES",
    "MAX_CELLS",
    "MM",
    "Block",
    "Crack",
    "FracturableZone",
    "MeshSizing",
    "Perforation",
    "Plate",
    "Profile",
    "SlabZone",
    "SphereZone",
    "TunnelZone",
    "Vector",
    "Wellbore",
    "axis_index",
    "axis_vector",
    "check_axis",
    "check_length",
    "check_symmetry_axes",
    "check_vector",
    "estimate_cells",
    "refuse_mesh_options",
    "show_length",
    "tunnel_extension",
]
