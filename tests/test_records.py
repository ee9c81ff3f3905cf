"""Step records: the history row round trip and the progress line."""

import math

from hfcdem.coupling.records import SimulationStopped, StepRecord


def _record(time=2.0, wall=10.0):
    return StepRecord(
        time=time, dt=0.5, injection_pressure=12.5e6, injected_volume=1e-3, cavity_fluid=0.1,
        fracture_fluid=2e-4, fracture_volume=2e-4, leaked_volume=0.0, mass_error=1e-15,
        volume_mismatch=1e-12, wet_facets=7, tensile=3, shear=1, fracture_degree=0.01,
        newton_iterations=4, rebuilds=9, wall_time=wall, held_shut=2,
    )  # fmt: skip


def test_a_row_reads_back_with_counts_as_integers():
    rec = _record()
    row = {k: str(v) for k, v in rec.as_row().items()}
    back = StepRecord.from_row(row)
    assert back == rec
    assert isinstance(back.tensile, int) and isinstance(back.time, float)
    assert isinstance(back.held_shut, int)


def test_a_row_written_before_the_held_shut_column_reads_back_as_none_held():
    row = {k: str(v) for k, v in _record().as_row().items() if k != "held_shut"}
    assert StepRecord.from_row(row).held_shut == 0


def test_the_progress_line_estimates_the_time_left():
    line = _record(time=2.0, wall=10.0).progress_line(t_end=6.0)
    assert "p   12.5000 MPa" in line and "broken     4" in line
    assert "eta    20.0 s" in line  # 10 s for 2 s simulated: 20 s for the 4 s left
    assert "eta     nan s" in _record(time=0.0).progress_line(6.0)
    assert issubclass(SimulationStopped, RuntimeError) and math.isfinite(_record().dt)
