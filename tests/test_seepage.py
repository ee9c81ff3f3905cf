"""Seepage through intact joints: mass balance, an equivalent porous medium, ranks.

A plate [0, 1] x [0, 0.25] meshed with crossed diagonals (a lattice with no
x-y coupling, so its steady profile is exactly linear) has every interior facet
as a joint of the perforation paper's aperture.  Its equivalent conductivity
and storage make the joint network a 1D diffusion with ``D = k_eq / s_eq``,
checked against ``p0 erfc(x / 2 sqrt(D t))`` before the front reaches x = 1.
"""

import math

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import tag_sides

from hfcdem.config.materials import ElasticMaterial, Fluid, InSituStress, InterfaceModel
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.seepage import INITIAL_JOINT_APERTURE, JointSeepage, joint_network
from hfcdem.solid.cdem import CDEMSolid

L, H, P0 = 1.0, 0.25, 1e6
FLUID = Fluid()  # water: 1 mPa s, Kw = 2.2 GPa
TAUS = (0.015, 0.03)  # D t / L^2 at which the front is compared: erfc(L / 2 sqrt(D t)) < 5e-5


def _plate(nx: int, comm: MPI.Comm = MPI.COMM_WORLD) -> CDEMSolid:
    mesh = dolfinx.mesh.create_rectangle(
        comm,
        [[0.0, 0.0], [L, H]],
        [nx, max(nx // 4, 1)],
        diagonal=dolfinx.mesh.DiagonalType.crossed,
        ghost_mode=dolfinx.mesh.GhostMode.shared_facet,
    )
    return CDEMSolid(
        tag_sides(mesh, L),
        ElasticMaterial(10e9, 0.25),
        InSituStress(1e6, 0.5e6),
        InterfaceModel(alpha=100, tensile_strength=1e6),
    )


def _seepage(solid: CDEMSolid, sides: list[str], aperture=INITIAL_JOINT_APERTURE) -> JointSeepage:
    net = joint_network(solid, cavity_vertices(solid, sides, None))
    return JointSeepage(net, aperture, FLUID)


def _equivalent(solid: CDEMSolid) -> tuple[float, float, float, float]:
    """k_eq, s_eq per unit plate area, steady error against the linear profile, flux mismatch."""
    sp = _seepage(solid, ["left", "right"])
    left = sp.net.centroid[sp.cavity_facets, 0] < 0.5 * L
    pc = np.where(left, P0, 0.0)
    p = sp.steady(pc)
    q = sp.inflow(pc, p)
    q_in, q_out = float(q[left].sum()), float(q[~left].sum())
    linear = P0 * (1.0 - sp.net.centroid[:, 0] / L)
    k_eq = q_in / (H * P0 / L)
    s_eq = float(sp.storage.sum()) / (L * H)
    return k_eq, s_eq, float(np.abs(p - linear).max() / P0), abs(q_in + q_out) / q_in


def _front(solid: CDEMSolid, steps: int) -> tuple[list[float], np.ndarray]:
    """Max error / p0 against erfc at each of TAUS, and the final pressures."""
    k_eq, s_eq, _, _ = _equivalent(solid)
    diff = k_eq / s_eq
    sp = _seepage(solid, ["left"])
    x = sp.net.centroid[:, 0]
    dt = TAUS[-1] * L * L / diff / steps
    errors = []
    for k in range(1, steps + 1):
        p = sp.step(dt, P0)
        if any(k == round(tau / TAUS[-1] * steps) for tau in TAUS):
            scale = 2.0 * math.sqrt(diff * k * dt)
            exact = P0 * np.array([math.erfc(xi / scale) for xi in x])
            errors.append(float(np.abs(p - exact).max() / P0))
    return errors, p


def test_steady_plate_is_linear_and_conserves():
    nx, ny = 16, 4
    k_eq, s_eq, linear_error, mismatch = _equivalent(_plate(nx))
    assert linear_error < 2e-14  # measured 5.1e-15: every facet on the linear profile
    assert mismatch < 1e-13  # inflow = outflow, measured 3.4e-14
    # storage: aperture x joint length / Kw; the joints are the interior facets
    # (4 half-diagonals per cell and the interior grid lines)
    h = L / nx
    length = nx * ny * 2.0 * math.sqrt(2.0) * h + (nx - 1) * H + (ny - 1) * L
    assert s_eq == pytest.approx(INITIAL_JOINT_APERTURE * length / FLUID.bulk_modulus / (L * H))
    assert k_eq == pytest.approx(3.607023e-13, rel=1e-6)  # regression: 1D flux / gradient


def test_mass_balance_every_step():
    solid = _plate(16)
    net = joint_network(solid, cavity_vertices(solid, ["left"], None))
    rng = np.random.default_rng(14)
    aperture = INITIAL_JOINT_APERTURE * rng.lognormal(0.0, 0.5, net.size)
    sp = JointSeepage(net, aperture, FLUID)
    stored, worst, total = sp.stored(), 0.0, 0.0
    for k in range(60):
        dt = 1e-4 if k < 30 else 3e-4  # a change of dt refactorises
        sp.step(dt, P0 * min(1.0, (k + 1) / 20))
        gained = sp.stored() - stored
        stored += gained
        injected = sp.flux_into_network()
        total += injected
        assert injected > 0.0
        worst = max(worst, abs(injected - gained) / abs(gained))
    assert worst < 1e-13  # measured 4.3e-14
    assert abs(total - sp.stored()) / sp.stored() < 1e-14  # measured 1e-15


def test_front_converges_with_mesh():
    errors = {nx: _front(_plate(nx), 400)[0] for nx in (8, 16, 32)}
    for e, expected in zip(errors[32], (5.865e-3, 3.718e-3), strict=True):
        assert e == pytest.approx(expected, rel=0.01)
    for tau in range(len(TAUS)):
        e8, e16, e32 = (errors[nx][tau] for nx in (8, 16, 32))
        assert e8 / e16 > 2.6 and e16 / e32 > 2.25  # measured 2.68-3.05, 2.29-2.37


def test_front_converges_with_time_step():
    solid = _plate(32)
    runs = {steps: _front(solid, steps) for steps in (50, 100, 200, 1600)}
    errors = [runs[s][0][-1] for s in (50, 100, 200)]
    assert errors[0] > errors[1] > errors[2]
    assert errors == pytest.approx([6.054e-3, 4.711e-3, 4.049e-3], rel=0.01)
    # implicit Euler: the distance to the converged-in-time solution halves with dt
    fine = runs[1600][1]
    gaps = [float(np.abs(runs[s][1] - fine).max()) / P0 for s in (50, 100, 200)]
    # first order against a reference at dt / 32, dt / 16: (32 - 1) / (16 - 1), (16 - 1) / (8 - 1)
    assert gaps[0] / gaps[1] == pytest.approx(31 / 15, rel=0.01)  # measured 2.066
    assert gaps[1] / gaps[2] == pytest.approx(15 / 7, rel=0.01)  # measured 2.143


def test_same_pressures_on_any_number_of_ranks():
    comm = MPI.COMM_WORLD
    pressures = []
    for c in (comm, MPI.COMM_SELF):
        sp = _seepage(_plate(16, c), ["left"])
        for _ in range(20):
            p = sp.step(2e-4, P0)
        pressures.append(p)
    difference = float(np.abs(pressures[0] - pressures[1]).max())
    assert comm.allreduce(difference, op=MPI.MAX) == 0.0
    gathered = comm.allgather(pressures[0])
    assert all(np.array_equal(g, gathered[0]) for g in gathered)


def test_bad_input_is_refused():
    solid = _plate(8)
    net = joint_network(solid, cavity_vertices(solid, ["left"], None))
    with pytest.raises(ValueError, match=r"aperture .* > 0 m"):
        JointSeepage(net, -5e-6, FLUID)
    with pytest.raises(ValueError, match=r"aperture must be one value or"):
        JointSeepage(net, np.full(net.size + 1, INITIAL_JOINT_APERTURE), FLUID)
    sp = JointSeepage(net, INITIAL_JOINT_APERTURE, FLUID)
    for dt in (0.0, -1.0):
        with pytest.raises(ValueError, match=r"dt must be > 0 s"):
            sp.step(dt, P0)
    with pytest.raises(ValueError, match=r"dt must be finite \(s\)"):
        sp.step(math.nan, P0)
    with pytest.raises(ValueError, match=r"cavity_pressure must be finite \(Pa\)"):
        sp.step(1e-4, math.inf)
    with pytest.raises(ValueError, match=r"cavity_pressure must be one value or"):
        sp.step(1e-4, np.zeros(len(sp.cavity_facets) + 1))
    with pytest.raises(ValueError, match=r"pressure must be finite \(Pa\)"):
        JointSeepage(net, INITIAL_JOINT_APERTURE, FLUID, pressure=math.nan)
    with pytest.raises(ValueError, match=r"facets must be local interface indices"):
        joint_network(solid, np.zeros(0, np.int64), [solid.num_facets])
