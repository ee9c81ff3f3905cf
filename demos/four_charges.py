# ---
# jupyter:
#   jupytext:
#     formats: py:percent
# ---

# %% [markdown]
# # Four perforating charges: which tunnel breaks the rock at the lowest pressure?
#
# Each shaped charge leaves its own tunnel: longer or shorter, and with its
# own narrowing and widening along the way.  The perforation paper (section
# 4) puts four of them in the same rock and stress as perforation No. 2 and
# pumps water into each: No. 1 (25 g DP3 HMX) breaks down at 68.02 MPa,
# No. 2 (39 g DP3 HMX) at 64.01, No. 3 (89-type deep-penetrating) at 68.56
# and No. 4 (95-type deep-penetrating) at 65.37 MPa (its Fig. 15, in
# ``hfcdem/references.py``).  Its conclusion: No. 2 breaks lowest, No. 3
# highest.  This demo runs the four and checks both.
#
# Only No. 2's tunnel is given section by section (Tables 7 and 8).  For the
# others the paper gives the lengths, 235, 200 and 195 mm, so their profiles
# here are ASSUMED: No. 2's profile extended at its last slope (No. 1) or cut
# short (No. 3 and 4), see ``hfcdem/config/catalogue.py``.  Whatever ranking
# comes out for them follows from that assumption; it is no reproduction.
#
# The physics is perforation No. 2's (see ``perforation_no2.py``): a 2 m cube
# at Sv 76, SH 73, Sh 60 MPa, the tunnel along SH, 1e-7 m^3/s of water, and
# joints along the tunnel walls that hold water, so they break on effective
# stress.  What to expect before running: once water stands in the joints,
# the breakdown is the pressure that drives cracks through them against the
# stress across them.  That is near Sh + T0 = 63 MPa for any tunnel, so the
# four should come out close together, much closer than the paper's spread
# of 4.55 MPa.
#
# The four cases run as a study (``studies/four_charges.toml``).  Each case
# costs about a ``perforation_no2.py`` run; with ``mpirun -n 2`` and
# ``--groups 2`` two cases run side by side on one rank each.  Cases already
# done are skipped, so a stopped demo continues where it stopped::
#
#     python3 demos/four_charges.py -o results/four_charges
#     mpirun -n 2 python3 demos/four_charges.py -o results/four_charges --groups 2

# %%
"""Four perforating charges: which tunnel shape breaks the rock at the lowest pressure?

Section 4 of the perforation paper: one perforation along SH from a 140 mm
wellbore in a 2 m cube at 76/73/60 MPa (Sv/SH/Sh), water injected at 1e-7 m3/s.
The four charges leave tunnels of different length and profile; the paper finds
No. 2 (39 g DP3 HMX) breaking lowest and No. 3 highest.  Profiles No. 1, 3 and 4
are ASSUMED from the paper's lengths (hfcdem/config/catalogue.py): their ordering is a
consequence of that assumption, not a reproduction.

The cases run as a study (studies/four_charges.toml): with ``mpirun -n 2`` and
``--groups 2`` two cases run at once on one rank each.  Cases already done are
skipped, so a stopped demo continues where it stopped.  Run::

    python3 demos/four_charges.py -o results/four_charges
    mpirun -n 2 python3 demos/four_charges.py -o results/four_charges --groups 2

Printed: each charge's breakdown pressure next to the paper's, and whether the
ordering matches.  Written: results.csv, study.png, one folder per case
(pressure.png, fracture.png, fields.bp, interfaces.pvd: see README).
"""

from __future__ import annotations

from pathlib import Path

from hfcdem.references import CHARGE_NAMES, CHARGES
from hfcdem.reproduce.compare import PEAK_MESH_ERROR, resolved
from hfcdem.workflows.demos import demo_parser, parse_demo_line, run_demo, run_study_file
from hfcdem.workflows.study import breakdown_text, pick_metric

ROOT = Path(__file__).resolve().parents[1]  # the checkout: scenes and studies

# %% [markdown]
# ## The study, and the comparison
#
# The study file sweeps one scene field, the tunnel profile of No. 2's
# scene, over ``no1`` ... ``no4``, and pumps for 120 s (No. 2 first cracks
# after about 55 s and peaks after about 94 s).  ``run_study`` runs each case
# as ``hfcdem run`` would, in its own folder, and gathers one row per case.
#
# The paper's breakdown is the highest injection pressure of the run, so
# that is what the cases are ranked by.  A case that never cracked the rock
# has not broken down at all: then no ranking is printed, rather than one
# that leaves a case out.


# %%
def main(argv: list[str] | None = None) -> list[dict]:
    """Run the demo; return one result row per charge."""
    parser = demo_parser(__doc__, "results/four_charges", study=True)
    args, say = parse_demo_line(parser, argv)  # PETSc options too
    rows = run_study_file(ROOT / "studies/four_charges.toml", args, say)

    # what we get next to what the paper printed (Fig. 15 and 19); the ranking is by
    # peak pressure, and there is none unless every case cracked
    ours, metric = pick_metric(rows)
    for row in rows:
        key = row["value"]
        say(
            f"No. {key[-1]} ({CHARGE_NAMES[key]}): breakdown {breakdown_text(row)}, "
            f"first crack {row.get('first_crack_pressure_MPa') or float('nan'):.2f} MPa; "
            f"paper {CHARGES[key]:.2f} MPa; fracture degree {row.get('fracture_degree', 0):.4f}"
        )
    if ours:
        lowest, highest = min(ours, key=ours.get), max(ours, key=ours.get)
        decided = (
            ""
            if resolved(ours[lowest], ours[highest])
            else (f" (not decided: within the mesh error, {PEAK_MESH_ERROR:.1%})")
        )
        say(
            f"by {metric}: lowest No. {lowest[-1]} (paper: No. 2), "
            f"highest No. {highest[-1]} (paper: No. 3){decided}"
        )
    return rows


# %% [markdown]
# ## Reading the answer
#
# One line per charge: our breakdown (the confirmed peak, or "no drop
# confirmed" with the peak), the first crack's pressure, the paper's value
# and the fracture degree (the broken share of the interface area).  Then
# the ranking against the paper's: lowest No. 2, highest No. 3.  README
# ("Perforation scenes") has the coarse run: both orderings hold, but our
# four peaks lie within about 1 MPa of each other (1.6 %, less than the
# 1.7 % the mesh moves No. 2's peak, so the ranking is not decided), where
# the paper's are spread over 4.55 MPa.  With the joints soaked, the tunnel's shape moves the
# breakdown little; ``shape_study.py`` asks that directly.
# ``study.png`` draws breakdown and fracture degree per case; each case's
# folder has its ``pressure.png`` and ``fracture.png``.

# %%
if __name__ == "__main__":
    run_demo(main)
