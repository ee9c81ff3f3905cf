"""The closed-form references, checked against each other and by quadrature."""

import numpy as np
import pytest
from scipy.integrate import quad

from hfcdem import analytic

E, NU, P, A = 210e9, 0.25, 22e6, 0.1


def test_sneddon_area_is_integral_of_opening():
    # x = a sin(t) removes the square-root endpoint singularity
    area, _ = quad(
        lambda t: analytic.sneddon_opening(A * np.sin(t), A, P, E, NU) * A * np.cos(t),
        -np.pi / 2,
        np.pi / 2,
    )
    assert area == pytest.approx(analytic.sneddon_area(A, P, E, NU), rel=1e-6)


def test_sneddon_table1_centre_opening():
    # (4 p / E') a with E' = E / (1 - nu^2)
    expected = 4 * P * A * (1 - NU**2) / E
    assert analytic.sneddon_opening(0.0, A, P, E, NU) == pytest.approx(expected)
    assert analytic.sneddon_opening(1.5 * A, A, P, E, NU) == 0.0


def test_penny_volume_is_integral_of_opening():
    vol, _ = quad(
        lambda t: (
            2
            * np.pi
            * A
            * np.sin(t)
            * analytic.penny_opening(A * np.sin(t), A, P, E, NU)
            * A
            * np.cos(t)
        ),
        0,
        np.pi / 2,
    )
    assert vol == pytest.approx(analytic.penny_volume(A, P, E, NU), rel=1e-6)


@pytest.mark.parametrize("theta", [0.0, 0.3, np.pi / 2])
def test_kirsch_field_meets_wall_and_far_field(theta):
    sh_max, sh_min, pw, a = 38e6, 34e6, 20e6, 0.035
    wall = analytic.kirsch_stress(a, theta, a, sh_max, sh_min, pw)
    assert wall.rr == pytest.approx(pw)
    assert wall.rt == pytest.approx(0.0, abs=1e-6)
    assert wall.tt == pytest.approx(analytic.kirsch_wall_hoop_stress(theta, sh_max, sh_min, pw))
    far = analytic.kirsch_stress(1e4 * a, theta, a, sh_max, sh_min, pw)
    c, s = np.cos(theta), np.sin(theta)
    assert far.rr == pytest.approx(sh_max * c**2 + sh_min * s**2, rel=1e-6)
    assert far.tt == pytest.approx(sh_max * s**2 + sh_min * c**2, rel=1e-6)


def test_kirsch_field_is_in_equilibrium():
    # radial equilibrium: d(s_rr)/dr + (1/r) d(s_rt)/dtheta + (s_rr - s_tt)/r = 0
    a, r, th, h = 0.035, 0.05, 0.4, 1e-7
    f = lambda r_, t_: analytic.kirsch_stress(r_, t_, a, 38e6, 34e6, 20e6)  # noqa: E731
    d_rr = (f(r + h, th).rr - f(r - h, th).rr) / (2 * h)
    d_rt = (f(r, th + h).rt - f(r, th - h).rt) / (2 * h)
    s = f(r, th)
    residual = d_rr + d_rt / r + (s.rr - s.tt) / r
    assert abs(residual) < 1e-6 * 38e6 / a


def test_hubbert_willis_is_kirsch_hoop_stress_reaching_strength():
    sh_max, sh_min, t = 6e6, 4e6, 3e6
    pb = analytic.hubbert_willis_breakdown(sh_max, sh_min, t)
    assert analytic.kirsch_wall_hoop_stress(0.0, sh_max, sh_min, pb) == pytest.approx(-t)


def test_haimson_fairhurst_values():
    # without poroelastic coupling a penetrating fluid halves the Hubbert-Willis value
    hw = analytic.hubbert_willis_breakdown(6e6, 4e6, 3e6)
    hf = analytic.haimson_fairhurst_breakdown(6e6, 4e6, 3e6, 0.0, biot=0.0, poisson_ratio=0.25)
    assert hf == pytest.approx(hw / 2)
    # biot 1, nu 0.25: eta = 1/3, Pb = (3 Sh - SH + T - 2/3 P0) / (4/3)
    hf = analytic.haimson_fairhurst_breakdown(6e6, 4e6, 3e6, 1e6, biot=1.0, poisson_ratio=0.25)
    assert hf == pytest.approx((12e6 - 6e6 + 3e6 - 2e6 / 3) * 0.75)


def test_kgd_viscosity_scaling_exponents():
    s1 = analytic.kgd_viscosity(10.0, 1e-4, 20e9, 0.2, 1e-3)
    s2 = analytic.kgd_viscosity(20.0, 1e-4, 20e9, 0.2, 1e-3)
    assert s2.half_length / s1.half_length == pytest.approx(2 ** (2 / 3))
    assert s2.inlet_opening / s1.inlet_opening == pytest.approx(2 ** (1 / 3))
    assert s2.net_pressure / s1.net_pressure == pytest.approx(2 ** (-1 / 3))


def test_kgd_toughness_net_pressure_opens_crack_to_half_length():
    s = analytic.kgd_toughness(10.0, 1e-4, 20e9, 0.2, 1e6)
    assert s.half_length / analytic.kgd_toughness(
        5.0, 1e-4, 20e9, 0.2, 1e6
    ).half_length == pytest.approx(2 ** (2 / 3))
    assert s.net_pressure == pytest.approx(1e6 / np.sqrt(np.pi * s.half_length))


def test_frustum_stack_of_a_cylinder_and_a_cone():
    assert analytic.frustum_volume([2, 2], [0, 3]) == pytest.approx(np.pi * 3)
    assert analytic.frustum_volume([2, 0], [0, 3]) == pytest.approx(np.pi * 3 / 3)
    assert analytic.frustum_lateral_area([2, 2], [0, 3]) == pytest.approx(2 * np.pi * 3)
    assert analytic.equal_volume_cylinder_diameter([2, 2, 2], [0, 1, 3]) == pytest.approx(2.0)
    with pytest.raises(ValueError, match="equal length"):
        analytic.frustum_volume([1, 2, 3], [0, 1])


def test_hole_wall_least_stress_is_kirsch_for_a_vertical_hole():
    # the lab specimen's wellbore: 3 Sh - SH = -3 MPa, along SH (x)
    stress = np.diag([6e6, 1e6, 15e6])
    least, where = analytic.hole_wall_least_stress(stress, (0, 0, 1), 0.23)
    assert least == pytest.approx(3 * 1e6 - 6e6, rel=1e-6)
    assert abs(where[0]) == pytest.approx(1.0)
    hoop = analytic.kirsch_wall_hoop_stress(0.0, 6e6, 1e6, 2e6)
    assert analytic.hole_wall_least_stress(stress, (0, 0, 1), 0.23, 2e6)[0] == pytest.approx(hoop)


def test_hole_wall_least_stress_of_antiplane_shear_and_rotations():
    # shear along the axis alone: tau_tz = 2 tau at the wall, least principal -2 tau
    tau = 1e6
    stress = np.array([[0.0, 0.0, tau], [0.0, 0.0, 0.0], [tau, 0.0, 0.0]])
    least, _ = analytic.hole_wall_least_stress(stress, (0, 0, 1), 0.25)
    assert least == pytest.approx(-2 * tau, rel=1e-4)
    # turning the stress and the hole together changes nothing
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    s = np.diag([6e6, 1e6, 15e6])
    axis = np.array([np.cos(0.5), np.sin(0.5), 0.0])
    a, wa = analytic.hole_wall_least_stress(s, axis, 0.23)
    b, wb = analytic.hole_wall_least_stress(q @ s @ q.T, q @ axis, 0.23)
    assert b == pytest.approx(a, rel=1e-4)
    assert abs(np.dot(q @ wa, wb)) == pytest.approx(1.0, abs=1e-3)  # the same wall point


def test_filtered_wall_breakdown_tends_to_hubbert_willis_and_rises_with_the_length():
    hw = analytic.hubbert_willis_breakdown(20e6, 12e6, 5e6)
    # the shift grows about linearly with l / a (+0.28 % at 1e-3): at 1e-4, +0.03 %
    short = analytic.filtered_wall_breakdown(0.03, 20e6, 12e6, 5e6, 3e-6)
    assert short == pytest.approx(hw, rel=5e-4)
    p3, p6 = (analytic.filtered_wall_breakdown(0.03, 20e6, 12e6, 5e6, lv) for lv in (3e-3, 6e-3))
    assert hw < p3 < p6
