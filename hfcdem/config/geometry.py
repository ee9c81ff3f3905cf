"""Scene geometries: the parts assembled, checked for fit, before Gmsh runs.

A 3D :class:`PerforatedBlock` (wellbore and perforation tunnels in a rock
block); the 2D plates live in :mod:`hfcdem.config.plates`.  Each refuses a
scene that cannot be meshed (tunnels leaving the block or crossing, sizes that
cannot resolve a feature or would give an absurd cell count) and knows its
mirror symmetries.  :class:`Scene`
pairs a geometry (block or plate) with its name and physics.

Validation needs a little geometry (where tunnels reach, how many cells a
sizing gives), so that computation lives here rather than in :mod:`hfcdem.mesh`,
which builds on it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from hfcdem.config.fingerprint import fingerprinted
from hfcdem.config.parts import (
    AXES,
    MAX_CELLS,
    Block,
    FracturableZone,
    MeshSizing,
    Perforation,
    SlabZone,
    SphereZone,
    TunnelZone,
    Wellbore,
    axis_index,
    axis_vector,
    check_symmetry_axes,
    estimate_cells,
    refuse_mesh_options,
    show_length,
    tunnel_extension,
)
from hfcdem.config.plates import AngledPathPlate, BoreholeSquare, CrackPlate, KGDStrip
from hfcdem.config.tables import SceneError


def _segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> float:
    """Shortest distance between the segments p0-p1 and q0-q1."""
    u, v, w0 = p1 - p0, q1 - q0, p0 - q0
    a, b, c, d, e = u @ u, u @ v, v @ v, u @ w0, v @ w0
    den = a * c - b * b
    s = np.clip((b * e - c * d) / den, 0.0, 1.0) if den > 1e-14 * a * c else 0.0
    t = np.clip((b * s + e) / c, 0.0, 1.0)
    s = np.clip((b * t - d) / a, 0.0, 1.0)
    return float(np.linalg.norm(w0 + s * u - t * v))


# ---------------------------------------------------------------------------


@fingerprinted
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
        object.__setattr__(self, "symmetry", check_symmetry_axes(self.symmetry, AXES))
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
        refuse_mesh_options(self.mesh, self.kind, ("wall_rings", "path_size", "size_integration"))
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

    def kept_fraction(self, k: int, skip: str | None = None) -> float:
        """Share of perforation ``k`` (from 0) in the model: 1, 1/2, 1/4, or 0 if dropped.

        ``skip`` leaves out one mirror plane (the share seen on that plane).
        """
        fraction = 1.0
        for axis in self.symmetry:
            if axis != skip:
                fraction *= {"cut": 0.5, "kept": 1.0, "dropped": 0.0}[self.relation(k, axis)]
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
        return estimate_cells(self.mesh, volume, refined, 3)


Geometry = PerforatedBlock | CrackPlate | KGDStrip | BoreholeSquare | AngledPathPlate


@fingerprinted
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


__all__ = [
    "AngledPathPlate",
    "BoreholeSquare",
    "CrackPlate",
    "Geometry",
    "KGDStrip",
    "PerforatedBlock",
    "Scene",
]
