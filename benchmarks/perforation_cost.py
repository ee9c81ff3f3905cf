"""What a perforation run costs: mesh, unknowns, the coupled build, memory, and a full run.

The No. 2 scene at each resolution: cells, unknowns, seconds to mesh, seconds
to build the solid and fluid (the first factorisation and condensation), peak
memory; with ``--run`` also the whole injection (wall time, steps, rebuilds and
their seconds).  What one interface event costs is ``event_cost.py``'s: since
the solid keeps its factor through events (a low-rank correction) and a rebuild
of unchanged states is a cache hit, timing ``rebuild()`` here measured nothing.

    make run CMD="mpirun -n 2 python3 benchmarks/perforation_cost.py coarse default paper"
    make run CMD="mpirun -n 2 python3 benchmarks/perforation_cost.py coarse --run"
    make run CMD="mpirun -n 2 python3 benchmarks/perforation_cost.py default --solver direct"
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.workflows.run import build_fracture, build_solid, run_scene

SCENE = Path(__file__).resolve().parents[1] / "meshes/scenes/perforation_no2.toml"
comm = MPI.COMM_WORLD


def memory_mb() -> float:
    """Peak resident memory of all ranks together (MB)."""
    return comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, op=MPI.SUM) / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("resolutions", nargs="+", help="coarse, default or paper")
    parser.add_argument("--run", action="store_true", help="also run the whole injection")
    parser.add_argument("--duration", default=None, help="injection time for --run")
    parser.add_argument(
        "--solver", default="auto", choices=("auto", "direct", "iterative"), help="linear solver"
    )
    args = parser.parse_args()
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    say("| resolution | solver | cells | unknowns | mesh s | build s | memory MB | run |")
    say("|---|---|---|---|---|---|---|---|")
    for res in args.resolutions:
        chosen = {"solver.linear_solver": args.solver}
        scene = load_scene(SCENE, None if res == "default" else res, overrides=chosen)
        t0 = time.perf_counter()
        tmesh = create_scene_mesh(scene, comm).tmesh
        t1 = time.perf_counter()
        solid = build_solid(scene, tmesh)
        frac = build_fracture(scene, solid)
        t2 = time.perf_counter()
        cells = tmesh.mesh.topology.index_map(3).size_global
        dofs = solid.V.dofmap.index_map.size_global * 3
        run = ""
        if args.run:
            overrides = chosen | ({"injection.duration": args.duration} if args.duration else {})
            scene = load_scene(SCENE, None if res == "default" else res, overrides=overrides)
            s = run_scene(scene, Path("results/benchmarks") / f"no2_{res}", comm, force=True)
            run = (
                f"{s['simulated_time_s']:.0f} s simulated in {s['wall_time_s']:.0f} s: "
                f"{s['steps']} steps, {s['rebuilds']} rebuilds ({s['rebuild_seconds']:.0f} s)"
            )
        say(
            f"| {res} | {solid.solver_kind} | {cells} | {dofs} | {t1 - t0:.1f} | "
            f"{t2 - t1:.1f} | {memory_mb():.0f} | {run} |"
        )
        del frac, solid, tmesh


if __name__ == "__main__":
    main()
