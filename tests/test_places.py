"""Places along a tunnel in the paper's terms, and the stress binned by distance from the wall."""

from types import SimpleNamespace

import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import unit_block

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.config.scene import load_scene
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.workflows.places import (
    place_counts,
    place_ratios,
    stress_along_tunnels,
    tunnel_place,
    turn_past_tips,
    wall_distances,
    wellbore_place,
)

MPa = 1e6
E, NU = 30e9, 0.25
SH = 8 * MPa


def perforated(radius=0.1, length=0.6, axis="y"):
    """A scene's geometry as the helpers read it: a wellbore along ``axis``, one tunnel."""
    tunnel = SimpleNamespace(profile=SimpleNamespace(stations=(0.0, 0.2, length)))
    wellbore = SimpleNamespace(axis=axis, radius=radius)
    return SimpleNamespace(geometry=SimpleNamespace(wellbore=wellbore, perforations=(tunnel,)))


def block_solid(comm):
    """The unit cube, every interior facet an interface, SH along x (compression positive)."""
    return CDEMSolid(
        unit_block(3, comm),
        ElasticMaterial(E, NU),
        InSituStress(SH, 5 * MPa, 6 * MPa),
        InterfaceModel(alpha=100, tensile_strength=1e3 * MPa, cohesion=1e3 * MPa),
        rollers={"left": 0, "bottom": 1},
    )


def test_distances_are_across_the_wellbore_axis():
    scene = perforated(radius=0.1, axis="y")
    d = wall_distances(scene, np.array([[0.3, 5.0, 0.4], [0.1, -2.0, 0.0], [0.0, 0.0, 0.05]]))
    assert d == pytest.approx([0.4, 0.0, -0.05])
    assert wellbore_place(scene, np.array([0.35, 1.0, 0.0])) == {
        "distance_from_wellbore_wall_m": pytest.approx(0.25),
        "place": "middle",
        "fraction_of_tunnel": pytest.approx(0.25 / 0.6),
    }
    plate = SimpleNamespace(geometry=SimpleNamespace())
    assert wall_distances(plate, np.zeros((1, 3))) is None
    assert wellbore_place(plate, np.zeros(3)) == {}


def test_the_tunnels_thirds_name_the_places():
    places = [tunnel_place(d, 0.23) for d in (0.0, 0.07, 0.1225, 0.2, 0.23, 0.3)]
    assert places == ["root", "root", "middle", "far end", "far end", "beyond the tip"]


def test_parts_of_the_tunnel_count_points_and_keep_their_highest_ratio():
    """Rank 0 holds the points, the others none: the answer is the same on any rank count."""
    comm = MPI.COMM_WORLD
    scene = perforated(radius=0.1, length=0.6)  # thirds end at 0.2, 0.4, 0.6 m from the wall
    pts = np.array([[0.15, 0.0, 0.0], [0.2, 1.0, 0.0], [0.45, 0.0, 0.0], [0.0, 0.0, 0.9]])
    ratio = np.array([0.4, 0.97, 1.02, 0.3])
    mine = slice(None) if comm.rank == 0 else slice(0)
    assert place_counts(scene, pts[mine], comm) == {"root": 2, "middle": 1, "beyond the tip": 1}
    assert place_ratios(scene, pts[mine], ratio[mine], comm) == {
        "root": pytest.approx(0.97),
        "middle": pytest.approx(1.02),
        "far end": 0.0,  # no facet there
        "beyond the tip": pytest.approx(0.3),
    }
    plate = SimpleNamespace(geometry=SimpleNamespace())
    assert place_counts(plate, pts, comm) is None
    assert place_ratios(plate, pts, ratio, comm) is None


def test_the_turn_past_the_tips_is_measured_from_sh():
    """The lab at 60 deg: tunnels from r = 10 to 40 mm; what lies past r = 40 mm is judged."""
    scene = load_scene("meshes/scenes/lab_specimen_60deg.toml", "coarse")

    def at(r, deg, z=0.001):
        return [r * np.cos(np.radians(deg)), r * np.sin(np.radians(deg)), z]

    inside = [at(0.03, 10.0)]  # beside a tunnel: not past its tip
    past = [at(0.045, 60.0), at(0.05, 230.0), at(0.048, 250.0)]  # the second tunnel is at 240
    turn = turn_past_tips(scene, np.array(inside + past), np.array([5.0, 1.0, 2.0, 1.0]))
    assert turn["past_tip"] == 3
    assert turn["farthest_past_tip_m"] == pytest.approx(0.01)
    assert turn["turn_deg"] == pytest.approx((0.0 + 2 * 10.0 - 10.0) / 4.0)
    assert turn["cell_angle_deg"] == pytest.approx(np.degrees(0.002 / 0.04))
    none = turn_past_tips(scene, np.array(inside), np.ones(1))
    assert none["past_tip"] == 0 and none["turn_deg"] is None
    assert turn_past_tips(perforated(), np.zeros((1, 3)), np.ones(1)) is None  # not a block


@pytest.mark.parametrize("strain", [-1e-4, 5e-4])
def test_a_uniform_strain_gives_the_closed_form_stress_in_every_bin(strain):
    # u = (e x, 0, 0): sigma_xx = -SH + (lambda + 2 mu) e in every cell, exactly
    solid = block_solid(MPI.COMM_WORLD)
    solid.u.interpolate(lambda x: np.vstack([strain * x[0], 0 * x[1], 0 * x[2]]))
    lam = E * NU / ((1 + NU) * (1 - 2 * NU))
    expected = (-SH + (lam + E / (1 + NU)) * strain) / MPa
    prof = stress_along_tunnels(perforated(), solid, bins=4)  # 0.15 m: every bin has cells
    assert prof is not None
    assert prof["cells"] == 4 * 3 * 3 * 6  # every cell of the cube, once
    assert prof["distance_m"] == pytest.approx([0.075, 0.225, 0.375, 0.525])
    assert all(v is not None for v in prof["largest_MPa"])
    assert prof["largest_MPa"] == pytest.approx([expected] * 4, rel=1e-12)
    assert prof["mean_MPa"] == pytest.approx([expected] * 4, rel=1e-12)
    assert prof["peak_MPa"] == pytest.approx(expected, rel=1e-12)
    assert prof["tensile_cells"] == (prof["cells"] if expected > 0 else 0)


def test_the_profile_and_its_peak_do_not_depend_on_the_rank_count():
    # u_x = a x^2 / 2: sigma_xx grows with x, so the peak is in the cells at x = 1
    def profile(comm):
        solid = block_solid(comm)
        solid.u.interpolate(lambda x: np.vstack([1e-3 * x[0] ** 2 / 2, 0 * x[1], 0 * x[2]]))
        return stress_along_tunnels(perforated(), solid, bins=4)

    world, alone = profile(MPI.COMM_WORLD), profile(MPI.COMM_SELF)
    assert world["cells"] == alone["cells"]
    assert world["largest_MPa"] == pytest.approx(alone["largest_MPa"], rel=1e-12)
    assert world["mean_MPa"] == pytest.approx(alone["mean_MPa"], rel=1e-12)
    assert world["peak_MPa"] == pytest.approx(alone["peak_MPa"], rel=1e-12)
    assert world["peak_MPa"] >= max(world["largest_MPa"])
    assert world["peak_point_m"][0] > 0.8
    assert world["largest_MPa"][-1] > world["largest_MPa"][0]  # the far bins reach larger x
    assert world["peak_place"] == "beyond the tip"  # x > 0.8: 0.7 m from the wall


def test_a_scene_without_tunnels_has_no_profile():
    plate = SimpleNamespace(geometry=SimpleNamespace())
    assert stress_along_tunnels(plate, None) is None


def test_an_unknown_component_is_refused():
    with pytest.raises(ValueError, match="component"):
        stress_along_tunnels(perforated(), block_solid(MPI.COMM_WORLD), component="xq")
