"""2D plates: the crack as shared interior facets, the KGD path, the borehole square."""

from pathlib import Path

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from hfcdem.config.scene import load_scene, parse_scene
from hfcdem.mesh import plates
from hfcdem.mesh.build import create_scene_mesh, measure_mesh

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"


def _facet_points(tmesh, name):
    facets = tmesh.facets(name)
    if len(facets) == 0:  # entities_to_geometry divides by zero on an empty list (0.9)
        return np.zeros((0, 3))
    nodes = dolfinx.mesh.entities_to_geometry(tmesh.mesh, 1, facets)
    return tmesh.mesh.geometry.x[nodes].reshape(-1, 3)


def _sum(comm, value):
    return comm.allreduce(value, op=MPI.SUM)


@pytest.fixture(scope="module")
def crack():
    return create_scene_mesh(load_scene(SCENES / "crack_plate.toml", resolution="coarse"))


def test_crack_is_interior_facets_shared_by_two_cells(crack):
    tm = crack.tmesh
    mesh = tm.mesh
    one = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
    dS = ufl.Measure("dS", domain=mesh, subdomain_data=tm.facet_tags)
    inner = _sum(
        tm.comm, dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * dS(tm.facet_tag("crack"))))
    )
    outer = _sum(tm.comm, dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * tm.ds("crack"))))
    assert inner == pytest.approx(0.2, rel=1e-12)
    assert outer == 0.0
    f2c = mesh.topology.connectivity(1, 2)
    facets = tm.facets("crack")
    owned = facets[facets < mesh.topology.index_map(1).size_local]
    assert all(len(f2c.links(f)) == 2 for f in owned)
    assert _sum(tm.comm, len(owned)) >= 2
    # the crack lies on y = 0 between -0.1 and 0.1
    pts = _facet_points(tm, "crack")
    assert np.allclose(pts[:, 1], 0.0) and np.all(np.abs(pts[:, 0]) <= 0.1 + 1e-12)


def test_half_crack_plate_and_refused_plane():
    sm = create_scene_mesh(
        parse_scene(
            {"name": "half", "geometry": {"catalogue": "crack_plate", "symmetry": ["x"]}},
            resolution="coarse",
        )
    )
    m = measure_mesh(sm)
    assert m["areas"]["crack"]["measured"] == pytest.approx(0.1, rel=1e-12)
    assert m["areas"]["symmetry_x"]["measured"] == pytest.approx(1.0, rel=1e-12)
    pts = _facet_points(sm.tmesh, "symmetry_x")
    assert np.allclose(pts[:, 0], 0.0)
    assert "outer_xmin" not in sm.tmesh.facet_names


def test_kgd_injection_point_is_a_vertex_and_zone_is_the_band():
    sm = create_scene_mesh(load_scene(SCENES / "kgd_strip.toml", resolution="coarse"))
    x = sm.tmesh.mesh.geometry.x
    here = bool(np.any(np.linalg.norm(x, axis=1) < 1e-12))
    assert sm.tmesh.comm.allreduce(here, op=MPI.LOR)
    m = measure_mesh(sm)
    assert m["areas"]["crack"]["measured"] == pytest.approx(1.0)  # half of a 2 m crack
    assert m["areas"]["fracture_path"]["measured"] == pytest.approx(23.0)
    assert m["volumes"]["cells_fracturable"]["measured"] == pytest.approx(4.0 * 80.0)
    assert set(sm.tmesh.cell_names) == {"rock", "fracturable"}


def test_expected_measures_of_a_quarter_borehole():
    g = load_scene(SCENES / "borehole_plate.toml", overrides={"geometry.symmetry": "auto"}).geometry
    e = plates.expected_measures(g)
    assert e["areas"]["wellbore_wall"] == pytest.approx(np.pi * 0.03 / 2)
    assert e["areas"]["symmetry_x"] == pytest.approx(0.5 - 0.03)
    assert e["volume"] == pytest.approx(0.25 - np.pi * 0.03**2 / 4)


def test_plate_measures_do_not_depend_on_the_rank_count(crack):
    alone = measure_mesh(create_scene_mesh(crack.scene, MPI.COMM_SELF))
    here = measure_mesh(crack)
    assert here["cells"] == alone["cells"]
    for name, value in alone["areas"].items():
        assert here["areas"][name]["measured"] == pytest.approx(value["measured"], rel=1e-12)
