# ---
# jupyter:
#   jupytext:
#     formats: py:percent
# ---

# %% [markdown]
# # The perforation shape study: does the real tunnel shape matter?
#
# Models of perforation breakdown often take the tunnel as a cylinder; a
# real one narrows and then widens.  Perforation No. 2's tunnel is 230 mm
# long, 33.44 mm across at the entry, 23.50 mm at its neck and 50.00 mm at
# the far end (Tables 7 and 8).  Section 5 of the perforation paper asks
# whether that shape matters by changing it one feature at a time:
#
# | model | tunnel | paper (MPa) |
# |---|---|---|
# | no2 | the measured profile | 64.01 |
# | 1-1 | cylinder of the entry diameter | 66.83 |
# | 1-2 | cylinder of the far-end diameter | 53.86 |
# | 1-3 | cylinder of No. 2's volume | 65.35 |
# | 2-1, 2-2 | far-well sections 10 mm wider, narrower | 56.67, 65.67 |
# | 3-1, 3-2 | near-well sections 10 mm wider, narrower | 58.35, 66.66 |
# | 4-1, 4-2 | every segment 10 mm longer (280 mm), shorter (180 mm) | 56.97, 68.75 |
#
# (Fig. 21; ``hfcdem/references.py``).  From these the paper concludes that
# breakdown falls as the tunnel widens and as it lengthens, and that No. 2
# lies between its two bounding cylinders.  Two notes.  The paper's text
# quotes 68.75 MPa for 4-1 and 56.97 MPa for 4-2 while arguing that the
# longer tunnel breaks lower; the two are swapped here to fit the argument
# (4-1, 280 mm, at 56.97 MPa).  And the cylinder of No. 2's volume, built
# from the sections by conical frustums, is 34.86 mm across, not the
# 36.34 mm printed; model 1-3 uses the computed one
# (``hfcdem/config/catalogue.py`` has both).
#
# What to expect before running: elasticity gives little reason for a
# large effect.  Kirsch's wall stress around a pressurised cylinder does not
# depend on its diameter, and a strength criterion holds no length.  In our
# model the joints along the tunnel walls hold water, so the breakdown is
# the pressure that drives cracks through them against the stress across
# them, near Sh + T0 = 63 MPa (Sh 60 MPa, T0 3 MPa) whatever the shape.
# Expect small differences, and the paper's orderings decided by fractions
# of a MPa.
#
# The ten models run as a study (``studies/shape_study.toml``), each about a
# ``perforation_no2.py`` run, hours in all; ``--models`` picks a few.  Done
# cases are skipped, so a stopped demo continues::
#
#     python3 demos/shape_study.py -o results/shape_study --models no2,1-1,1-2
#     mpirun -n 2 python3 demos/shape_study.py -o results/shape_study --groups 2

# %%
"""Perforation shape study: does the real tunnel shape matter, or is a cylinder enough?

Section 5 of the perforation paper: Perforation No. 2 (a tunnel that narrows
then widens) against equal-section cylinders of its entry diameter (1-1), its
far-end diameter (1-2) and its volume (1-3), against wider and narrower
far-well (2-1, 2-2) and near-well (3-1, 3-2) sections, and against a longer and
a shorter tunnel (4-1, 4-2).  The paper finds breakdown falling with diameter
and with length, and No. 2 between its two bounding cylinders.

The cases run as a study (studies/shape_study.toml, a sweep over the tunnel
profile); done cases are skipped, so a stopped demo continues.  Run::

    python3 demos/shape_study.py -o results/shape_study
    mpirun -n 2 python3 demos/shape_study.py -o results/shape_study --groups 2

Printed: each model's breakdown next to the paper's (Fig. 21) and each of the
paper's orderings, held or not.  Written: results.csv, study.png (breakdown and
fracture degree per model), one folder per case.
"""

from __future__ import annotations

from pathlib import Path

from hfcdem.references import SHAPE_ORDERINGS, SHAPES
from hfcdem.reproduce.compare import PEAK_MESH_ERROR, resolved
from hfcdem.workflows.demos import demo_parser, parse_demo_line, run_demo, run_study_file
from hfcdem.workflows.study import breakdown_text, pick_metric

ROOT = Path(__file__).resolve().parents[1]  # the checkout: scenes and studies

# %% [markdown]
# ## The study, and the comparison
#
# The study sweeps the tunnel profile of No. 2's scene over the ten models
# and pumps each for 120 s; everything else is No. 2's (see
# ``perforation_no2.py``).  The cases are ranked by peak pressure, the
# paper's breakdown, and only when every case cracked.  Each of the paper's
# six orderings is then checked pair by pair, for the pairs that ran, and
# printed as holding or not with both pressures; a pair closer than the mesh
# error (1.7 %: No. 2's highest pressure moves that much from the coarse to
# the default mesh) is not decided.


# %%
def main(argv: list[str] | None = None) -> list[dict]:
    """Run the demo; return one result row per model."""
    parser = demo_parser(__doc__, "results/shape_study", study=True)
    parser.add_argument("--models", default=None, help="comma-separated subset, e.g. no2,1-1")
    args, say = parse_demo_line(parser, argv)  # PETSc options too
    rows = run_study_file(
        ROOT / "studies/shape_study.toml",
        args,
        say,
        args.models.split(",") if args.models else None,
    )

    ours, metric = pick_metric(rows)
    for row in rows:
        key = row["value"]
        say(
            f"model {key:>4}: breakdown {breakdown_text(row)}, first crack "
            f"{row.get('first_crack_pressure_MPa') or float('nan'):.2f} MPa; paper "
            f"{SHAPES[key]:.2f} MPa; fracture degree {row.get('fracture_degree', 0):.4f}"
        )
    # the paper's conclusions, one pair at a time
    for low, high, claim in SHAPE_ORDERINGS:
        if low in ours and high in ours:
            held = "holds" if ours[low] < ours[high] else "does NOT hold"
            if not resolved(ours[low], ours[high]):
                held = f"not decided, the two within the mesh error ({PEAK_MESH_ERROR:.1%})"
            say(
                f"{claim} ({low} < {high}) by {metric}: {held} "
                f"({ours[low]:.2f} vs {ours[high]:.2f} MPa)"
            )
    return rows


# %% [markdown]
# ## Reading the answer
#
# One line per model, our breakdown next to the paper's, then one line per
# ordering.  README ("Perforation scenes") has the coarse runs: every peak
# between about 62 and 65 MPa, near Sh + T0, so the paper's spread of 54 to
# 69 MPa is not reproduced.  Only one of the paper's orderings is decided
# there, the large cylinder below No. 2 (62.42 against 64.15 MPa), and it
# holds; the others differ by a few tenths of a MPa, less than the mesh
# error.  With soaked joints the breakdown is a pressure to
# push cracks through the rock, and the tunnel's shape changes it little.
# ``study.png`` draws breakdown and fracture degree per model; each model's
# folder has its pictures.

# %%
if __name__ == "__main__":
    run_demo(main)
