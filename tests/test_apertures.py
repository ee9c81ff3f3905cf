"""Joint apertures that follow the mesh size: the equivalent medium no longer does.

Steady radial flow through the joints of an annulus (every interior facet a
joint, the hole at p0, the outer circle at 0) measures the lattice's
equivalent conductivity ``k_eq = Q ln(R/r0) / (2 pi p0)``; its void per unit
area is the sum of the facets' void over the annulus area.  With one aperture
on every facet both double at each halving of h; with the apertures held at a
reference cell size they stay.
"""

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI
from test_seepage import FLUID, P0, R0, R, _annulus

from hfcdem.config.materials import JointAperture
from hfcdem.config.scene import load_scene
from hfcdem.config.tables import SceneError
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.apertures import network_apertures, network_cell_sizes
from hfcdem.flow.seepage import JointSeepage, joint_network

A = 1e-6  # m
SIZES = (0.1, 0.05, 0.025)
SCENE = Path(__file__).resolve().parents[1] / "meshes/scenes/borehole_seepage.toml"


def test_apertures_at_the_reference_size_are_the_aperture():
    hyd, void = JointAperture(A, 0.01).scaled(np.array([0.01, 0.08, 0.00125]))
    assert hyd == pytest.approx([A, 2.0 * A, 0.5 * A], rel=1e-14)  # (h / h_ref)^(1/3)
    assert void == pytest.approx([A, 8.0 * A, 0.125 * A], rel=1e-14)  # h / h_ref
    same = JointAperture(A).scaled(np.array([0.01, 0.08]))
    assert np.all(same[0] == A) and np.all(same[1] == A)


@pytest.mark.parametrize(
    ("value", "size", "match"),
    [(0.0, None, "aperture must be > 0 m"), (A, -1.0, "reference size"), (A, math.nan, "size")],
)
def test_bad_apertures_are_refused(value, size, match):
    with pytest.raises(ValueError, match=match):
        JointAperture(value, size)


def _medium(h: float, aperture: JointAperture, comm=MPI.COMM_WORLD) -> tuple[float, float]:
    """k_eq (m^3/(Pa s) per metre) and void per unit area of the annulus's joints."""
    solid = _annulus(h, comm)
    facets = np.arange(solid.num_facets)
    net = joint_network(solid, cavity_vertices(solid, ["wall", "outer"], None), facets)
    hyd, void = network_apertures(solid, net, facets, aperture)
    sp = JointSeepage(net, hyd, FLUID, void_aperture=void)
    hole = np.linalg.norm(net.centroid[sp.cavity_facets, :2], axis=1) < 0.5 * (R0 + R)
    pc = np.where(hole, P0, 0.0)
    q = sp.inflow(pc, sp.steady(pc))
    k_eq = float(q[hole].sum()) * math.log(R / R0) / (2.0 * math.pi * P0)
    return k_eq, float(sp.void.sum()) / (math.pi * (R**2 - R0**2))


def test_the_equivalent_medium_does_not_follow_the_mesh():
    """Measured (h = 0.1, 0.05, 0.025; 1 um at cells of 0.05 m).

    One aperture: k_eq 1.478e-15, 2.976e-15, 5.838e-15; void 3.50e-5, 7.03e-5, 1.39e-4.
    Held at 0.05 m: k_eq 3.080e-15, 3.001e-15, 2.955e-15 (-2.6 %, -1.5 % per
    halving: the mean cell diameter is not exactly the lattice's spacing);
    void 7.17e-5, 7.05e-5, 7.02e-5.
    """
    plain = [_medium(h, JointAperture(A)) for h in SIZES]
    held = [_medium(h, JointAperture(A, 0.05)) for h in SIZES]
    for (k0, v0), (k1, v1) in itertools.pairwise(plain):
        assert 1.95 < k1 / k0 < 2.05 and 1.95 < v1 / v0 < 2.05  # measured 1.96-2.01
    k = np.array([m[0] for m in held])
    v = np.array([m[1] for m in held])
    assert k == pytest.approx([3.080e-15, 3.001e-15, 2.955e-15], rel=2e-3)
    assert k.max() / k.min() < 1.045  # measured 1.042 over a factor 4 in h
    assert v.max() / v.min() < 1.025  # measured 1.021
    # at the reference size the two agree: the scaling changes nothing there
    assert held[1][0] == pytest.approx(plain[1][0], rel=0.01)  # measured 0.85 %


def test_cell_sizes_are_the_same_on_any_number_of_ranks():
    sizes = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        solid = _annulus(0.1, comm)
        facets = np.arange(solid.num_facets)
        net = joint_network(solid, cavity_vertices(solid, ["wall", "outer"], None), facets)
        sizes.append(network_cell_sizes(solid, net, facets))
    assert np.array_equal(sizes[0], sizes[1])
    assert 0.07 < sizes[0].min() and sizes[0].max() < 0.15  # cells of about 0.1 m


def test_the_scene_gives_the_reference_size():
    scene = load_scene(SCENE, "coarse", overrides={"rock.joint_reference_size": "5 mm"})
    joints = scene.physics.joints
    assert joints.value == pytest.approx(5e-6) and joints.reference_size == pytest.approx(5e-3)
    assert load_scene(SCENE, "coarse").physics.joints.reference_size is None
    for bad in ("1 um", "20 m"):
        with pytest.raises(SceneError, match=r"rock\.joint_reference_size.*10 um to 10 m"):
            load_scene(SCENE, "coarse", overrides={"rock.joint_reference_size": bad})
    with pytest.raises(SceneError, match=r"rock\.joint_reference_size"):
        load_scene(SCENE, "coarse", overrides={"rock.joint_reference_size": "5 MPa"})
