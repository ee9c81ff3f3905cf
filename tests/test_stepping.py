"""The step controller against hand-worked sequences: growth, halving, event location."""

import math

import pytest

from hfcdem.coupling.stepping import StepController


def test_easy_steps_grow_by_the_factor_up_to_dt_max():
    c = StepController(dt=1.0, dt_min=0.1, dt_max=3.0, growth=1.5)
    sizes = []
    for _ in range(4):
        dt = c.dt
        c.accepted(dt, changed=False, newton_iterations=3)
        sizes.append(c.dt)
    assert sizes == pytest.approx([1.5, 2.25, 3.0, 3.0])


def test_a_hard_or_eventful_step_does_not_grow():
    c = StepController(dt=1.0, dt_min=0.1, dt_max=3.0, growth=1.5, easy_iterations=6)
    c.accepted(1.0, changed=False, newton_iterations=7)
    assert c.dt == 1.0
    c.step_ratio = 0.4
    c.accepted(1.0, changed=True, newton_iterations=1)
    assert c.dt == 1.0
    assert c.last_ratio == 1.0  # states changed: the next break is located afresh
    c.accepted(1.0, changed=False, newton_iterations=1)
    assert c.last_ratio == 0.4 and c.dt == 1.5


def test_halving_stops_below_dt_min():
    c = StepController(dt=1.0, dt_min=0.3, dt_max=1.0)
    assert c.halve(1.0) and c.dt == 0.5
    assert not c.halve(0.5) and c.dt == 0.25


def test_limit_and_retry():
    c = StepController(dt=2.0, dt_min=0.1, dt_max=5.0)
    c.limit(0.7)
    assert c.dt == 0.7
    c.limit(5.0)
    assert c.dt == 0.7
    c.retry_with(0.2)
    assert c.dt == 0.2


def test_a_pressure_jump_halves_the_step():
    c = StepController(dt=1.0, dt_min=0.1, dt_max=1.0, max_pressure_change=0.1)
    assert c.pressure_cut(1.0, 10e6, 11.5e6) == 0.5  # 15 % > 10 %
    assert c.pressure_cut(1.0, 10e6, 10.9e6) is None  # 9 %
    # at least 1 MPa wide: 0.2 MPa from zero is 20 % of 1 MPa
    assert c.pressure_cut(1.0, 0.0, 0.2e6) == 0.5
    assert c.pressure_cut(1.0, 0.0, 0.05e6) is None
    assert c.pressure_cut(0.4, 10e6, 20e6) is None  # not above 4 dt_min: no cut
    assert c.pressure_cuts == 2  # the halvings counted


def test_the_step_lands_on_the_next_break():
    """Failure ratio r(t) = 0.2 + 0.4 t: a 4 s step overshoots to 1.8, 2 s lands on 1."""
    c = StepController(dt=4.0, dt_min=0.01, dt_max=4.0, break_tolerance=0.01)
    c.last_ratio = 0.2
    ratio = lambda dt: 0.2 + 0.4 * dt  # noqa: E731
    shorter = c.overshoot(4.0, ratio(4.0))
    assert shorter == pytest.approx(2.0)  # (1 - 0.2) / (1.8 - 0.2) of 4 s
    assert c.event_cuts == 1
    assert c.overshoot(shorter, ratio(shorter)) is None
    assert c.landed(ratio(shorter))
    assert c.step_ratio == pytest.approx(1.0)


def test_event_cuts_are_clipped_floored_and_limited():
    c = StepController(dt=1.0, dt_min=0.1, dt_max=1.0, max_event_cuts=2)
    assert c.overshoot(1.0, 100.0) == pytest.approx(0.1)  # 5 % of 1 s, floored to dt_min
    assert c.overshoot(1.0, 1.02) == pytest.approx(0.9)  # 98 % clipped to 90 %
    assert c.overshoot(1.0, 2.0) is None  # two cuts made: the break is taken as it comes
    assert c.step_ratio == 2.0
    c.broke()
    assert c.overshoot(1.0, 2.0) == pytest.approx(0.5)
    assert c.overshoot(1.0, math.inf) is None  # zero strength: no location
    assert not c.landed(math.inf)


def test_a_jump_after_a_state_change_is_cut_only_when_the_load_could_have_made_it():
    """No. 4 coarse: a contact switch took the ratio from 0.75 to 1.29 within a 2 s step."""
    c = StepController(dt=2.0, dt_min=0.01, dt_max=2.0)
    c.last_ratio = 0.749
    assert c.overshoot(2.0, 1.291, switched=True) == pytest.approx(2.0 * 0.251 / 0.542)
    # a loose block: 4e5 at any step, so no cut lands on it (the line puts it at 2e-6)
    c.broke()
    c.last_ratio = 0.0
    assert c.overshoot(0.5, 438433.6, switched=True) is None
    assert c.event_cuts == 0 and c.step_ratio == pytest.approx(438433.6)
    assert c.overshoot(0.5, 438433.6) == pytest.approx(0.025)  # no switch: 5 % of the step


def test_within_tolerance_or_already_broken_is_not_cut():
    c = StepController(dt=1.0, dt_min=0.1, dt_max=1.0, break_tolerance=0.01)
    assert c.overshoot(1.0, 1.005) is None
    c.last_ratio = 1.2  # the last step ended past a break
    assert c.overshoot(1.0, 3.0) is None
    assert not c.landed(3.0)


def test_bad_limits_name_the_field():
    with pytest.raises(ValueError, match="dt_min"):
        StepController(dt=1.0, dt_min=0.0, dt_max=1.0)
    with pytest.raises(ValueError, match="growth"):
        StepController(dt=1.0, dt_min=0.1, dt_max=1.0, growth=0.5)
