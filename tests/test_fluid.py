"""The fluid, the pump schedule and Carter leak-off."""

import numpy as np
import pytest
from scipy.integrate import quad

from hfcdem.flow.fluid import CarterLeakOff, Fluid, Injection


def test_cubic_law():
    fluid = Fluid(viscosity=1e-3)
    assert fluid.conductivity(np.array([1e-3]))[0] == pytest.approx(1e-9 / 12e-3)


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"viscosity": -1.0}, "viscosity"),
        ({"bulk_modulus": 0.0}, "bulk_modulus"),
        ({"residual_aperture": -1e-6}, "residual_aperture"),
        ({"gravity": (0.0, "x")}, "could not convert|gravity"),
    ],
)
def test_bad_fluid_names_the_field(kwargs, key):
    with pytest.raises(ValueError, match=key):
        Fluid(**kwargs)


def test_rate_schedule_volume_is_exact_for_linear_pieces():
    inj = Injection.rate_schedule([(0.0, 0.0), (10.0, 1e-3), (20.0, 1e-3)])
    assert inj.value_at(5.0) == pytest.approx(5e-4)
    assert inj.volume_between(0.0, 20.0) == pytest.approx(0.5 * 10 * 1e-3 + 10 * 1e-3)
    assert inj.volume_between(4.0, 12.0) == pytest.approx(0.5 * (4e-4 + 1e-3) * 6.0 + 2.0 * 1e-3)
    assert Injection.constant_rate(2e-6).volume_between(1.0, 3.0) == pytest.approx(4e-6)


def test_bad_schedules_are_named():
    with pytest.raises(ValueError, match="increasing"):
        Injection.rate_schedule([(1.0, 1e-6), (0.5, 1e-6)])
    with pytest.raises(ValueError, match="injection rate"):
        Injection.constant_rate(-1e-6)
    with pytest.raises(ValueError, match="no prescribed volume"):
        Injection.pressure_schedule([(0.0, 1e6)]).volume_between(0.0, 1.0)


def test_carter_volume_is_the_integral_of_the_leak_off_rate():
    # independent of the implementation: integrate q = 2 faces x A x C_L / sqrt(t - t_wet)
    # numerically (QUADPACK, with the inverse square-root end point as its weight)
    coefficient, area, t_wet = 1e-4, 2.0, 1.0
    lo = CarterLeakOff(coefficient)

    def integral(t0: float, t1: float) -> float:
        a = max(t0, t_wet)
        value, _ = quad(lambda t: 2.0 * area * coefficient, a, t1, weight="alg", wvar=(-0.5, 0))
        return (
            value
            if a == t_wet
            else quad(lambda t: 2 * area * coefficient / np.sqrt(t - t_wet), a, t1)[0]
        )

    for t0, t1 in [(1.0, 5.0), (0.0, 3.0), (2.0, 2.5)]:
        v = lo.volume(np.array([area]), np.array([t_wet]), t0, t1)[0]
        assert v == pytest.approx(integral(t0, t1), rel=1e-9)
    # additive over split intervals, nothing before the facet is wet
    a = lo.volume(np.array([area]), np.array([t_wet]), 1.0, 3.0)[0]
    b = lo.volume(np.array([area]), np.array([t_wet]), 3.0, 5.0)[0]
    assert a + b == pytest.approx(lo.volume(np.array([area]), np.array([t_wet]), 1.0, 5.0)[0])
    assert lo.volume(np.array([area]), np.array([np.inf]), 1.0, 5.0)[0] == 0.0
    assert lo.volume(np.array([area]), np.array([4.0]), 1.0, 3.0)[0] == 0.0
