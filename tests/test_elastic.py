"""Continuous elastic blocks: Kirsch around a borehole, rank independence."""

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem import analytic
from hfcdem.config.materials import ElasticMaterial, InSituStress
from hfcdem.config.parts import MeshSizing, Plate, Wellbore
from hfcdem.config.plates import BoreholeSquare
from hfcdem.io.sampling import evaluate_at_points, interpolate_expression
from hfcdem.mesh.build import mesh_geometry
from hfcdem.solid.elastic import solve_cavity_pressure

MPa = 1e6
ROCK = ElasticMaterial(21.5e9, 0.25)


def quarter_plate(a, half_width, size, size_far, comm=MPI.COMM_WORLD):
    """A quarter plate around a borehole of radius ``a`` (grading 0.25, exact sizing)."""
    sizing = MeshSizing(size, size_far, grading=0.25, circle_elements=6, size_integration="exact")
    plate = Plate(2 * half_width, 2 * half_width)
    return mesh_geometry(
        BoreholeSquare(plate, Wellbore(2 * a, "z"), sizing, symmetry=("x", "y")), comm
    )


def wall_hoop_stress(comm, size, sh_max, sh_min, pw, theta):
    a = 0.035
    tmesh = quarter_plate(a, 40 * a, size, 8 * a, comm)
    sol = solve_cavity_pressure(
        tmesh,
        ROCK,
        InSituStress(sh_max, sh_min),
        {"wellbore_wall": pw},
        rollers={"symmetry_x": 0, "symmetry_y": 1},
    )
    sigma = interpolate_expression(sol.total_stress, tmesh.mesh, ("DG", 1, (2, 2)))
    pts = a * (1 + 1e-9) * np.column_stack([np.cos(theta), np.sin(theta)])
    s = evaluate_at_points(sigma, pts).reshape(-1, 2, 2)
    c, sn = np.cos(theta), np.sin(theta)
    return -(s[:, 0, 0] * sn**2 - 2 * s[:, 0, 1] * sn * c + s[:, 1, 1] * c**2), sol


@pytest.mark.parametrize(
    ("sh_max", "sh_min", "pw"), [(38e6, 34e6, 20e6), (6e6, 1e6, 0.0), (10e6, 10e6, 25e6)]
)
def test_kirsch_hoop_stress_within_5_percent(sh_max, sh_min, pw):
    theta = np.array([0.0, np.pi / 2])
    hoop, _ = wall_hoop_stress(MPI.COMM_WORLD, 0.0035, sh_max, sh_min, pw, theta)
    ref = analytic.kirsch_wall_hoop_stress(theta, sh_max, sh_min, pw)
    scale = np.abs(ref).max()
    assert np.all(np.abs(hoop - ref) <= 0.05 * scale), (hoop / MPa, ref / MPa)


def test_kirsch_error_falls_with_mesh_size():
    theta = np.array([0.0, np.pi / 4, np.pi / 2])
    ref = analytic.kirsch_wall_hoop_stress(theta, 38e6, 34e6, 20e6)
    errors = []
    for size in (0.014, 0.007, 0.0035):
        hoop, _ = wall_hoop_stress(MPI.COMM_WORLD, size, 38e6, 34e6, 20e6, theta)
        errors.append(np.abs(hoop - ref).max() / np.abs(ref).max())
    assert errors[2] < errors[1] < errors[0], errors


def test_hydrostatic_state_without_cavity_load_stays_still():
    # pressure equal to an isotropic in-situ stress: nothing changes, nothing moves
    a = 0.035
    tmesh = quarter_plate(a, 20 * a, 0.007, 4 * a)
    sol = solve_cavity_pressure(
        tmesh,
        ROCK,
        InSituStress(30e6, 30e6),
        {"wellbore_wall": 30e6},
        rollers={"symmetry_x": 0, "symmetry_y": 1},
    )
    umax = tmesh.comm.allreduce(np.abs(sol.displacement.x.array).max(initial=0.0), op=MPI.MAX)
    assert umax < 1e-15


def test_rank_independence_of_wall_stress():
    theta = np.linspace(0, np.pi / 2, 7)
    world, _ = wall_hoop_stress(MPI.COMM_WORLD, 0.007, 38e6, 34e6, 20e6, theta)
    alone, _ = wall_hoop_stress(MPI.COMM_SELF, 0.007, 38e6, 34e6, 20e6, theta)
    assert np.allclose(world, alone, rtol=1e-8, atol=1e-6 * MPa)
