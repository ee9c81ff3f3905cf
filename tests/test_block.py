"""Perforated blocks: lofted tunnels measured against frustums, tags on their surfaces."""

from pathlib import Path

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.config.parts import Profile, tunnel_extension
from hfcdem.config.scene import load_scene, parse_scene
from hfcdem.mesh import block as geometry
from hfcdem.mesh.build import create_scene_mesh, measure_mesh
from hfcdem.mesh.tagged import MeshingError

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"


@pytest.fixture(scope="module")
def no2():
    """Perforation No. 2 at the scene file's default resolution."""
    sm = create_scene_mesh(load_scene(SCENES / "perforation_no2.toml"))
    return sm, measure_mesh(sm)


def test_no2_lofted_volume_matches_the_frustums_within_1_percent(no2):
    _, m = no2
    (perf,) = m["perforations"]
    # the half model keeps half the tunnel; compare the tunnel outside the wellbore
    assert perf["kept_fraction"] == 0.5
    assert abs(perf["volume_vs_frustums"]["rel_error"]) < 0.01
    assert abs(perf["volume"]["rel_error"]) < 0.01
    # the frustum value itself is Table 7-8's: 2.1951e-4 m3 for the whole tunnel
    assert perf["full_tunnel_frustum_volume"] == pytest.approx(2.19512e-4, rel=1e-4)


def test_no2_wall_areas_within_2_percent(no2):
    _, m = no2
    for name in ("wellbore_wall", "perforation_1_wall", "perforation_1_tip"):
        assert abs(m["areas"][name]["rel_error"]) < 0.02, name
    assert abs(m["volumes"]["rock_total"]["rel_error"]) < 1e-3
    assert m["missing_tags"] == []


def test_no2_tags_are_the_api(no2):
    sm, _ = no2
    assert set(sm.tmesh.cell_names) == {"rock", "fracturable"}
    assert set(sm.tmesh.facet_names) == {
        "wellbore_wall",
        "perforation_1_wall",
        "perforation_1_tip",
        "outer_xmin",
        "outer_xmax",
        "outer_ymin",
        "outer_ymax",
        "outer_zmax",
        "symmetry_z",
    }


def _facet_points(tmesh, name):
    mesh = tmesh.mesh
    facets = tmesh.facets(name)
    if len(facets) == 0:  # entities_to_geometry divides by zero on an empty list (0.9)
        return np.zeros((0, 3))
    nodes = dolfinx.mesh.entities_to_geometry(mesh, mesh.topology.dim - 1, facets)
    return mesh.geometry.x[nodes].reshape(-1, 3)


def _check_tags_on_surfaces(sm):
    """Every tagged facet's vertices lie on the analytic surface its name says."""
    geom = sm.scene.geometry
    residuals = {name: res for name, _, res in geometry.face_candidates(geom)}
    scale = float(np.max(geom.block.size))
    worst = 0.0
    for name in sm.tmesh.facet_names:
        pts = _facet_points(sm.tmesh, name)
        if len(pts):
            worst = max(worst, float(np.max(residuals[name](pts))) / scale)
    return sm.tmesh.comm.allreduce(worst, op=MPI.MAX)


def test_no2_facets_lie_on_their_surfaces(no2):
    sm, _ = no2
    assert _check_tags_on_surfaces(sm) < 1e-7


def test_eighth_model_keeps_one_tunnel_and_tags_three_planes():
    scene = parse_scene(
        {
            "name": "lab0",
            "geometry": {"catalogue": "lab_specimen", "cluster": {"azimuth": "0 deg"}},
        },
        resolution="coarse",
    )
    sm = create_scene_mesh(scene)
    m = measure_mesh(sm)
    names = set(sm.tmesh.facet_names)
    assert {"symmetry_x", "symmetry_y", "symmetry_z", "perforation_1_wall"} <= names
    assert "perforation_2_wall" not in names and "outer_xmin" not in names
    for axis, i in (("x", 0), ("y", 1), ("z", 2)):
        pts = _facet_points(sm.tmesh, f"symmetry_{axis}")
        local = float(np.max(np.abs(pts[:, i]))) if len(pts) else 0.0
        assert sm.tmesh.comm.allreduce(local, op=MPI.MAX) < 1e-12
        assert abs(m["areas"][f"symmetry_{axis}"]["rel_error"]) < 2e-3
    assert abs(m["volumes"]["rock_total"]["rel_error"]) < 1e-3


def test_measures_do_not_depend_on_the_rank_count():
    scene = load_scene(SCENES / "shape_1-1.toml", resolution="coarse")
    here = measure_mesh(create_scene_mesh(scene, MPI.COMM_WORLD))
    alone = measure_mesh(create_scene_mesh(scene, MPI.COMM_SELF))
    assert here["cells"] == alone["cells"] and here["vertices"] == alone["vertices"]
    for group in ("volumes", "areas"):
        for name, value in alone[group].items():
            assert here[group][name]["measured"] == pytest.approx(value["measured"], rel=1e-10)
    assert here["perforations"][0]["volume"]["measured"] == pytest.approx(
        alone["perforations"][0]["volume"]["measured"], rel=1e-10
    )


def test_sliver_measures_by_brute_force():
    big_r = 0.07
    profile = Profile.from_lengths([0.03344, 0.03333], [0.05])
    m = geometry.sliver_measures(profile, big_r)
    delta, _ = tunnel_extension(profile, big_r)
    # volume: voxels of the tunnel's extension outside the wellbore (axis x, wellbore y)
    n = 160
    r_max = float(profile.radius_at(-delta))
    a = np.linspace(-delta, 0.0, n + 1)[:-1] + 0.5 * delta / n
    u = np.linspace(-r_max, r_max, n + 1)[:-1] + r_max / n
    aa, uu, tt = np.meshgrid(a, u, u, indexing="ij")
    inside = (uu**2 + tt**2 <= profile.radius_at(aa) ** 2) & ((big_r + aa) ** 2 + tt**2 >= big_r**2)
    voxels = inside.sum() * (delta / n) * (2 * r_max / n) ** 2
    assert m.volume == pytest.approx(voxels, rel=0.02)
    # hole in the wellbore wall: area on the cylinder by its own (angle, axial) coordinates
    phi = np.linspace(-0.5, 0.5, 2001)
    y = np.linspace(-r_max, r_max, 2001)
    pp, yy = np.meshgrid(phi, y, indexing="ij")
    x, z = big_r * np.cos(pp), big_r * np.sin(pp)
    hole = (yy**2 + z**2 <= profile.radius_at(x - big_r) ** 2).sum()
    assert m.hole_area == pytest.approx(hole * big_r * (phi[1] - phi[0]) * (y[1] - y[0]), rel=0.01)


def test_gmsh_failures_name_the_scene():
    scene = parse_scene(
        {
            "name": "hollow-zone",
            "geometry": {
                "catalogue": "perforation_no2",
                "fracturable": {"shape": "sphere", "radius": "10 mm"},  # inside the wellbore
            },
        },
        resolution="coarse",
    )
    with pytest.raises(MeshingError, match=r"'hollow-zone'.*does not meet the rock"):
        create_scene_mesh(scene)
