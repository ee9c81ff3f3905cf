"""Breakdown detection on pressure histories."""

import numpy as np
import pytest

from hfcdem.workflows.breakdown import detect_breakdown


def test_peak_then_sustained_drop():
    t = np.linspace(0, 10, 101)
    p = np.where(t < 6, 10 * t, 60 - 20 * (t - 6))
    found = detect_breakdown(t, p, drop_fraction=0.05)
    assert found is not None
    assert found.pressure == pytest.approx(60.0)
    assert found.time == pytest.approx(6.0)
    assert found.confirmed_at > found.time


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
