"""Richardson extrapolation: limit and order recovered from synthetic sequences."""

import math

import numpy as np
import pytest

from hfcdem.workflows.richardson import Extrapolation, extrapolate, observed_order


@pytest.mark.parametrize(
    ("limit", "c", "p", "h"),
    [
        (3.0, 2.0, 1.5, [0.05, 0.08, 0.2]),  # ratios 1.6 and 2.5
        (3.0, 2.0, 1.5, [0.2, 0.05, 0.37, 0.08]),  # unsorted; the coarsest is left out
        (-1.0, 0.3, 2.7, [0.01, 0.017, 0.05]),
        (64.0, -5.0, 0.5, [1e-3, 3e-3, 4e-3]),  # from below, ratios 3 and 1.33
        (19.6, 40.0, 1.0, [0.005, 0.01, 0.02]),  # uniform ratio 2, first order
    ],
)
def test_limit_and_order_of_a_power_law(limit, c, p, h):
    f = [limit + c * x**p for x in h]
    e = extrapolate(h, f)
    finest = limit + c * min(h) ** p
    assert e.method == "richardson" and e.extrapolated
    assert e.limit == pytest.approx(limit, abs=1e-10)
    assert e.order == pytest.approx(p, abs=1e-10)
    assert e.finest == finest
    assert e.error == pytest.approx(abs(finest - limit), rel=1e-8)


def test_order_at_a_uniform_ratio_matches_the_closed_form():
    h = np.array([0.1, 0.2, 0.4])
    f = np.array([1.0, 1.3, 2.2])  # differences 0.3 and 0.9: p = log2(3)
    assert observed_order(h, f) == pytest.approx(math.log2(3.0), abs=1e-12)


def test_a_sequence_that_is_not_monotone_falls_back_to_the_two_finest():
    e = extrapolate([0.1, 0.2, 0.4], [1.0, 1.2, 1.1])
    assert e.method == "two-finest: not monotone" and not e.extrapolated
    assert e.limit is None and e.order is None
    assert e.error == pytest.approx(0.2)
    assert observed_order([0.1, 0.2, 0.4], [1.0, 1.2, 1.1]) is None


def test_differences_that_grow_as_h_falls_are_diverging():
    h = [1.0, 2.0, 3.0]
    e = extrapolate(h, [5.0 + x**-0.5 for x in h])
    assert e.method.startswith("two-finest: diverging")
    assert e.order == pytest.approx(-0.5, abs=1e-10) and e.limit is None
    assert e.error == pytest.approx(1.0 - 2.0**-0.5)


def test_few_or_missing_answers():
    two = extrapolate([0.1, 0.2, 0.4], [1.0, float("nan"), 1.5])  # no breakdown at 0.2
    assert two.method == "two-finest: two answers" and two.error == pytest.approx(0.5)
    assert two.cases == 2
    one = extrapolate([0.1], [2.0])
    assert one.method.startswith("none") and math.isnan(one.error) and one.finest == 2.0
    assert extrapolate([], []).method.startswith("none")
    same = extrapolate([0.1, 0.2, 0.4], [7.0, 7.0, 7.0])
    assert same.limit == 7.0 and same.error == 0.0


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="distinct"):
        extrapolate([0.1, 0.1, 0.2], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="same length"):
        extrapolate([0.1, 0.2], [1.0])
    with pytest.raises(ValueError, match="error"):
        Extrapolation(1.0, None, -0.1, None, "two-finest: two answers", 2)
    with pytest.raises(ValueError, match="method"):
        Extrapolation(1.0, None, 0.1, None, "guess", 2)
