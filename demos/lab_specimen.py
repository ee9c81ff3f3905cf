# ---
# jupyter:
#   jupytext:
#     formats: py:percent
# ---

# %% [markdown]
# # The lab specimen: breakdown against the perforation's azimuth
#
# The one case of the perforation paper with laboratory measurements behind
# it (section 3.2, after the tests of Jiang et al.): a 300 mm cube of cement
# mortar under Sv 15, SH 6 and Sh 1 MPa, a vertical wellbore of 20 mm and two
# opposite perforations of 2 mm x 30 mm, pointing 30, 45 or 60 deg away from
# SH.  Water is pumped at 2.1e-9 m^3/s.  The measured breakdown rises with
# the azimuth: 10.39, 10.55 and 15.55 MPa; the paper's CDEM gives 10.46,
# 10.65 and 15.64 MPa (``hfcdem/references.py``).  The fracture starts along
# the perforations and turns toward SH.  This demo runs the three azimuths
# and sets each breakdown beside the measurement.
#
# Why the azimuth matters: a crack that starts from the perforations tends
# to open first in the vertical plane that holds them and the well.  For
# perforations at an angle beta from SH, the stress across that plane is
#
# $$\sigma_n = S_H \sin^2\beta + S_h \cos^2\beta,$$
#
# 2.25, 3.5 and 4.75 MPa at 30, 45 and 60 deg: the further from SH, the
# harder the start, and the more the crack has to turn to open against Sh,
# the least stress.  The borehole alone would not do: Hubbert-Willis for the
# open hole, 3 Sh - SH + T0 = 3 - 6 + 2.59 MPa, is below zero, since the wall
# on the SH axis is in tension before any pressure.  Here the injection tube
# seals the well and only the perforations take the pressure.
#
# What to expect before running: a breakdown that rises with azimuth, near
# the measured values.  The rock is Tables 2-3's mortar (E 8.402 GPa,
# nu 0.23, T0 2.59 MPa).
#
# The three azimuths run as a study (``studies/lab_azimuth.toml``), about
# six minutes on 2 cores on the coarse mesh; with ``mpirun -n 2`` and
# ``--groups 2`` two run side by side::
#
#     python3 demos/lab_specimen.py -o results/lab_specimen
#     mpirun -n 2 python3 demos/lab_specimen.py -o results/lab_specimen --groups 2

# %%
"""Lab specimen: breakdown against the perforation azimuth, next to the measurements.

Section 3.2 of the perforation paper, after the tests of Jiang et al.: a 300 mm
cube of cement mortar under Sv 15, SH 6, Sh 1 MPa, a 20 mm vertical wellbore and
two opposite 2 mm x 30 mm perforations at 30, 45 or 60 degrees from SH, water
pumped at 2.1e-9 m3/s.  Measured breakdown: 10.39, 10.55 and 15.55 MPa, rising
with azimuth; the fracture starts along the perforations and turns toward SH.

The three azimuths run as a study (studies/lab_azimuth.toml).  Run::

    python3 demos/lab_specimen.py -o results/lab_specimen
    mpirun -n 2 python3 demos/lab_specimen.py -o results/lab_specimen --groups 2

Printed: breakdown per azimuth next to the measured value, and whether it rises
with azimuth.  Written: results.csv, study.png, one folder per azimuth with
fracture.png (the fracture seen along the wellbore: does it turn toward SH?).
"""

from __future__ import annotations

import itertools
from pathlib import Path

from hfcdem.references import LAB_MEASURED, LAB_PAPER_SIMULATED
from hfcdem.workflows.demos import demo_parser, parse_demo_line, run_demo, run_study_file
from hfcdem.workflows.study import breakdown_text, numeric

ROOT = Path(__file__).resolve().parents[1]  # the checkout: scenes and studies

# %% [markdown]
# ## The study, and the comparison
#
# The study sweeps the perforations' azimuth of the 30 deg scene
# (``meshes/scenes/lab_specimen_30deg.toml``).  The model is half the
# specimen, cut by the horizontal plane through both perforations, so it
# takes half the rate.  Two inputs are calibrated and say so in the scene
# file: the stored fluid is a 5 um film on the tunnel walls, and the joints
# stay dry (the mortar lets no water into them; with soaked joints the
# breakdown falls to about 3 MPa at every azimuth).  The pumping lasts 3 s:
# the pressure rises several MPa a second here.
#
# Each azimuth's breakdown is set beside the measurement, with the gap; the
# last line says whether ours rises with the azimuth, as the measurements
# do.  It is only printed when all three found a breakdown.


# %%
def main(argv: list[str] | None = None) -> list[dict]:
    """Run the demo; return one result row per azimuth."""
    parser = demo_parser(__doc__, "results/lab_specimen", study=True, duration_example="30 s")
    args, say = parse_demo_line(parser, argv)  # PETSc options too
    rows = run_study_file(ROOT / "studies/lab_azimuth.toml", args, say)

    ours = []
    for row in rows:
        azimuth = round(numeric(row["value"]) * 180.0 / 3.141592653589793)
        bd = row.get("breakdown_pressure_MPa")
        ours.append(bd)
        gap = f" ({bd / LAB_MEASURED[azimuth] - 1:+.1%})" if bd else ""
        say(
            f"azimuth {azimuth} deg: breakdown {breakdown_text(row)}{gap}, measured "
            f"{LAB_MEASURED[azimuth]:.2f} MPa, paper's CDEM {LAB_PAPER_SIMULATED[azimuth]:.2f} MPa"
        )
    if all(ours):
        rising = all(a < b for a, b in itertools.pairwise(ours))
        say(f"breakdown rises with azimuth: {'yes' if rising else 'NO'} (measured: yes)")
    return rows


# %% [markdown]
# ## Reading the answer
#
# ``study.png`` draws the three breakdowns; each azimuth's folder has its
# ``pressure.png`` and ``fracture.png``, the fracture seen down the well, to
# check whether it turns toward SH.  This case is not reproduced yet.
# README ("Perforation scenes") has the coarse runs of 2026-12-04: peaks of
# 10.11, 7.71 and 9.91 MPa, not rising with the azimuth.  The 30 and 45 deg
# runs start with interfaces broken by the in-situ stress alone and end after
# their peaks at the model's validity limit: blocks cut loose from the tunnel
# wall moved further than a small-displacement solid can follow, and the
# summary says so (``validity_limit``) rather than failing.  Why they start
# broken is printed at the start of each run and kept in ``summary.json``
# (``in_situ_wall_tension``): Table 2's Sv of 15 MPa across the 2 mm tunnels
# puts their walls in 10.3 / 8.3 / 6.0 MPa of tension at 30 / 45 / 60 deg,
# above T0 = 2.59 MPa, before any fluid arrives.

# %%
if __name__ == "__main__":
    run_demo(main)
