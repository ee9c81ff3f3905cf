"""A pumped scene's answers against its time step (the first step and the largest, halved together).

Runs the scene at ``--resolution`` (default ``coarse``) for each pair
``--steps "FIRST/LARGEST,..."`` (default: the shipped perforation scenes' 0.5 / 2 s,
then halved three times) and prints, per row: the breakdown (a peak confirmed by
a drop; none if the run never confirmed one), the highest pressure, the first
crack (pressure, time, place), the failures, the steps taken and the wall time.

    make run CMD="python3 benchmarks/time_step_convergence.py meshes/scenes/perforation_no2.toml"
    make run CMD="mpirun -n 2 python3 benchmarks/time_step_convergence.py \\
        meshes/scenes/field_cluster.toml --steps '0.5 s/2 s,0.25 s/1 s,0.125 s/0.5 s'"
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.workflows.run import run_scene

COMM = MPI.COMM_WORLD
STEPS = "0.5 s/2 s,0.25 s/1 s,0.125 s/0.5 s,0.0625 s/0.25 s"


def say(text: str) -> None:
    """Print on rank 0."""
    if COMM.rank == 0:
        print(text, flush=True)


def mpa(value: float | None) -> str:
    """A pressure in MPa for the table ('none' when absent)."""
    return "none" if value is None else f"{value:.3f}"


def main() -> None:
    """Run the scene once per step pair and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--resolution", default="coarse")
    parser.add_argument("--steps", default=STEPS, help="FIRST/LARGEST pairs, comma-separated")
    args = parser.parse_args()
    pairs = [tuple(pair.split("/")) for pair in args.steps.split(",")]
    say("| time step (first / largest) | breakdown MPa | highest MPa | first crack | "
        "tensile / shear | steps | wall s |")  # fmt: skip
    say("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for k, (first, largest) in enumerate(pairs):
            sets = {"solver.time_step": first, "solver.max_time_step": largest}
            scene = load_scene(
                args.scene, args.resolution, overrides=sets | {"output.pictures": False}
            )
            where = Path(COMM.bcast(tmp, root=0)) / f"run_{k}"
            t0 = time.perf_counter()
            s = run_scene(scene, where, COMM, force=True, say=lambda m: None)
            crack = s.get("first_crack") or {}
            where_crack = (
                f"{mpa(s['first_crack_pressure_MPa'])} MPa at {s['first_crack_time_s']:.2f} s, "
                f"{crack.get('place', '-')}"
                if s["first_crack_time_s"] is not None
                else "none"
            )
            say(
                f"| {first} / {largest} | {mpa(s['breakdown_pressure_MPa'])} | "
                f"{mpa(s['peak_pressure_MPa'])} | {where_crack} | "
                f"{s['tensile_failures']} / {s['shear_failures']} | {s['steps']} | "
                f"{time.perf_counter() - t0:.0f} |"
            )


if __name__ == "__main__":
    main()
