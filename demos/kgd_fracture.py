# ---
# jupyter:
#   jupytext:
#     formats: py:percent
# ---

# %% [markdown]
# # A KGD hydraulic fracture against its self-similar solution
#
# The borehole demos break rock with a pressure that stays in the hole.  Here
# the fluid goes into the crack and drives it: water pumped at a constant
# rate into a straight plane-strain fracture, which opens, fills and grows.
# The question is whether hfcdem's coupling of the CDEM solid with flow along
# the broken interfaces grows the fracture at the right speed, with the right
# pressure and opening.
#
# The fracture of Khristianovic, Geertsma and de Klerk (KGD) is a 2D crack of
# half-length l(t) fed at its centre with Q0 per unit height.  Three pieces of
# physics meet: the fluid flows along the crack by the cubic law,
# q = -w^3 / (12 mu) dp/dx; the rock opens the crack elastically under the
# net pressure p - sigma0; and the volume pumped equals the volume stored.
# With zero toughness and no leak-off the viscous drop governs, the fracture
# is full of fluid to its tip, and the solution is self-similar.  With
# E' = E / (1 - nu^2) and mu' = 12 mu,
#
# $$\varepsilon = \left(\frac{\mu'}{E' t}\right)^{1/3}, \qquad
#   L = \left(\frac{E' Q_0^3 t^4}{\mu'}\right)^{1/6},$$
#
# $$l = 0.61524\, L, \qquad w(0, t) = 1.8302\, \varepsilon\, l, \qquad
#   p_\mathrm{net}(0, t) = 0.54495\, \varepsilon E'.$$
#
# So l grows as t^(2/3), the inlet opening as t^(1/3), and the net pressure
# falls as t^(-1/3): a propagating KGD has no breakdown peak.
#
# The set-up is the KGD benchmark of the implicit DDA hydraulic-fracture
# paper (seed 000, its section 4.2): E 25 GPa, nu 0.25, water of 1 mPa s,
# Q0 = 4e-3 m^2/s, 10 s of pumping.  What to expect before running: at
# t = 10 s the formulas above give l = 20.63 m, w(0) = 1.343 mm and
# p_net = 0.517 MPa.  README ("What is verified") has hfcdem within 3 % of
# all three on the default 0.5 m facets (l -0.6 %, p +2.8 %, w -0.1 %).
#
# Run it::
#
#     python3 demos/kgd_fracture.py -o results/kgd
#     mpirun -n 2 python3 demos/kgd_fracture.py -o results/kgd --stress 5

# %%
"""A KGD hydraulic fracture: water driven into rock, against the self-similar solution.

The benchmark of seed 000 (section 4.2): a plane-strain fracture grows from an
inlet at a constant rate, with zero toughness and no leak-off.  Only the half
x >= 0 is modelled; the fracture may open along y = 0, where every facet
carries springs that break as soon as fluid has pressurised the facet behind
them.  Fluid flows along the broken facets by the cubic law; the solid is
condensed onto the fluid unknowns once per break, so each time step is a small
Newton solve (PETSc SNES).

Printed and written: the half-length, the net pressure and the opening at
the inlet, each next to the zero-toughness solution, and mass balance.  Run::

    python3 demos/kgd_fracture.py -o results/kgd
    mpirun -n 2 python3 demos/kgd_fracture.py -o results/kgd --stress 5

Outputs: summary.json, history.csv (one row per step), kgd.png (the three
curves against the solution), fracture.vtu (ParaView: fluid pressure,
aperture, saturation and state per fracture facet).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI

from hfcdem.analytic import kgd_viscosity
from hfcdem.config.materials import ElasticMaterial, Fluid, Injection, InSituStress, InterfaceModel
from hfcdem.config.parts import Crack, MeshSizing, Plate
from hfcdem.config.plates import KGDStrip
from hfcdem.coupling.hydrofrac import FlowSettings, HydraulicFracture
from hfcdem.info import versions
from hfcdem.io.files import prepare_output_dir, write_interfaces, write_json
from hfcdem.mesh.build import mesh_geometry
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.workflows.demos import parse_demo_line, run_demo

# seed 000, section 4.2: rock, water and the pump (per metre of fracture height)
ROCK = ElasticMaterial(youngs_modulus=25e9, poisson_ratio=0.25)
WATER = Fluid(viscosity=1e-3, bulk_modulus=2.2e9)
RATE = 4e-3  # m^3/s per metre, both wings

# %% [markdown]
# ## The model
#
# Only the half x >= 0 of a 400 m square plate is modelled, with rollers on
# the symmetry line x = 0.  The outer edges are fixed; 200 m away, ten times
# the final half-length, they do not stiffen the fracture.  The fracture may
# only run along y = 0: a path of 32 m on the half, split into facets of
# exactly ``--dx``, the first of them open at the start.  The path's facets
# are the only interfaces.  Their tensile strength is zero, which is how a
# strength-based model says zero toughness: a facet breaks as soon as the
# fluid has pressurised the facet behind it.  Their cohesion is too high for
# shear, and their springs are stiff (alpha 1000), so they add little
# compliance before they break.
#
# The pump feeds half of Q0 into the half model at the origin.  The flow
# fills every broken facet to the tip (``filling="no_lag"``), as the
# self-similar solution assumes.  The solid is condensed onto the fluid
# unknowns once per break, so a time step is a small Newton solve on the
# fracture alone.  ``--stress`` adds a background stress sigma0 in every
# direction; the fracture starts at that pressure and the comparison is in
# net pressure, so the answer should not change.


# %%
def kgd_half_plate(dx: float, comm: MPI.Comm) -> TaggedMesh:
    """Mesh the half plate with its fracture path split into facets of ``dx``."""
    # Half of a 400 m plate: far enough that its fixed edges do not stiffen a
    # fracture of 20 m.  The path (32 m) is split into facets of exactly dx, the
    # first of them open at the start (the crack), the injection point a vertex.
    sizing = MeshSizing(dx, 40.0, grading=0.3, path_size=dx, size_integration="exact")
    strip = KGDStrip(Plate(400.0, 400.0), Crack(2 * dx, 64.0), sizing, symmetry=("x",))
    return mesh_geometry(strip, comm)


def fluid_driven_fracture(tmesh: TaggedMesh, stress: float, dt: float) -> HydraulicFracture:
    """Water pumped into the path's open facet; springs break at zero tension."""
    # Springs on the path only, zero tensile strength: the KGD's zero toughness.
    solid = CDEMSolid(
        tmesh,
        ROCK,
        InSituStress(sh_max=stress, sh_min=stress, sv=stress),
        InterfaceModel(alpha=1e3, tensile_strength=0.0, cohesion=1e10, break_rule="all"),
        zone="fracture_path",
        rollers={"symmetry_x": 0},
        fixed=tmesh.facet_groups("outer"),
    )
    # Half the rate enters the half model; the fracture is full of fluid to its
    # tip (no lag), as the self-similar solution assumes.
    return HydraulicFracture(
        solid,
        WATER,
        Injection.constant_rate(RATE / 2),
        FlowSettings(
            injection_point=(0.0, 0.0),
            filling="no_lag",
            dt_initial=dt,
            dt_max=dt,
            initial_pressure=stress,
        ),
    )


# %% [markdown]
# ## The run: every step next to the solution
#
# Fixed steps of ``--dt`` up to ``--t-end``.  After each one, three numbers
# are measured and printed beside the self-similar solution at the same
# time: the half-length (how far along the path the fluid has reached from
# the inlet), the net pressure at the inlet and the opening there.  The mass
# balance (pumped against stored) is recorded at every step; its worst
# relative error goes into the summary.


# %%
def main(argv: list[str] | None = None) -> dict:
    """Run the demo; return the summary it writes."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-o", "--output", default="results/kgd", help="output directory")
    parser.add_argument("--dx", type=float, default=0.5, help="facet length on the path, m")
    parser.add_argument("--dt", type=float, default=0.5, help="time step, s")
    parser.add_argument("--t-end", type=float, default=10.0, help="injection time, s")
    parser.add_argument("--stress", type=float, default=0.0, help="background stress, MPa")
    args, say = parse_demo_line(parser, argv)  # PETSc options too
    comm = MPI.COMM_WORLD
    out = prepare_output_dir(args.output, comm)
    wall0 = time.perf_counter()
    stress = args.stress * 1e6

    tmesh = kgd_half_plate(args.dx, comm)
    frac = fluid_driven_fracture(tmesh, stress, args.dt)
    rows = []
    while frac.t < args.t_end * (1 - 1e-12):
        frac.dt = min(frac.dt, args.t_end - frac.t)
        rec = frac.step()
        ref = kgd_viscosity(rec.time, RATE, ROCK.youngs_modulus, ROCK.poisson_ratio, 1e-3)
        length = frac.wet_extent((0.0, 0.0), (1.0, 0.0))
        opening = frac.opening_at_cavity()
        rows.append((rec.time, length, rec.injection_pressure - stress, opening, ref))
        say(
            f"t {rec.time:5.2f} s  half-length {length:6.2f} m ({ref.half_length:6.2f})  "
            f"net pressure {(rec.injection_pressure - stress) / 1e6:6.4f} MPa "
            f"({ref.net_pressure / 1e6:6.4f})  opening {opening * 1e3:6.4f} mm "
            f"({ref.inlet_opening * 1e3:6.4f})  wall {rec.wall_time:5.1f} s"
        )

    t_end, length, p_net, opening, ref = rows[-1]
    frac.write_history(out / "history.csv")
    points, data = frac.facet_fields()
    write_interfaces(out / "fracture.vtu", points, data, comm)
    if comm.rank == 0:
        _plot(out / "kgd.png", rows)
    summary = {
        "time_s": t_end,
        "half_length_m": length,
        "kgd_half_length_m": ref.half_length,
        "net_pressure_MPa": p_net / 1e6,
        "kgd_net_pressure_MPa": ref.net_pressure / 1e6,
        "inlet_opening_mm": opening * 1e3,
        "kgd_inlet_opening_mm": ref.inlet_opening * 1e3,
        "max_mass_error": max(r.mass_error for r in frac.history),
        "max_volume_mismatch": max(r.volume_mismatch for r in frac.history),
        "steps": len(frac.history),
        "dx_m": args.dx,
        "dt_s": args.dt,
        "background_stress_MPa": args.stress,
        "ranks": comm.size,
        "wall_time_s": time.perf_counter() - wall0,
        "versions": versions(),
    }
    write_json(out / "summary.json", summary, comm)
    say(
        f"half-length {length:.2f} m, KGD {ref.half_length:.2f} m; net pressure "
        f"{p_net / 1e6:.4f} MPa, KGD {ref.net_pressure / 1e6:.4f} MPa; opening "
        f"{opening * 1e3:.4f} mm, KGD {ref.inlet_opening * 1e3:.4f} mm; "
        f"worst mass error {summary['max_mass_error']:.1e}; results in {out}/"
    )
    return summary


# %% [markdown]
# ## The picture
#
# ``kgd.png`` has three panels, half-length, inlet net pressure and inlet
# opening against time: the solution as a line, hfcdem's steps as dots.


# %%
def _plot(path, rows) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.array([r[0] for r in rows])
    fine = np.linspace(t[0], t[-1], 200)
    ref = [kgd_viscosity(x, RATE, ROCK.youngs_modulus, ROCK.poisson_ratio, 1e-3) for x in fine]
    panels = [
        ("half-length (m)", [r[1] for r in rows], [s.half_length for s in ref]),
        (
            "net pressure at the inlet (MPa)",
            [r[2] / 1e6 for r in rows],
            [s.net_pressure / 1e6 for s in ref],
        ),
        (
            "opening at the inlet (mm)",
            [r[3] * 1e3 for r in rows],
            [s.inlet_opening * 1e3 for s in ref],
        ),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, (label, model, exact) in zip(axes, panels, strict=True):
        ax.plot(fine, exact, "k-", label="KGD, zero toughness")
        ax.plot(t, model, "o", ms=4, label="hfcdem")
        ax.set_xlabel("time (s)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# %% [markdown]
# ## Reading the answer
#
# The last line gives the three figures at ``--t-end`` beside the solution.
# The half-length moves in whole facets, so it advances in steps of ``--dx``
# and its gap is of that order: coarser facets (the test runs ``--dx 1``)
# leave it some per cent off, and the test asks for 10 % on all three.  The
# first steps are the roughest: the fracture is then only a few facets long.
# ``history.csv`` holds every step (time, injection pressure, volumes
# pumped and stored); ``fracture.vtu`` the pressure, aperture, saturation
# and state of each path facet at the end, for ParaView.  ``--stress 5``
# should give the same net pressures and lengths (README: the same figures
# with 5 MPa of background stress).

# %%
if __name__ == "__main__":
    run_demo(main)
