"""The fluid record per facet: defaults, round trips, independent copies."""

import math

import numpy as np
import pytest

from hfcdem.coupling.fluidstate import FluidState, facet_keys


def test_keys_are_sorted_vertex_ids():
    assert facet_keys(np.array([[5, 2], [1, 3]])) == [(2, 5), (1, 3)]


def test_unknown_facets_are_dry_and_empty():
    content, wet_since, pressure = FluidState().on([(1, 2), (2, 3)])
    assert content.tolist() == [0.0, 0.0]
    assert wet_since.tolist() == [math.inf, math.inf]
    assert pressure.tolist() == [0.0, 0.0]


def test_store_then_on_gives_the_values_back_in_any_order():
    state = FluidState()
    keys = [(1, 2), (2, 3), (3, 4)]
    state.store(keys, np.array([1.0, 2.0, 3.0]), np.array([0.5, math.inf, 1.5]), np.ones(3))
    content, wet_since, _ = state.on([(3, 4), (9, 9), (1, 2)])
    assert content.tolist() == [3.0, 0.0, 1.0]
    assert wet_since.tolist() == [1.5, math.inf, 0.5]
    # storing a subset keeps the others
    state.store([(2, 3)], np.array([7.0]), np.array([2.0]), np.array([5.0]))
    assert state.on(keys)[0].tolist() == [1.0, 7.0, 3.0]


def test_a_copy_is_independent_and_restores():
    state = FluidState()
    state.store([(1, 2)], np.array([1.0]), np.array([0.0]), np.array([2.0]))
    saved = state.copy()
    state.store([(1, 2), (2, 3)], np.array([9.0, 4.0]), np.array([0.0, 1.0]), np.zeros(2))
    assert saved.content == {(1, 2): 1.0}
    state.restore(saved)
    assert state == saved
    state.store([(1, 2)], np.array([5.0]), np.array([0.0]), np.array([0.0]))
    assert saved.content == {(1, 2): 1.0}  # restore copied, it did not alias


def test_store_needs_one_value_per_key():
    with pytest.raises(ValueError, match="wet_since"):
        FluidState().store([(1, 2)], np.ones(1), np.ones(2), np.ones(1))
