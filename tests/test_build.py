"""Every scene file meshes (coarse), serially and in parallel, and its mesh checks out."""

import json
from pathlib import Path

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.config.geometry import PerforatedBlock
from hfcdem.config.scene import load_scene
from hfcdem.mesh import block as geometry
from hfcdem.mesh import plates
from hfcdem.mesh.build import create_scene_mesh, measure_mesh, mesh_report

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"
SCENE_FILES = sorted(SCENES.glob("*.toml"))
REFERENCE = json.loads((SCENES.parent / "reference_counts.json").read_text())


def _residuals(geom):
    if isinstance(geom, PerforatedBlock):
        return {name: res for name, _, res in geometry.face_candidates(geom)}, max(geom.block.size)
    return dict(plates.curve_candidates(geom)), max(geom.plate.width, geom.plate.height)


def _worst_offset(sm):
    """Largest distance (relative) of a tagged facet's vertex from its named surface."""
    residuals, scale = _residuals(sm.scene.geometry)
    mesh = sm.tmesh.mesh
    worst = 0.0
    for name in sm.tmesh.facet_names:
        facets = sm.tmesh.facets(name)
        if len(facets) == 0:  # entities_to_geometry divides by zero on an empty list (0.9)
            continue
        nodes = dolfinx.mesh.entities_to_geometry(mesh, mesh.topology.dim - 1, facets)
        pts = mesh.geometry.x[nodes].reshape(-1, 3)
        worst = max(worst, float(np.max(residuals[name](pts))) / scale)
    return sm.tmesh.comm.allreduce(worst, op=MPI.MAX)


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.stem)
def test_scene_file_meshes(path):
    scene = load_scene(path, resolution="coarse")
    sm = create_scene_mesh(scene)
    m = measure_mesh(sm)
    geom = scene.geometry
    # the same counts as meshes/reference_counts.json (Gmsh is deterministic in the image)
    ref = REFERENCE["coarse"][path.stem]
    assert m["cells"] == pytest.approx(ref["cells"], rel=0.02)
    assert m["vertices"] == pytest.approx(ref["vertices"], rel=0.02)
    assert m["missing_tags"] == []
    assert abs(m["volumes"]["rock_total"]["rel_error"]) < 2e-3
    for name, value in m["areas"].items():
        if name.startswith(("outer_", "symmetry_", "crack", "fracture_path")):
            assert abs(value["rel_error"]) < 1e-3, name  # planes and straight lines
    assert {f"symmetry_{a}" for a in geom.symmetry} <= set(sm.tmesh.facet_names)
    assert "rock" in sm.tmesh.cell_names
    if geom.fracturable is not None:
        assert m["volumes"]["cells_fracturable"]["measured"] > 0.0
    if isinstance(geom, PerforatedBlock):
        kept = [k for k in range(len(geom.perforations)) if geom.kept_fraction(k) > 0]
        expected = {f"perforation_{k + 1}_{part}" for k in kept for part in ("wall", "tip")}
        assert expected <= set(sm.tmesh.facet_names)
    # every tagged facet lies on the surface its name says (symmetry facets on their planes)
    assert _worst_offset(sm) < 1e-7
    assert sm.build["quality"]["min"] > 0.05
    report = mesh_report(sm)
    assert report["cells"] == m["cells"] and report["ranks"] == MPI.COMM_WORLD.size
