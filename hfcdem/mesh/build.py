"""Mesh a scene and check the mesh: files for ParaView, a picture and ``mesh_report.json``.

:func:`create_scene_mesh` runs Gmsh on rank 0 (through
:func:`hfcdem.mesh.tagged.mesh_from_gmsh`) and distributes the mesh with
shared-facet ghosting.  :func:`measure_mesh` integrates over the distributed
mesh with DOLFINx (volumes by ``1 dx``, wall areas by ``1 ds`` over each facet
tag) and compares with the analytic values of :mod:`hfcdem.mesh.block` and
:mod:`hfcdem.mesh.plates`.  A tunnel's own volume is measured by the divergence
theorem over its wall and tip with the field ``F = (a - sqrt(R^2 - t^2)) d``
(``a``, ``t`` coordinates along the tunnel axis ``d`` and across it, from
the wellbore axis): ``div F = 1`` and ``F`` vanishes on the wellbore wall, so
the opening the mesh does not have contributes nothing.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import dolfinx
import gmsh
import numpy as np
import ufl
from dolfinx.io import XDMFFile
from mpi4py import MPI

from hfcdem.config import catalogue
from hfcdem.config.geometry import Geometry, PerforatedBlock, Scene
from hfcdem.io.files import prepare_output_dir, write_json
from hfcdem.mesh import block as geometry
from hfcdem.mesh import plates
from hfcdem.mesh.frames import kept_corners, tunnel_frame
from hfcdem.mesh.tagged import TaggedMesh, mesh_from_gmsh


@dataclass(frozen=True)
class SceneMesh:
    """A scene's distributed mesh and the facts Gmsh reported while building it."""

    scene: Scene
    tmesh: TaggedMesh
    build: dict[str, Any] = field(default_factory=dict)
    msh_path: Path | None = None


def create_scene_mesh(
    scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD, msh_path: str | Path | None = None
) -> SceneMesh:
    """Build and mesh ``scene``'s geometry on rank 0, distribute it over ``comm``.

    ``msh_path``: also write Gmsh's ``.msh`` file there (from rank 0).
    """
    geom = scene.geometry
    facts: dict[str, Any] = {}
    target = Path(msh_path) if msh_path is not None else None

    def build(model: Any) -> None:
        t0 = time.perf_counter()
        if isinstance(geom, PerforatedBlock):
            facts.update(geometry.build_perforated_block(geom, model))
        else:
            facts.update(plates.build_plate(geom, model))
        facts["gmsh_seconds"] = time.perf_counter() - t0
        if target is not None:
            gmsh.option.setNumber("Mesh.Binary", 1)
            gmsh.write(str(target))

    tmesh = mesh_from_gmsh(build, comm, gdim=geom.dim, name=scene.name)
    return SceneMesh(scene, tmesh, comm.bcast(facts, root=0), target)


def mesh_geometry(
    geometry: Geometry, comm: MPI.Comm = MPI.COMM_WORLD, name: str | None = None
) -> TaggedMesh:
    """Mesh a scene geometry without a scene file (the API of tests and benchmarks)."""
    scene = Scene(name or geometry.kind, geometry)
    return create_scene_mesh(scene, comm).tmesh


# ---------------------------------------------------------------------------
# Measurements
# ---------------------------------------------------------------------------


def _assemble(comm: MPI.Comm, form: Any) -> float:
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form))
    return float(comm.allreduce(local, op=MPI.SUM))


def _tunnel_volume(sm: SceneMesh, k: int) -> float:
    """Volume of tunnel ``k`` (from 0) outside the wellbore, by the divergence theorem."""
    geom = sm.scene.geometry
    assert isinstance(geom, PerforatedBlock)
    tm = sm.tmesh
    frame = tunnel_frame(geom, k)
    mesh = tm.mesh
    gdim = mesh.geometry.dim

    def constant(value: Any) -> dolfinx.fem.Constant:
        # constants, not literals: one compiled kernel serves every tunnel and scene
        return dolfinx.fem.Constant(mesh, np.asarray(value, dtype=dolfinx.default_scalar_type))

    x = ufl.SpatialCoordinate(mesh)
    n = ufl.FacetNormal(mesh)
    rel = x - constant(frame.origin[:gdim])
    d = constant(frame.d[:gdim])
    a = ufl.dot(rel, d)
    t = ufl.dot(rel, constant(frame.t[:gdim]))
    r2 = constant(frame.wellbore_radius**2)
    flux = (a - ufl.sqrt(ufl.max_value(r2 - t**2, 0.0))) * ufl.dot(d, n)
    names = [f"perforation_{k + 1}_wall", f"perforation_{k + 1}_tip"]
    # n points out of the rock, into the tunnel: the tunnel's outward normal is -n
    return -sum(_assemble(tm.comm, flux * tm.ds(name)) for name in names if name in tm.facet_names)


def _relative(measured: float, expected: float) -> float:
    return (measured - expected) / expected if expected else math.nan


def _pair(measured: float, expected: float) -> dict[str, float]:
    return {"measured": measured, "expected": expected, "rel_error": _relative(measured, expected)}


def measure_mesh(sm: SceneMesh) -> dict[str, Any]:
    """Measure counts, sizes, volumes and wall areas, next to their analytic values."""
    tm = sm.tmesh
    comm = tm.comm
    geom = sm.scene.geometry
    mesh = tm.mesh
    tdim = mesh.topology.dim
    cells = mesh.topology.index_map(tdim)
    owned = np.arange(cells.size_local, dtype=np.int32)
    h = mesh.h(tdim, owned)
    h_min = comm.allreduce(float(h.min()) if len(h) else math.inf, op=MPI.MIN)
    h_max = comm.allreduce(float(h.max()) if len(h) else 0.0, op=MPI.MAX)

    expected = (
        geometry.expected_measures(geom)
        if isinstance(geom, PerforatedBlock)
        else plates.expected_measures(geom)
    )
    one = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=tm.cell_tags)
    dS = ufl.Measure("dS", domain=mesh, subdomain_data=tm.facet_tags)
    volume = _assemble(comm, one * dx)
    if isinstance(geom, PerforatedBlock):
        lo, hi = kept_corners(geom.block.half, geom.symmetry)
    else:
        lo, hi = kept_corners(geom.plate.half[:2], geom.symmetry)
    box = float(np.prod(hi - lo))
    volumes: dict[str, Any] = {
        "rock_total": _pair(volume, expected["volume"]),
        "cavity": _pair(box - volume, expected["cavity"]),
    }
    for name, tag in sorted(tm.cell_names.items()):
        volumes[f"cells_{name}"] = {"measured": _assemble(comm, one * dx(tag))}
    areas: dict[str, Any] = {}
    interior = {"crack", "fracture_path"}
    for name, tag in sorted(tm.facet_names.items()):
        measure = dS(tag) if name in interior else tm.ds(name)
        value = _assemble(comm, one * measure)
        ref = expected["areas"].get(name)
        areas[name] = _pair(value, ref) if ref is not None else {"measured": value}
    missing = sorted(set(expected["areas"]) - set(tm.facet_names))
    perforations = []
    if isinstance(geom, PerforatedBlock):
        for k, perf in enumerate(geom.perforations):
            ref = expected["perforations"].get(k + 1)
            entry: dict[str, Any] = {
                "index": k + 1,
                "profile": perf.profile.name,
                "assumed": perf.profile.assumed,
                "source": perf.profile.source,
                "diameters_mm": [round(v * 1e3, 6) for v in perf.profile.diameters],
                "stations_mm": [round(v * 1e3, 6) for v in perf.profile.stations],
                "length_mm": round(perf.profile.length * 1e3, 6),
                "direction": list(perf.direction),
                "entry_m": perf.entry,
                "in_model": ref is not None,
            }
            if ref is not None:
                vol = _tunnel_volume(sm, k)
                entry.update(
                    {
                        "kept_fraction": ref["fraction"],
                        "volume": _pair(vol, ref["volume"]),
                        "volume_vs_frustums": _pair(vol, ref["frustum_volume"]),
                        "sliver_volume": ref["sliver_volume"],
                        "frustum_wall_area": ref["frustum_wall_area"],
                        "full_tunnel_frustum_volume": ref["frustum_volume"] / ref["fraction"],
                    }
                )
            perforations.append(entry)
    return {
        "cells": cells.size_global,
        "vertices": mesh.topology.index_map(0).size_global,
        "cell_diameter": {"min": h_min, "max": h_max},
        "volumes": volumes,
        "areas": areas,
        "missing_tags": missing,
        "perforations": perforations,
    }


def mesh_report(sm: SceneMesh, files: dict[str, str] | None = None) -> dict[str, Any]:
    """Return the full ``mesh_report.json`` content of a scene mesh."""
    scene = sm.scene
    geom = scene.geometry
    measured = measure_mesh(sm)
    sizing = geom.mesh
    report: dict[str, Any] = {
        "scene": scene.name,
        "description": scene.description,
        "kind": geom.kind,
        "catalogue": scene.catalogue,
        "resolution": scene.resolution,
        "source": scene.source,
        "ranks": sm.tmesh.comm.size,
        "cells": measured["cells"],
        "vertices": measured["vertices"],
        "seconds_to_mesh": sm.tmesh.seconds,
        "seconds_in_gmsh": sm.build.get("gmsh_seconds"),
        "estimated_cells": geom.estimated_cells(),
        "element_quality": sm.build.get("quality"),
        "cell_diameter_m": measured["cell_diameter"],
        "sizing_m": {
            "size": sizing.size,
            "size_far": sizing.size_far,
            "grading": sizing.grading,
            "circle_elements": sizing.circle_elements,
            "wellbore_size": getattr(geom, "wellbore_size", None),
            "algorithm": sizing.algorithm,
        },
        "symmetry": list(geom.symmetry),
        "tags": {"cells": dict(sm.tmesh.cell_names), "facets": dict(sm.tmesh.facet_names)},
        # in 2D "volumes" are areas (m2 per unit thickness) and "areas" lengths (m)
        "units": {"volumes": "m3", "areas": "m2"}
        if geom.dim == 3
        else {"volumes": "m2", "areas": "m"},
        "volumes": measured["volumes"],
        "areas": measured["areas"],
        "missing_tags": measured["missing_tags"],
    }
    if isinstance(geom, PerforatedBlock):
        report["wellbore"] = {"diameter_m": geom.wellbore.diameter, "axis": geom.wellbore.axis}
        report["perforations"] = measured["perforations"]
        report["assumed_profiles"] = list(scene.assumed_profiles)
        report["notes"] = [
            f"ASSUMED profile {p['profile']}: {p['source']}"
            for p in measured["perforations"]
            if p["assumed"]
        ]
        report["equal_volume_cylinder_1_3_mm"] = {
            "computed_from_table7_frustums": catalogue.D13_COMPUTED_MM,
            "paper": catalogue.D13_PAPER_MM,
        }
    if files:
        report["files"] = files
    return report


# ---------------------------------------------------------------------------
# Files
# ---------------------------------------------------------------------------


def write_xdmf(path: Path, tmesh: TaggedMesh) -> Path:
    """Write the mesh with its cell and facet tags to one XDMF file (ParaView)."""
    target = path.with_suffix(".xdmf")
    mesh = tmesh.mesh
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    with XDMFFile(tmesh.comm, target, "w") as xdmf:
        xdmf.write_mesh(mesh)
        xdmf.write_meshtags(tmesh.cell_tags, mesh.geometry)
        xdmf.write_meshtags(tmesh.facet_tags, mesh.geometry)
    return target


def mesh_scene(
    scene: Scene,
    out_dir: str | Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    picture: bool = True,
) -> dict[str, Any]:
    """Mesh ``scene`` and write ``NAME.msh``, ``NAME.xdmf``, ``NAME.png`` and ``mesh_report.json``.

    Collective; returns the report (on every rank).
    """
    out = prepare_output_dir(out_dir, comm)
    msh = out / f"{scene.name}.msh"
    sm = create_scene_mesh(scene, comm, msh)
    files = {"msh": msh.name, "xdmf": write_xdmf(out / scene.name, sm.tmesh).name}
    problem = None
    if picture:
        png = out / f"{scene.name}.png"
        if comm.rank == 0:
            try:
                from hfcdem.mesh.picture import render_mesh

                render_mesh(msh, png, scene)
            except Exception as exc:  # a missing display must not lose the mesh
                problem = f"no picture: {type(exc).__name__}: {exc}"
        problem = comm.bcast(problem, root=0)
        if problem is None:
            files["png"] = png.name
    report = mesh_report(sm, files)
    if problem is not None:
        report["picture_error"] = problem
    write_json(out / "mesh_report.json", report, comm)
    return report


__all__ = [
    "SceneMesh",
    "create_scene_mesh",
    "measure_mesh",
    "mesh_geometry",
    "mesh_report",
    "mesh_scene",
    "write_xdmf",
]
