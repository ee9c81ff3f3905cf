"""What one interface event costs in the No. 2 solid: afresh against an in-place update.

For each resolution and solid mode (``full`` DG, ``reduced`` band): the unknowns
solved for, the seconds of a solve of a unit tunnel pressure on the solid as
built (its factorisation done), and of a solve after an event (one facet next to
the tunnel wall breaks: the change of that facet assembled, reduced, and taken
into the low-rank correction of the kept factor, or added and MUMPS
refactorising numerically on the kept sparsity), how many events refactorised,
the columns the correction holds at the end, and the largest difference between
the updated and a fresh solution.  The reduced
band is the one a run starts with (the cracks and the cavity walls with one
vertex ring).

    make run CMD="python3 benchmarks/event_cost.py coarse default"
    make run CMD="mpirun -n 2 python3 benchmarks/event_cost.py coarse --events 5"
"""

from __future__ import annotations

import argparse
import time

import dolfinx
import numpy as np
from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.cdem import CDEMSolid, Loads
from hfcdem.workflows.run import build_fracture, build_solid

comm = MPI.COMM_WORLD
SCENE = "meshes/scenes/perforation_no2.toml"


def say(msg: str) -> None:
    """Print on rank 0."""
    if comm.rank == 0:
        print(msg, flush=True)


def timed(fn) -> float:  # type: ignore[no-untyped-def]
    """Seconds of ``fn()`` on the slowest rank."""
    comm.Barrier()
    t0 = time.perf_counter()
    fn()
    return comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)


def wall_facets(solid: CDEMSolid, cavity_vertices: np.ndarray, count: int) -> list[np.ndarray]:
    """``count`` single owned interfaces at the tunnel wall, one per event (by position)."""
    at_wall = np.isin(solid.vertex_ids, cavity_vertices).sum(axis=1) >= solid.gdim - 1
    key = np.where(at_wall & solid.owned, solid.midpoints[:, 0], np.inf)
    events = []
    for k in range(count):
        target = np.sort(np.concatenate(comm.allgather(key[np.isfinite(key)])))[5 * k]
        events.append(np.flatnonzero(key == target))
    return events


def row(res: str, mode: str, events: int) -> None:
    """Print the row of one resolution and mode."""
    scene = load_scene(SCENE, None if res == "default" else res, overrides={"solver.solid": mode})
    tmesh = create_scene_mesh(scene, comm).tmesh
    solid = build_solid(scene, tmesh)
    frac = build_fracture(scene, solid)  # frees the reduced band a run starts with
    cavity = frac.settings.cavity
    loads = Loads(cavity=dict.fromkeys(cavity, 1.0), in_situ_factor=0.0)
    t_fresh = timed(lambda: solid.solve(loads))
    t_events = []
    for chosen in wall_facets(solid, frac.cavity_vertices, events):
        solid.break_facets(chosen, np.ones(len(chosen), dtype=np.int8), 0.0)
        t_events.append(timed(lambda: solid.solve(loads)))
    updated = solid.u.x.array.copy()
    ref = build_solid(scene, tmesh)
    ref.band.include(solid.band.free, rings=0)
    ref.states.restore(solid.states.copy())
    ref.solve(loads)
    diff = comm.allreduce(float(np.abs(updated - ref.u.x.array).max()), op=MPI.MAX)
    diff /= comm.allreduce(float(np.abs(ref.u.x.array).max()), op=MPI.MAX)
    counts = solid.operator.counts
    say(
        f"| {res} | {mode} | {solid.num_dofs} | {solid.band.count()} | {t_fresh:.2f} "
        f"| {np.mean(t_events):.2f} | {counts['updated']}/{events} "
        f"| {solid.operator.low_rank_columns} | {diff:.1e} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("resolutions", nargs="+", help="coarse, default or paper")
    parser.add_argument("--modes", nargs="+", default=["full", "reduced"])
    parser.add_argument("--events", type=int, default=3)
    args = parser.parse_args()
    say(f"{comm.size} rank(s); seconds of the slowest rank; DOLFINx {dolfinx.__version__}")
    say(
        "\n| resolution | solid | unknowns | free interfaces | first solve s "
        "| solve after an event s | refactorised | low-rank columns | max diff / max u |\n"
        "|---|---|---|---|---|---|---|---|---|"
    )
    for res in args.resolutions:
        for mode in args.modes:
            row(res, mode, args.events)


if __name__ == "__main__":
    main()
