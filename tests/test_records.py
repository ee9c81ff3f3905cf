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


def test_the_progress_line_says_the_time_left():
    line = _record(time=2.0, wall=10.0).progress_line(20.0)
    assert "p   12.5000 MPa" in line and "broken     4" in line
    assert line.endswith("wall    10.0 s  eta   20 s")
    assert _record().progress_line(7200.0).endswith("eta  2.0 h")
    assert _record(time=0.0).progress_line(math.nan).endswith("eta      ?")
    assert issubclass(SimulationStopped, RuntimeError) and math.isfinite(_record().dt)
