"""Element sizes graded from refined walls: Gmsh Distance and Threshold fields.

Every mesher grades the same way: the size is ``size_min`` on the refined
curves or surfaces and grows linearly with the distance from them to
``size_max`` at ``dist_max``; where several walls are refined the smallest size
wins.  The Gmsh size sources the fields replace (points, curvature, boundary
extension) are switched off.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gmsh


def add_grading(
    model: Any,
    dim: int,
    tags: Sequence[int],
    size_min: float,
    size_max: float,
    dist_max: float,
    sampling: int,
) -> int:
    """Add a size growing from ``size_min`` on the ``dim``-entities ``tags``; return its field.

    ``sampling`` is the number of points per curve or surface edge at which
    Gmsh measures the distance.
    """
    field = model.mesh.field
    dist = field.add("Distance")
    field.setNumbers(dist, "CurvesList" if dim == 1 else "SurfacesList", list(tags))
    field.setNumber(dist, "Sampling", sampling)
    thr = field.add("Threshold")
    field.setNumber(thr, "InField", dist)
    field.setNumber(thr, "SizeMin", size_min)
    field.setNumber(thr, "SizeMax", size_max)
    field.setNumber(thr, "DistMin", 0.0)
    field.setNumber(thr, "DistMax", dist_max)
    return int(thr)


def use_gradings(model: Any, fields: Sequence[int], size_max: float | None = None) -> None:
    """Make the smallest of ``fields`` the element size everywhere.

    ``size_max`` also caps every size and makes Gmsh's 1D size integration
    coarser (the default 1e-9 costs seconds per scene); a scene with
    ``size_integration = "exact"`` and the penny block leave both at Gmsh's defaults.
    """
    field = model.mesh.field
    if len(fields) == 1:
        field.setAsBackgroundMesh(fields[0])
    else:
        smallest = field.add("Min")
        field.setNumbers(smallest, "FieldsList", list(fields))
        field.setAsBackgroundMesh(smallest)
    for opt in ("MeshSizeFromPoints", "MeshSizeFromCurvature", "MeshSizeExtendFromBoundary"):
        gmsh.option.setNumber(f"Mesh.{opt}", 0)
    if size_max is not None:
        gmsh.option.setNumber("Mesh.LcIntegrationPrecision", 1e-4)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size_max)


__all__ = ["add_grading", "use_gradings"]
