"""The KGD series of the HFDDA paper (Figs. 8-10) in the reproduction report."""

import csv

import pytest
from mpi4py import MPI

from hfcdem.reproduce.runner import run_reproduction


def test_the_mesh_series_with_a_background_stress(shared_tmp_path):
    # a pre-existing crack that 5 MPa presses shut at the start: it used to start with
    # negative fluid (its faces overlap in the linear model) and dx = 2 m reported an inlet
    # pressure of 1.8e16 Pa, dx = 4 m stopped at t = 0 (a singular group Jacobian)
    (record,) = run_reproduction(shared_tmp_path, tier="quick", only=["kgd_mesh_stress"])
    assert record.status == "ok", record.message
    rows = {c.quantity: c for c in record.comparisons}
    for quantity, measured in (
        ("half-length (fluid front) at dx = 0.5 m", -0.006),
        ("inlet net pressure at dx = 0.5 m", 0.091),
        ("inlet opening at dx = 0.5 m", -0.002),
    ):
        assert rows[quantity].met and rows[quantity].gap == pytest.approx(measured, abs=0.005)
    assert rows["the series as dx grows"].agrees  # p +20.0 % at 4 m, +9.1 % at 0.5 m
    if MPI.COMM_WORLD.rank == 0:
        cases = shared_tmp_path / "cases" / "kgd_mesh_stress"
        for history in sorted(cases.glob("case_*/history.csv")):
            with history.open() as f:
                fluid = [float(r["fracture_fluid"]) for r in csv.DictReader(f)]
            assert min(fluid) >= 0.0, history
        assert (cases / "series.png").stat().st_size > 5_000
