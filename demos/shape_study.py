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

import argparse
from pathlib import Path

from mpi4py import MPI

from hfcdem.cli import parse_with_petsc_options
from hfcdem.references import SHAPE_ORDERINGS, SHAPES
from hfcdem.workflows.study import breakdown_text, load_study, pick_metric, run_study

ROOT = Path(__file__).resolve().parents[1]  # the checkout: scenes and studies


def main(argv: list[str] | None = None) -> list[dict]:
    """Run the demo; return one result row per model."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-o", "--output", default="results/shape_study")
    parser.add_argument("--resolution", default="coarse", help="mesh resolution of the scene")
    parser.add_argument("--groups", type=int, default=1, help="cases run at once")
    parser.add_argument("--duration", default=None, help="injection time, e.g. '120 s'")
    parser.add_argument("--models", default=None, help="comma-separated subset, e.g. no2,1-1")
    args = parse_with_petsc_options(parser, argv)  # PETSc options too
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)

    study = load_study(ROOT / "studies/shape_study.toml", resolution=args.resolution)
    if args.models:
        study = study.with_values(tuple(args.models.split(",")))
    if args.duration:
        study = study.with_fixed({"injection.duration": args.duration})
    rows = run_study(study, args.output, comm, groups=args.groups, say=say)

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
            say(
                f"{claim} ({low} < {high}) by {metric}: {held} "
                f"({ours[low]:.2f} vs {ours[high]:.2f} MPa)"
            )
    return rows


if __name__ == "__main__":
    main()
