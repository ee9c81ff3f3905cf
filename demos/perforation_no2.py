# ---
# jupyter:
#   jupytext:
#     formats: py:percent
# ---

# %% [markdown]
# # Perforation No. 2: when does water break the rock around a real tunnel?
#
# A shaped charge leaves a tunnel that narrows and then widens (the 39 g DP3
# HMX charge of the perforation paper, Tables 7-8).  Pumping water into it
# raises the pressure on the tunnel wall; the rock around the wall carries the
# in-situ stress (Sv 76, SH 73, Sh 60 MPa) plus the hoop stress the pressure
# adds.  An interface between two blocks breaks when its normal traction
# passes the tensile strength T0 = 3 MPa or its shear passes Mohr-Coulomb;
# once broken and open it fills with water and carries the pressure itself.
#
# What to expect before running: a tunnel along SH in a plane-strain section
# would break near the Hubbert-Willis pressure of its cross-section, and with
# fluid already in the wall joints near Sh + T0 = 63 MPa.  The paper reports
# 64.01 MPa, the first crack at the tunnel's root after about 10 s.
#
# Run it (``make demo`` runs it on 2 ranks)::
#
#     python3 demos/perforation_no2.py -o results/perforation_no2
#     mpirun -n 2 python3 demos/perforation_no2.py -o results/perforation_no2

# %%
"""Perforation No. 2: when does water injected into a real perforation tunnel break the rock?

The main scene of the perforation paper (section 4): a 2 m cube of rock at
Sv 76, SH 73, Sh 60 MPa, a 140 mm horizontal cased wellbore along Sh and one
230 mm perforation along SH with the measured narrowing-then-widening profile
of the 39 g DP3 HMX charge.  Water is pumped into the tunnel at 1e-7 m3/s
(half of it into this half model); the tunnel wall and the joints along it
take the pressure; interfaces break in tension or shear and the new cracks
fill with water.

Run (the scene file is meshes/scenes/perforation_no2.toml; ``make demo`` runs
this on 2 ranks)::

    python3 demos/perforation_no2.py -o results/perforation_no2
    mpirun -n 2 python3 demos/perforation_no2.py -o results/perforation_no2

Printed: breakdown pressure next to the paper's 64.01 MPa, the first crack's
time and place, fracture degree and the failure modes, then where the
pictures and ParaView files are.
"""

from __future__ import annotations

from pathlib import Path

from hfcdem.references import CHARGES
from hfcdem.workflows.demos import demo_parser, parse_demo_line, run_demo, run_scene_file
from hfcdem.workflows.study import breakdown_text

ROOT = Path(__file__).resolve().parents[1]  # the checkout: scenes and studies

# %% [markdown]
# ## The run
#
# The scene file holds everything: geometry, rock, stresses, fluid and pump.
# Three inputs are calibrated and say so there (the paper does not give
# them): the stored fluid is a 5 um film on the tunnel wall, the start is a
# hydrostatic 30 MPa, and the pumping lasts 120 s instead of 60 s.  The
# coarse mesh (4,251 cells) takes about 2 minutes on 2 cores; the default
# mesh moves the first crack by about 5 % (README, "Convergence studies").


# %%
def main(argv: list[str] | None = None) -> dict:
    """Run the demo; return the run's summary."""
    parser = demo_parser(__doc__, "results/perforation_no2")
    args, say = parse_demo_line(parser, argv)  # PETSc options too
    summary = run_scene_file(ROOT / "meshes/scenes/perforation_no2.toml", args, say)

    bd = summary["breakdown_pressure_MPa"]
    gap = f" ({bd / CHARGES['no2'] - 1:+.1%})" if bd else ""
    say(f"breakdown {breakdown_text(summary)}{gap}, paper {CHARGES['no2']:.2f} MPa")
    first = summary.get("first_crack")
    if first:
        say(
            f"first crack at {summary['first_crack_time_s']:.3g} s, {first['interfaces']} "
            f"interfaces, {first['distance_from_wellbore_wall_m'] * 1e3:.0f} mm from the "
            "wellbore wall (the paper: at the root, after 10 s)"
        )
    stress = (first or {}).get("sigma_xx")
    if stress:
        say(
            f"sigma_xx then: largest {stress['peak_MPa']:.1f} MPa ({stress['peak_place']}), "
            f"{stress['tensile_cells']} of {stress['cells']} cells beside the zone's interfaces "
            "in tension (the paper: tension at the root, Fig. 18)"
        )
    say(
        f"fracture degree {summary['fracture_degree']:.4f}; {summary['tensile_failures']} tensile, "
        f"{summary['shear_failures']} shear failures ({summary['initial_failures']} before "
        f"injection); {summary['cells']} cells, {summary['wall_time_s']:.0f} s on "
        f"{summary['ranks']} rank(s)"
    )
    out = Path(args.output)
    say(
        f"pictures: {out / 'pressure.png'} (Fig. 15), {out / 'fracture.png'} (Figs. 16-17), "
        f"{out / 'sigma_xx.png'} (Fig. 18); "
        f"ParaView: {out / 'fields.bp'}, {out / 'interfaces.pvd'}"
    )
    return summary


# %% [markdown]
# ## Reading the answer
#
# The breakdown is the peak of the pressure once it has fallen 5 % of its
# rise (``pressure.png``, the paper's Fig. 15); the first crack's place is
# its distance from the wellbore wall along the tunnel (root, middle or far
# end).  On the coarse mesh the peak lands within 0.2 % of the paper's, but
# the first crack comes in the middle of the tunnel after about 53 s, not at
# the root after 10 s: the calibrated storage sets the time scale, and the
# shape changes the answer little (the shape study, README).
#
# The paper's Fig. 18 shows sigma_xx at its first cracks, in tension at the
# root.  ``sigma_xx.png`` draws ours along the tunnel in the step of the first
# crack (the largest and the mean of each twelfth of the tunnel).  On the
# coarse mesh no cell beside the zone's interfaces is in tension: the rock
# along the tunnel stays near -70 MPa, and the least compressed rock is at the
# tunnel's tip face, where sigma_xx equals minus the cavity pressure (about
# -62 MPa).  The paper does not say which axis is its x; ours is the tunnel's.
# ``hfcdem reproduce`` puts all this beside the other cases of the paper.

# %%
if __name__ == "__main__":
    run_demo(main)
