"""Field perforation cluster: breakdown and where the first crack starts.

Section 3.3 of the perforation paper, after field data of the Changqing
oilfield: a 2 m cube of rock at Sv 43, SH 38, Sh 34 MPa around a 140 mm
horizontal wellbore with a cluster of six 400 mm x 20 mm perforations, 200 mm
apart at 60 degree phasing, water pumped at 1e-7 m3/s.  Field breakdown:
43.0 MPa; the paper's first crack appears at the perforation root after 7 s.

Run (the scene file is meshes/scenes/field_cluster.toml)::

    python3 demos/field_cluster.py -o results/field_cluster
    mpirun -n 2 python3 demos/field_cluster.py -o results/field_cluster

Printed: breakdown next to the field value, the first crack's time and its
distance from the wellbore wall along its perforation (root = near 0).
Written: what ``hfcdem run`` writes (summary.json, pressure.png, fracture.png,
fields.bp, interfaces.pvd).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mpi4py import MPI

from hfcdem.cli import parse_with_petsc_options
from hfcdem.config.scene import load_scene
from hfcdem.references import FIELD_FIRST_CRACK_S, FIELD_MEASURED, FIELD_PAPER_SIMULATED
from hfcdem.workflows.run import OutputInUse, run_scene
from hfcdem.workflows.study import breakdown_text

ROOT = Path(__file__).resolve().parents[1]  # the checkout: scenes and studies


def main(argv: list[str] | None = None) -> dict:
    """Run the demo; return the run's summary."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-o", "--output", default="results/field_cluster")
    parser.add_argument("--resolution", default="coarse", help="mesh resolution of the scene")
    parser.add_argument("--duration", default=None, help="injection time, e.g. '120 s'")
    parser.add_argument("--force", action="store_true", help="overwrite another scene's results")
    args = parse_with_petsc_options(parser, argv)  # PETSc options too
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)

    overrides = {"injection.duration": args.duration} if args.duration else None
    scene = load_scene(
        ROOT / "meshes/scenes/field_cluster.toml", args.resolution, overrides=overrides
    )
    summary = run_scene(scene, args.output, comm, force=args.force, say=say)

    bd = summary["breakdown_pressure_MPa"]
    gap = f" ({bd / FIELD_MEASURED - 1:+.1%})" if bd else ""
    say(
        f"breakdown {breakdown_text(summary)}{gap}, field {FIELD_MEASURED:.1f} MPa, "
        f"paper's CDEM {FIELD_PAPER_SIMULATED:.2f} MPa"
    )
    first = summary.get("first_crack")
    if first:
        say(
            f"first crack at {summary['first_crack_time_s']:.3g} s "
            f"(paper {FIELD_FIRST_CRACK_S:g} s, at the root): {first['interfaces']} interfaces, "
            f"{first['distance_from_wellbore_wall_m'] * 1e3:.0f} mm from the wellbore wall"
        )
    return summary


if __name__ == "__main__":
    try:
        main()
    except OutputInUse as exc:  # another scene's results: say so once, keep them
        if MPI.COMM_WORLD.rank == 0:
            print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(3) from None
