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


@pytest.mark.serial
def test_interface_frames_at_the_output_times(tmp_path):
    from mpi4py import MPI

    from hfcdem.io.series import InterfaceFrames

    (tmp_path / "joints").mkdir()
    (tmp_path / "joints" / "frame_0099.vtu").write_text("an earlier run's")
    frames = InterfaceFrames(tmp_path, "joints", 10.0, 2.5, MPI.COMM_SELF)
    assert not (tmp_path / "joints" / "frame_0099.vtu").exists()
    points = np.zeros((1, 2, 3))
    points[0, 1, 0] = 1.0
    wrote = [frames.offer(t, points, {"s": np.array([t])}) for t in (0.0, 1.0, 2.5, 3.0, 8.0, 10.0)]
    assert wrote == [True, False, True, False, True, True]  # 8 s: one frame for 5 and 7.5
    assert [t for t, _ in read_pvd(tmp_path / "joints.pvd")] == [0.0, 2.5, 8.0, 10.0]
    assert (tmp_path / "joints" / "frame_0003.vtu").exists()
    with pytest.raises(ValueError, match="output interval"):
        InterfaceFrames(tmp_path, "joints", 10.0, 0.0, MPI.COMM_SELF)
