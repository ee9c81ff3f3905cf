"""The angled-path plate (Rubin's PMMA scene): its scene keys, checks and mesh."""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.config.plates import AngledPathPlate
from hfcdem.config.scene import load_scene, parse_geometry
from hfcdem.config.tables import SceneError
from hfcdem.mesh.build import create_scene_mesh, measure_mesh

RUBIN = Path(__file__).resolve().parents[1] / "meshes" / "scenes" / "rubin_pmma.toml"
MM = 1e-3


def geometry(**crack):
    data = {
        "kind": "angled_path_plate",
        "plate": {"width": "305 mm", "height": "96 mm"},
        "crack": {"length": "30 mm", "path_length": "50 mm", "path_angle": "51 deg", **crack},
        "support": {"corners": "8 mm"},
        "mesh": {"size": "12 mm", "size_far": "12 mm", "path_size": "7.5 mm"},
    }
    return data


@pytest.mark.serial
def test_rubin_scene_loads_with_the_papers_inputs():
    s = load_scene(RUBIN)
    g = s.geometry
    assert isinstance(g, AngledPathPlate)
    assert (g.plate.width, g.plate.height) == pytest.approx((0.305, 0.096))
    assert g.crack.length == pytest.approx(0.030) and g.slot_width == pytest.approx(1e-3)
    assert np.degrees(g.path_angle) == pytest.approx(51.0)
    start, d = g.wing(1)
    assert start == pytest.approx([0.015, 0.0]) and d == pytest.approx([0.62932, 0.77715], abs=1e-5)
    left, dl = g.wing(-1)  # "point": the right path turned by 180 deg
    assert left == pytest.approx([-0.015, 0.0]) and dl == pytest.approx(-d)
    assert g.corner_support == pytest.approx(8 * MM)
    phys = s.physics
    assert phys.rock.youngs_modulus == pytest.approx(2.0e9)
    assert phys.rock.poisson_ratio == pytest.approx(0.367)
    assert phys.interfaces.tensile_strength == pytest.approx(6.0e6)
    assert phys.interfaces.friction_angle == pytest.approx(28.41)
    assert phys.fluid.viscosity == pytest.approx(97.7)
    assert phys.fluid.bulk_modulus == pytest.approx(1.725e9)
    assert phys.fluid.density == pytest.approx(977.0)
    assert phys.injection.value_at(9.99) == 0.0  # the pump's 10 s delay
    assert phys.injection.value_at(20.0) == pytest.approx(1.33e-6)
    assert phys.initial_pressure == pytest.approx(0.0008 * 1.725e9)
    assert phys.duration == pytest.approx(70.0)
    assert phys.solver.fidelity == "viscous"
    # about 1800 blocks at the paper's resolution, a few hundred at coarse
    assert 1500 < g.estimated_cells() < 2200
    assert load_scene(RUBIN, "coarse").geometry.estimated_cells() < 700


@pytest.mark.serial
def test_mirror_wings_and_a_crack_line():
    g, _, _ = parse_geometry(geometry(wings="mirror"))
    _, d = g.wing(1)
    _, dl = g.wing(-1)
    assert dl == pytest.approx([-d[0], d[1]])
    assert g.slot_width == 0.0


@pytest.mark.serial
@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"crack": {"path_length": "60 mm"}}, "geometry.crack.path_length"),
        ({"crack": {"path_angle": "90 deg"}}, "geometry.crack.path_angle"),
        ({"crack": {"wings": "both"}}, "geometry.crack.wings"),
        ({"crack": {"width": "10 mm"}}, "geometry.crack.width"),
        ({"support": {"corners": "50 mm"}}, "geometry.support.corners"),
        ({"symmetry": ["x"]}, "geometry.symmetry"),
        ({"mesh": {"size": "12 mm", "size_far": "12 mm", "wall_rings": 2}}, "geometry.mesh"),
    ],
)
def test_bad_fields_are_named(change, field):
    data = geometry()
    for key, value in change.items():
        data[key] = {**data[key], **value} if isinstance(value, dict) else value
    with pytest.raises(SceneError, match=field.replace(".", r"\.")):
        parse_geometry(data)


def test_the_coarse_mesh_has_its_lines_and_slot_on_any_rank_count():
    scene = load_scene(RUBIN, "coarse")
    here = measure_mesh(create_scene_mesh(scene))
    areas = {k: v["measured"] for k, v in here["areas"].items()}
    assert areas["fracture_path"] == pytest.approx(0.100, rel=1e-9)  # two 50 mm paths
    assert areas["wellbore_wall"] == pytest.approx(2 * 0.030 + 2 * 0.001, rel=1e-9)
    assert areas["outer_corners"] == pytest.approx(8 * 8 * MM, rel=1e-9)
    assert areas["edge_ymax"] == pytest.approx(0.305 - 0.016, rel=1e-9)
    assert areas["edge_xmin"] == pytest.approx(0.096 - 0.016, rel=1e-9)
    assert here["volumes"]["cavity"]["measured"] == pytest.approx(3.0e-5, rel=1e-9)
    assert here["missing_tags"] == []
    if MPI.COMM_WORLD.size > 1:
        alone = measure_mesh(create_scene_mesh(scene, MPI.COMM_SELF))
        assert alone["cells"] == here["cells"]


def test_a_crack_line_meshes_with_its_origin_as_a_vertex():
    from hfcdem.config.geometry import Scene

    g, _, _ = parse_geometry(geometry())
    sm = create_scene_mesh(Scene("line", g))
    m = measure_mesh(sm)
    assert m["areas"]["crack"]["measured"] == pytest.approx(0.030, rel=1e-9)
    assert m["areas"]["fracture_path"]["measured"] == pytest.approx(0.100, rel=1e-9)
    x = sm.tmesh.mesh.geometry.x
    here = bool(np.any(np.linalg.norm(x, axis=1) < 1e-12))
    assert sm.tmesh.comm.allreduce(here, op=MPI.LOR)
