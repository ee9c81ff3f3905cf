"""The group Newton: SNES on the flow balance of the pressure groups."""

import numpy as np
import pytest

from hfcdem.flow.newton import snes_solve, solve_groups


def test_a_group_with_no_storage_and_no_flow_keeps_its_pressure():
    # group 0 is the zero-volume cavity of a point injection at dt = 0: its residual is 0
    # whatever its pressure; group 1 closes at 5 MPa (a crack the stress holds shut)
    def residual(p, frozen):
        p = np.asarray(p, dtype=float)
        return np.stack([0.0 * p[0], 2.6e-10 * (p[1] - 5e6) * (1.0 + p[1] / 2.2e9)])

    guess = np.array([3e6, 5.02e6])
    solution = snes_solve(residual, guess, 1e-18, 20, "test_idle_")
    assert solution.converged, solution.failure
    assert solution.pressure[0] == 3e6
    assert solution.pressure[1] == pytest.approx(5e6, rel=1e-12)


def test_solve_groups_converges_on_a_coupled_pair():
    def residual(p, frozen):
        p = np.asarray(p, dtype=float)
        return np.stack([p[0] ** 2 - 4.0 - 0.1 * p[1], p[1] - 0.5 * p[0]])

    solution = solve_groups(residual, np.array([1.0, 1.0]), 1e-12, 30)
    assert solution.converged
    assert np.abs(residual(solution.pressure, None)).max() < 1e-12
