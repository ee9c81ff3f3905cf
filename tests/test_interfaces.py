"""Interface strengths, failure criteria and the breaking rules (plain NumPy)."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.solid.interfaces import (
    FacetState,
    check_failure,
    select_breaking,
    stable_facet_hash,
    weibull_scatter,
)


def test_tension_cut_off_and_mohr_coulomb():
    t0, c0, mu = np.array([3e6] * 4), np.array([17e6] * 4), math.tan(math.radians(40))
    tn = np.array([3e6, 2.9e6, -10e6, -10e6])
    tau = np.array([0.0, 0.0, 17e6 + 10e6 * mu, 17e6 + 10e6 * mu - 1e3])
    check = check_failure(tn, tau, t0, c0, mu)
    assert check.ratio[0] == pytest.approx(1.0)
    assert check.ratio[1] < 1.0
    assert check.ratio[2] == pytest.approx(1.0)
    assert check.ratio[3] < 1.0
    assert check.mode[0] == FacetState.TENSILE
    assert check.mode[2] == FacetState.SHEAR


def test_tension_wins_when_both_criteria_hold():
    check = check_failure(np.array([5e6]), np.array([50e6]), np.array([3e6]), np.array([1e6]), 0.5)
    assert check.ratio[0] >= 1.0
    assert check.mode[0] == FacetState.TENSILE


def test_zero_strengths_give_finite_decisions_not_nan():
    check = check_failure(
        np.array([1.0, -1e6, 0.0]), np.array([0.0, 1.0, 0.0]), np.zeros(3), np.zeros(3), 0.0
    )
    assert not np.any(np.isnan(check.ratio))
    assert check.ratio[0] >= 1.0  # any tension breaks with T0 = 0
    assert check.ratio[1] >= 1.0  # any shear breaks without cohesion and friction
    assert check.ratio[2] == 0.0  # no load, no failure


def test_facet_hash_is_order_independent_and_seeded():
    ids = np.array([[1, 5, 9], [2, 3, 4], [7, 8, 100]])
    u = stable_facet_hash(ids, seed=3)
    assert np.array_equal(u[::-1], stable_facet_hash(ids[::-1, ::-1], seed=3))
    assert not np.array_equal(u, stable_facet_hash(ids, seed=4))
    assert np.all((u > 0) & (u < 1))


def test_weibull_scatter_keeps_the_mean_and_narrows_with_modulus():
    ids = np.arange(60000).reshape(-1, 2)
    u = stable_facet_hash(ids, seed=1)
    wide, narrow = weibull_scatter(3e6, 2.0, u), weibull_scatter(3e6, 20.0, u)
    assert wide.mean() == pytest.approx(3e6, rel=0.02)
    assert narrow.mean() == pytest.approx(3e6, rel=0.02)
    assert narrow.std() < wide.std() / 5


def test_break_rules_pick_the_same_facets_on_any_rank_count():
    comm = MPI.COMM_WORLD
    # every rank holds a different slice of the same global set
    ratio_all = np.array([0.5, 1.2, 3.0, 1.0, 2.0, 3.0])
    keys_all = np.arange(18, dtype=float).reshape(6, 3)
    mine = np.arange(comm.rank, 6, comm.size)
    ratio, keys = ratio_all[mine], keys_all[mine]
    for rule, count, expected in (
        ("all", 1, {1, 2, 3, 4, 5}),
        ("most_overstressed", 1, {2}),
        ("cap", 3, {2, 5, 4}),
    ):
        chosen = select_breaking(ratio, keys, rule, count, comm)
        picked = set().union(*comm.allgather({int(mine[i]) for i in chosen}))
        assert picked == expected, rule
