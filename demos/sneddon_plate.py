"""Pressurised crack in a plate: the paper's verification against Sneddon (section 3.1).

A 0.2 m crack in the middle of a 1 m square plate (Table 1: E 210 GPa, nu 0.25)
holds water at 22 MPa.  The paper compares the crack-face displacement u_y at
11 points along the crack with Sneddon's infinite-plate solution (its eq. 21),
u_y = 2 p l (1 - nu^2) / E sqrt(1 - x^2 / l^2).  The crack is an open interface
of the CDEM solid, loaded on both faces; the plate's outer edge is fixed.
Every other element face is a spring, kn = alpha E / h, as in the paper's
CDEM: the springs make the plate a little softer (+1.9 % at alpha 100, -0.3 %
at 1000, README "What is verified").

The 1 m plate is stiffer than Sneddon's infinite one; ``--half-width 5`` (a
10 m plate) shows the gap closing, so what is left is the discretisation.
Run::

    python3 demos/sneddon_plate.py -o results/sneddon
    mpirun -n 2 python3 demos/sneddon_plate.py -o results/sneddon --half-width 5

Printed: u_y at the 11 points, ours next to eq. (21).  Written: summary.json,
sneddon.csv, sneddon.png.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI

from hfcdem import analytic
from hfcdem.cdem import CDEMSolid, Loads
from hfcdem.interfaces import InterfaceModel
from hfcdem.meshing import CrackPlate, create_crack_plate
from hfcdem.output import prepare_output_dir, write_csv, write_json
from hfcdem.sampling import evaluate_at_points
from hfcdem.solid import ElasticMaterial, InSituStress

# Table 1 of the perforation paper
E, NU, P, HALF_CRACK = 210e9, 0.25, 22e6, 0.1


def main(argv: list[str] | None = None) -> dict:
    """Run the demo; return the summary it writes."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-o", "--output", default="results/sneddon")
    parser.add_argument("--half-width", type=float, default=0.5, help="plate half width, m")
    parser.add_argument("--size", type=float, default=0.005, help="element size at the crack, m")
    parser.add_argument("--alpha", type=float, default=100.0, help="spring factor alpha")
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    out = prepare_output_dir(args.output, comm)
    wall0 = time.perf_counter()

    # half model x >= 0; the far field is coarse
    plate = CrackPlate(HALF_CRACK, args.half_width, args.size, max(args.half_width / 10, args.size))
    solid = CDEMSolid(
        create_crack_plate(plate, comm),
        ElasticMaterial(E, NU),
        InSituStress(0.0, 0.0),
        InterfaceModel(alpha=args.alpha),
        degree=2,
        rollers={"symmetry_x": 0},
        fixed=["outer"],
    )
    solid.solve(Loads(crack_pressure=P))

    # the 11 monitoring points of the paper, evaluated just above and below the crack
    x = np.linspace(-HALF_CRACK, HALF_CRACK, 11)
    xs = np.clip(np.abs(x), 1e-9, HALF_CRACK * (1 - 1e-9))
    up = np.column_stack([xs, np.full_like(xs, 1e-10)])
    down = np.column_stack([xs, np.full_like(xs, -1e-10)])
    uy = 0.5 * (evaluate_at_points(solid.u, up)[:, 1] - evaluate_at_points(solid.u, down)[:, 1])
    exact = 0.5 * analytic.sneddon_opening(x, HALF_CRACK, P, E, NU)
    for xi, ours, ref in zip(x, uy, exact, strict=True):
        gap = f"{ours / ref - 1:+.2%}" if ref > 0 else "(tip)"
        say(f"x {xi:+.3f} m: u_y {ours * 1e6:7.3f} um, eq. (21) {ref * 1e6:7.3f} um {gap}")
    centre = float(uy[5] / exact[5] - 1)
    say(
        f"centre: {uy[5] * 1e6:.3f} um vs {exact[5] * 1e6:.3f} um ({centre:+.2%}), plate "
        f"{2 * args.half_width:g} m"
    )

    summary = {
        "plate_width_m": 2 * args.half_width,
        "alpha": args.alpha,
        "centre_uy_um": float(uy[5] * 1e6),
        "sneddon_centre_uy_um": float(exact[5] * 1e6),
        "centre_relative_error": centre,
        "max_relative_error_inner": float(np.max(np.abs(uy[1:-1] / exact[1:-1] - 1))),
        "wall_time_s": time.perf_counter() - wall0,
        "cells": solid.mesh.topology.index_map(2).size_global,
    }
    write_json(out / "summary.json", summary, comm)
    write_csv(
        out / "sneddon.csv", ["x_m", "uy_m", "sneddon_uy_m"], zip(x, uy, exact, strict=True), comm
    )
    if comm.rank == 0:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.5, 4))
        fine = np.linspace(-HALF_CRACK, HALF_CRACK, 201)
        ax.plot(
            fine,
            0.5 * analytic.sneddon_opening(fine, HALF_CRACK, P, E, NU) * 1e6,
            "k-",
            label="Sneddon, eq. (21)",
        )
        ax.plot(x, uy * 1e6, "o", label=f"hfcdem, {2 * args.half_width:g} m plate")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("u_y (um)")
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "sneddon.png", dpi=120)
        plt.close(fig)
    comm.barrier()
    return summary


if __name__ == "__main__":
    main()
