"""A quarter block with a penny-shaped crack: the 3D check of the CDEM solid.

The one verification mesh that is not a scene: a quarter block
``[0, w] x [0, w] x [-w, w]`` with an embedded quarter disk of ``radius`` at
z = 0, centred on the z axis.  Its facet groups use the scene names
(:mod:`hfcdem.mesh.plates`): ``crack`` (interior facets), ``symmetry_x`` and
``symmetry_y`` (the cut planes), ``outer_xmax``, ``outer_ymax``, ``outer_zmin``
and ``outer_zmax``; the cells are ``rock``.  Sizes grow from ``size_at_crack``
on the crack at ``grading`` per metre to ``size_far`` (:mod:`hfcdem.mesh.grading`,
sampled as the scenes' ``size_integration = "exact"``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mpi4py import MPI

from hfcdem.mesh.grading import add_grading, use_gradings
from hfcdem.mesh.tagged import TaggedMesh, mesh_from_gmsh


@dataclass(frozen=True)
class PennyBlock:
    """Quarter block of half width ``half_width`` around a penny crack of ``radius`` (m)."""

    radius: float
    half_width: float
    size_at_crack: float
    size_far: float
    grading: float = 0.3

    def __post_init__(self) -> None:
        for key in ("radius", "half_width", "size_at_crack", "size_far"):
            value = getattr(self, key)
            if not math.isfinite(value) or value <= 0.0:
                raise ValueError(f"{key} must be a positive length in m, got {value!r}")
        if self.half_width <= 2.0 * self.radius:
            raise ValueError("half_width must exceed twice the crack radius")
        if self.size_at_crack > self.radius / 2:
            raise ValueError("size_at_crack must resolve the crack: at most radius / 2")
        if self.size_far < self.size_at_crack:
            raise ValueError("size_far must be at least size_at_crack")
        if not 0.02 <= self.grading <= 2.0:
            raise ValueError(f"grading must be in [0.02, 2], got {self.grading!r}")

    def _group(self, box: tuple[float, ...], tol: float) -> str:
        """Name of the boundary or crack surface with bounding box ``box``."""
        x0, y0, z0, x1, y1, z1 = box
        w, a = self.half_width, self.radius
        if abs(z0) < tol and abs(z1) < tol and max(x1, y1) <= a + tol:
            return "crack"
        for name, low, high, at in (
            ("symmetry_x", x0, x1, 0.0),
            ("symmetry_y", y0, y1, 0.0),
            ("outer_xmax", x0, x1, w),
            ("outer_ymax", y0, y1, w),
            ("outer_zmin", z0, z1, -w),
            ("outer_zmax", z0, z1, w),
        ):
            if abs(low - at) < tol and abs(high - at) < tol:
                return name
        raise RuntimeError(f"cannot tell which face the surface {box} is")

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
        tol = 1e-7 + 1e-9 * w  # OCC pads bounding boxes by about 1e-7
        groups: dict[str, list[int]] = {}
        for _, surf in model.getEntities(2):
            groups.setdefault(self._group(model.getBoundingBox(2, surf), tol), []).append(surf)
        for name, tags in sorted(groups.items()):
            model.addPhysicalGroup(2, tags, name=name)
        reach = (self.size_far - self.size_at_crack) / self.grading
        field = add_grading(
            model, 2, groups["crack"], self.size_at_crack, self.size_far, reach, 400
        )
        use_gradings(model, [field])
        model.mesh.generate(3)


def create_penny_block(block: PennyBlock, comm: MPI.Comm = MPI.COMM_WORLD) -> TaggedMesh:
    """Mesh ``block`` on rank 0 and distribute it over ``comm``."""
    return mesh_from_gmsh(block.build, comm, gdim=3, name="penny_block")


__all__ = ["PennyBlock", "create_penny_block"]
