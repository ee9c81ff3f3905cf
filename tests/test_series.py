"""Fields over time: output times, the PVD collection, and frames kept across a resume."""

import numpy as np
import pytest

from hfcdem.io.series import output_times, pvd_text, read_pvd


def test_output_times_cover_the_run_and_end_on_its_end():
    assert output_times(0.0, 10.0, 2.5) == pytest.approx([2.5, 5.0, 7.5, 10.0])
    assert output_times(0.0, 10.0, 3.0) == pytest.approx([3.0, 6.0, 9.0, 10.0])
    assert output_times(4.0, 10.0, 5.0) == pytest.approx([5.0, 10.0])  # a resumed run
    assert output_times(5.0, 10.0, 5.0) == pytest.approx([10.0])
    assert np.all(np.diff(output_times(0.0, 1.0, 1e-3)) > 0)


def test_pvd_round_trips(tmp_path):
    frames = [(0.0, "interfaces/frame_0000.vtu"), (2.5, "interfaces/frame_0001.vtu")]
    path = tmp_path / "interfaces.pvd"
    path.write_text(pvd_text(frames))
    assert read_pvd(path) == frames
    assert read_pvd(tmp_path / "missing.pvd") == []
