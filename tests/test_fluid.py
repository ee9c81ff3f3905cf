"""Carter leak-off against an independent integral of its rate."""

import numpy as np
import pytest
from scipy.integrate import quad

from hfcdem.flow.fluid import CarterLeakOff


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
