"""Where a scene's shapes are: tunnel frames, the kept part of a model, slabs, planes.

Shared by the 3D block (:mod:`hfcdem.mesh.block`) and the 2D plates
(:mod:`hfcdem.mesh.plates`), and by the mesh report (:mod:`hfcdem.mesh.build`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from hfcdem.config.geometry import PerforatedBlock
from hfcdem.config.parts import Profile, SlabZone, axis_index, axis_vector, tunnel_extension

Residual = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class TunnelFrame:
    """Local frame of a perforation: axis ``d``, wellbore axis ``w``, third axis ``t = d x w``.

    ``origin`` is on the wellbore axis; ``start`` on the wall (station 0).
    """

    profile: Profile
    origin: np.ndarray
    start: np.ndarray
    d: np.ndarray
    w: np.ndarray
    t: np.ndarray
    wellbore_radius: float
    delta: float
    inner_radius: float

    def local(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Station along the axis (from the wall) and distance from the axis of ``points``."""
        rel = np.asarray(points) - self.start
        a = rel @ self.d
        radial = rel - np.outer(a, self.d)
        return a, np.linalg.norm(radial, axis=1)


def tunnel_frame(geom: PerforatedBlock, k: int) -> TunnelFrame:
    """Return the frame of perforation ``k`` (from 0)."""
    perf = geom.perforations[k]
    w = axis_vector(geom.wellbore.axis)
    d = np.asarray(perf.direction)
    delta, r_in = tunnel_extension(perf.profile, geom.wellbore.radius)
    return TunnelFrame(
        profile=perf.profile,
        origin=perf.entry * w,
        start=perf.start(geom.wellbore),
        d=d,
        w=w,
        t=np.cross(d, w),
        wellbore_radius=geom.wellbore.radius,
        delta=delta,
        inner_radius=r_in,
    )


def kept_corners(half: np.ndarray, symmetry: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners of the modelled part of a box of ``half`` sizes.

    ``half`` has one entry per model axis (3 for a block, 2 for a plate); each
    mirror plane in ``symmetry`` keeps the positive side.
    """
    hi = np.array(half, dtype=float)
    lo = -hi
    for axis in symmetry:
        lo[axis_index(axis)] = 0.0
    return lo, hi


def slab_box(zone: SlabZone, half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corner and edge lengths of a box (or rectangle) holding ``zone`` across the model.

    The box overhangs the model of ``half`` sizes by 0.5 m on every side, so the
    fragment cuts it cleanly at the model's faces.
    """
    big = 2.0 * np.asarray(half, dtype=float) + 1.0
    corner = -0.5 * big
    i = axis_index(zone.axis)
    corner[i] = zone.offset - 0.5 * zone.thickness
    size = big.copy()
    size[i] = zone.thickness
    return corner, size


def plane_residual(i: int, value: float) -> Residual:
    """Distance of points to the plane ``x[i] = value``."""

    def residual(p: np.ndarray) -> np.ndarray:
        return np.abs(p[:, i] - value)

    return residual


__all__ = [
    "Residual",
    "TunnelFrame",
    "kept_corners",
    "plane_residual",
    "slab_box",
    "tunnel_frame",
]
