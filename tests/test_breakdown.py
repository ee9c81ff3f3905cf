"""Breakdown detection on pressure histories."""

import numpy as np
import pytest

from hfcdem.coupling.breakdown import breakdown_note, detect_breakdown


def test_peak_then_sustained_drop():
    t = np.linspace(0, 10, 101)
    p = np.where(t < 6, 10 * t, 60 - 20 * (t - 6))
    found = detect_breakdown(t, p, drop_fraction=0.05)
    assert found is not None
    assert found.pressure == pytest.approx(60.0)
    assert found.time == pytest.approx(6.0)
    assert found.confirmed_at > found.time
    assert found.drop == pytest.approx(80.0)  # to the last record's -20
    assert found.relative_drop == pytest.approx(80.0 / 60.0)


def test_rising_or_wobbling_history_has_no_breakdown():
    t = np.linspace(0, 10, 101)
    assert detect_breakdown(t, 5 * t) is None
    wobble = 5 * t + 0.5 * np.sin(20 * t)
    assert detect_breakdown(t, wobble, drop_fraction=0.05) is None


def test_bad_arguments():
    with pytest.raises(ValueError, match="drop_fraction"):
        detect_breakdown([0, 1], [0, 1], drop_fraction=1.5)
    with pytest.raises(ValueError, match="same length"):
        detect_breakdown([0, 1], [0])


def test_propagation_from_an_open_crack_has_no_breakdown():
    # KGD: from the initial state the first step jumps up, then the pressure only falls
    t = np.linspace(0, 10, 21)
    p = np.concatenate([[0.0], 1.2 * (t[1:] / t[1]) ** (-1 / 3)])
    assert detect_breakdown(t, p) is None
    assert "open crack" in breakdown_note(p, None, open_crack=True)
    assert "not resolved" in breakdown_note(p, None, open_crack=False)
    # a later, higher peak that drops is still found
    q = np.concatenate([p[:10], [2.0, 3.0, 2.0, 1.5, 1.2, 1.0, 0.9, 0.8, 0.7, 0.6, 0.5]])
    found = detect_breakdown(t, q)
    assert found is not None and found.pressure == 3.0 and found.time == t[11]


def test_breakdown_note_says_why_there_is_none():
    t = np.linspace(0, 10, 101)
    assert breakdown_note(5 * t, None, open_crack=False).startswith("the pressure still rises")
    found = detect_breakdown(t, np.where(t < 6, 10 * t, 60 - 20 * (t - 6)))
    assert breakdown_note(np.where(t < 6, 10 * t, 60 - 20 * (t - 6)), found, False) is None


def test_a_run_cut_short_by_the_validity_limit_says_its_peak_is_a_lower_bound():
    # the lab at 45 deg, viscous flow (coarse): a cascade cuts blocks loose at 1.03 s while
    # the pressure still swings, so no drop confirms a peak
    p = [0.0, 2.1, 4.3, 6.39, 8.14, 7.86]
    note = breakdown_note(p, detect_breakdown(range(len(p)), p), False, validity_limit=True)
    assert note is not None and "validity limit" in note and "lower bound" in note
    # a solver's stop before the planned end leaves the same doubt
    said = breakdown_note(p, detect_breakdown(range(len(p)), p), False, stopped=True)
    assert said == (
        "the run stopped before a drop confirmed a peak: its highest pressure is a lower bound"
    )
    # a confirmed peak that the pressure regained before the stop
    q = [0.0, 2.0, 4.0, 6.0, 5.0, 4.9, 4.8, 4.7, 6.5, 7.5]
    found = detect_breakdown(range(len(q)), q)
    assert found is not None and found.pressure == 6.0
    assert breakdown_note(q, found, False) is None  # the planned end: the peak stands
    assert breakdown_note(q, found, False, stopped=True).startswith(
        "the pressure rose past it before the run stopped"
    )
    # the same history when the run reached its end: only the drop is too short
    assert breakdown_note(p, None, False) == "no sustained drop after the peak"
    # a confirmed breakdown has no note, however the run ended
    q = [0.0, 2.0, 6.0, 3.0, 2.5, 2.0, 1.5]
    found = detect_breakdown(range(len(q)), q)
    assert found is not None and breakdown_note(q, found, False, validity_limit=True) is None
    # the lab at 30 deg (coarse): a drop confirms 4.61 MPa, the pressure climbs to 10.12 MPa
    # and the validity limit ends the run before a drop can confirm that
    r = [0.0, 2.4, 4.61, 3.2, 3.3, 3.4, 5.0, 7.5, 10.12, 9.9]
    found = detect_breakdown(range(len(r)), r)
    assert found is not None and found.pressure == 4.61
    # its depth stops where the pressure regains the peak: the dip to 3.2, not the end
    assert found.drop == pytest.approx(4.61 - 3.2)
    note = breakdown_note(r, found, False, validity_limit=True)
    assert note is not None and "at least the highest pressure" in note
    assert breakdown_note(r, found, False) is None  # at the planned end: the drop stands


def test_a_lower_peak_the_pressure_regains_is_not_the_breakdown():
    # the Rubin case at its default mesh (history.csv, MPa): the slot-end facets break at
    # 1.58 MPa, the pressure dips for three records, then rises to the breakdown at 6.23
    t = [9.95, 10.05, 10.09, 10.15, 10.22, 10.31, 10.45, 10.67, 10.98, 11.46, 12.18, 13.18]
    p = [1.380, 1.482, 1.576, 1.294, 1.401, 1.561, 1.801, 2.161, 2.700, 3.504, 4.686, 6.230]
    t += [14.18, 15.18, 16.18, 17.18]
    p += [4.969, 4.072, 3.6, 3.2]
    found = detect_breakdown(t, p)
    assert found is not None
    assert found.pressure == pytest.approx(6.23e0) and found.time == 13.18
    assert found.confirmed_at == 16.18
    assert found.drop == pytest.approx(6.23 - 3.2)
    # cut before the second peak drops, the first dip alone is a (confirmed) breakdown
    early = detect_breakdown(t[:8], p[:8])
    assert early is not None and early.pressure == pytest.approx(1.576)
