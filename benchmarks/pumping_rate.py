"""Borehole breakdown against pumping rate, past the first break, with seepage into the joints.

Seed 001's borehole (a = 30 mm in a 1 m plate, E 20 GPa, SH 20 MPa, Sh 12 MPa,
T0 5 MPa; the mesh and rock of ``penetration_rate.py``), joints of the
fracturable zone (r < 6 a) of hydraulic aperture ``--aperture``, dry at the
start, a fluid of ``--viscosity``.  A constant rate is pumped into the cavity
for the time a sealed cavity needs to reach twice the dry first break; cracks
joined to the cavity take its fluid at its pressure
(:func:`hfcdem.coupling.pumping.pump_with_seepage`).

Printed per rate: the first break, the breakdown (the highest peak that a
sustained fall confirms, :func:`hfcdem.coupling.breakdown.detect_breakdown`;
the first peak followed by a 1 % fall until 2026-12-06), the highest pressure
of the run, the failures, the share of joints holding pressure at the end,
the largest mass-balance error and the wall time; then the time-step series
of one rate (``--series``).

    make run CMD="python3 benchmarks/pumping_rate.py"
    make run CMD="python3 benchmarks/pumping_rate.py --divisions 10 --series 2e-6"
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI
from wall_joint_verification import A, borehole_mesh, borehole_solid

from hfcdem.config.materials import Fluid
from hfcdem.coupling.penetration import CavityPumping
from hfcdem.coupling.pumping import PumpingResult, pump_with_seepage

SHMIN = 12e6
WALL = ("wellbore_wall",)
STORAGE = 1.6254e-12  # m^2/Pa of the a/5 cavity (docs/seepage.md, sealed cavity)
DRY = 14.435e6  # the a/5 dry first break (Pa)


def _run(tmesh, rate: float, steps: int, fluid: Fluid, aperture: float) -> PumpingResult:  # type: ignore[no-untyped-def]
    duration = 2.0 * DRY * STORAGE / rate
    pumping = CavityPumping(rate, duration, steps=steps)
    return pump_with_seepage(borehole_solid(tmesh, SHMIN), WALL, fluid, aperture, pumping)


def _mpa(value: float | None) -> str:
    return "-" if value is None else f"{value / 1e6:.3f}"


def main() -> None:
    """Print the rate sweep and one time-step series."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, default=5, help="a / h at the wall")
    parser.add_argument(
        "--rates", type=float, nargs="+", default=[2e-7, 6e-7, 2e-6, 6e-6, 2e-5, 2e-4]
    )
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--viscosity", type=float, default=1.0, help="Pa s")
    parser.add_argument("--aperture", type=float, default=5e-6, help="m")
    parser.add_argument("--series", type=float, default=2e-6, help="rate of the dt series")
    args = parser.parse_args()
    say = print if MPI.COMM_WORLD.rank == 0 else (lambda *a, **k: None)
    tmesh = borehole_mesh(A / args.divisions)
    fluid = Fluid(viscosity=args.viscosity)
    say(
        f"a/{args.divisions}, mu {args.viscosity:g} Pa s, aperture {args.aperture * 1e6:g} um, "
        f"{MPI.COMM_WORLD.size} rank(s)"
    )
    say("rate m2/s | first MPa | breakdown MPa | peak MPa | T/S | wet end | mass err | s")
    for rate in args.rates:
        t0 = time.perf_counter()
        r = _run(tmesh, rate, args.steps, fluid, args.aperture)
        wet = r.history[-1][6] if r.history else 0.0
        say(
            f"{rate:.1e} | {_mpa(r.first_pressure)} | {_mpa(r.breakdown)} | "
            f"{r.peak_pressure / 1e6:.3f} | {r.tensile}/{r.shear} | {wet:.2f} | "
            f"{r.max_mass_error:.1e} | {time.perf_counter() - t0:.1f}"
        )
    say(f"time step series at {args.series:.1e} m2/s:")
    for steps in (50, 100, 200, 400):
        r = _run(tmesh, args.series, steps, fluid, args.aperture)
        say(
            f"  {steps} steps: first {_mpa(r.first_pressure)}, breakdown {_mpa(r.breakdown)} "
            f"at {np.nan if r.breakdown_time is None else r.breakdown_time:.3f} s"
        )


if __name__ == "__main__":
    main()
