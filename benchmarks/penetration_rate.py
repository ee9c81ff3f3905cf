"""Borehole breakdown against pressurisation rate, the fluid seeping into the joints.

Seed 001's borehole (a = 30 mm in a 1 m plate, E 20 GPa, nu 0.25, SH 20 MPa,
Sh 12 MPa, T0 5 MPa, alpha 100), joints of the fracturable zone (r < 6 a) of
hydraulic aperture 5 um, filled from dry (saturation filling), a fluid of
``--viscosity``.  The cavity pressure rises at a constant rate until the first
joint breaks (:func:`hfcdem.coupling.penetration.ramp_breakdown`).

Printed per wall size h: the two limits of the same mesh (the linear ramp
with dry joints, and with every joint at the cavity pressure), the closed forms
(Hubbert-Willis 3 Sh - SH + T0 = 21 MPa; Haimson-Fairhurst with eta = 0,
(3 Sh - SH + T0) / 2 = 10.5 MPa), then one row per rate with the breakdown
pressure, the share of joints holding pressure at the break and the wall
time.  The dimensionless rate ``A t_h / P_dry`` uses the time the fluid needs
to fill one joint of length h from the wall, ``t_h = 6 mu h^2 / (a^2 P_dry)``
(the front of a filling conduit, x^2 = a^2 P t / (6 mu)).

    make run CMD="python3 benchmarks/penetration_rate.py --divisions 5 10 20"
    make run CMD="python3 benchmarks/penetration_rate.py --limits --divisions 5 10 20 40"
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI
from wall_joint_verification import SH, T0, A, borehole_mesh, borehole_solid

from hfcdem.config.materials import Fluid
from hfcdem.coupling.penetration import PressureRamp, ramp_breakdown
from hfcdem.io.plots import plot_lines
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import CascadeStopped

SHMIN = 12e6
WALL = ("wellbore_wall",)
HW = 3 * SHMIN - SH + T0
HF = HW / 2


def _solid(tmesh) -> CDEMSolid:  # type: ignore[no-untyped-def]
    return borehole_solid(tmesh, SHMIN)


def _limit(tmesh, wet: bool) -> float:  # type: ignore[no-untyped-def]
    """First break of the linear ramp: dry joints, or every joint at the cavity pressure."""
    solid = _solid(tmesh)
    base = Loads(cavity={WALL[0]: 0.0})
    solid.equilibrate(base)  # what breaks at excavation (a/40: one facet) is not the breakdown
    joint = ((solid.state == FacetState.INTACT) & ~solid.is_crack).astype(float)
    unit = Loads(cavity={WALL[0]: 1.0}, joint_pressure=joint if wet else None, in_situ_factor=0.0)
    try:
        first = solid.ramp(base, unit, 40e6)
    except CascadeStopped as stop:
        first = stop.first_break
    return float(first) if first is not None else float("nan")


def _limits_table(divisions: list[int], say) -> None:  # type: ignore[no-untyped-def]
    """Both limits against the wall size, with first-order Richardson extrapolation."""
    say("| h | dry (MPa) | vs HW | Richardson | vs HW | wet (MPa) | vs HF | Richardson | vs HF |")
    say("|---|---|---|---|---|---|---|---|---|")
    last = None
    for div in divisions:
        tmesh = borehole_mesh(A / div)
        dry, wet = _limit(tmesh, False), _limit(tmesh, True)
        cells = ["", "", "", ""]
        if last is not None:  # errors O(h): 2 P(h) - P(2h)
            rd, rw = 2 * dry - last[0], 2 * wet - last[1]
            cells = [
                f"{rd / 1e6:.3f}",
                f"{rd / HW - 1:+.1%}",
                f"{rw / 1e6:.3f}",
                f"{rw / HF - 1:+.1%}",
            ]
        say(
            f"| a/{div} | {dry / 1e6:.4f} | {dry / HW - 1:+.1%} | {cells[0]} | {cells[1]} | "
            f"{wet / 1e6:.4f} | {wet / HF - 1:+.1%} | {cells[2]} | {cells[3]} |"
        )
        last = (dry, wet)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, nargs="+", default=[5, 10], help="h = a / n")
    parser.add_argument("--rates", type=float, nargs="+", default=list(np.logspace(3, 10, 15)))
    parser.add_argument("--viscosity", type=float, default=1.0, help="Pa s")
    parser.add_argument("--aperture", type=float, default=5e-6, help="m")
    parser.add_argument("--steps", type=int, default=200, help="time steps to 25 MPa")
    parser.add_argument("--plot", default="results/penetration_rate.png")
    parser.add_argument(
        "--limits", action="store_true", help="only the two limits against h, extrapolated"
    )
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    if args.limits:
        _limits_table(args.divisions, say)
        return
    fluid = Fluid(viscosity=args.viscosity)
    say(f"# {comm.size} rank(s), viscosity {args.viscosity} Pa s, aperture {args.aperture} m,")
    say(f"# {args.steps} steps to 25 MPa; HW {HW / 1e6:.2f} MPa, HF (eta 0) {HF / 1e6:.2f} MPa")
    curves = []
    styles = iter(["o-", "s-", "^-", "d-"])
    for div in args.divisions:
        h = A / div
        tmesh = borehole_mesh(h)
        dry, wet = _limit(tmesh, False), _limit(tmesh, True)
        t_h = 6 * args.viscosity * h**2 / (args.aperture**2 * dry)
        say(
            f"\n## h = a/{div}: dry limit {dry / 1e6:.4f} MPa ({dry / HW - 1:+.1%} of HW), "
            f"wet limit {wet / 1e6:.4f} MPa ({wet / HF - 1:+.1%} of HF); t_h = {t_h:.3g} s"
        )
        say(
            "| rate (MPa/s) | A t_h / P_dry | breakdown (MPa) | (P - wet)/(dry - wet) | "
            "joints wet | wall joints p/Pw | steps | wall (s) |"
        )
        say("|---|---|---|---|---|---|---|---|")
        xs, ys = [], []
        for rate in args.rates:
            t0 = time.perf_counter()
            r = ramp_breakdown(
                _solid(tmesh), WALL, fluid, args.aperture, PressureRamp(rate, 25e6, args.steps)
            )
            wall = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
            if r.pressure is None:
                say(f"| {rate / 1e6:.3g} | - | no break to 25 MPa | | | | {r.steps} | {wall:.1f} |")
                continue
            x = rate * t_h / dry
            y = (r.pressure - wet) / (dry - wet)
            xs.append(x)
            ys.append(y)
            say(
                f"| {rate / 1e6:.3g} | {x:.3g} | {r.pressure / 1e6:.4f} | {y:.3f} | "
                f"{r.wet_fraction:.1%} | {r.wall_joint_pressure:.3f} | {r.steps} | {wall:.1f} |"
            )
        curves.append((np.array(xs), np.array(ys), f"h = a/{div}", next(styles)))
    Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
    plot_lines(
        args.plot,
        curves,
        "dimensionless pressurisation rate A t_h / P_dry",
        "(P_b - P_wet) / (P_dry - P_wet)",
        "Borehole breakdown vs rate: 0 = penetrating (HF), 1 = dry joints (HW)",
        xscale="log",
    )
    say(f"\nplot: {args.plot}")


if __name__ == "__main__":
    main()
