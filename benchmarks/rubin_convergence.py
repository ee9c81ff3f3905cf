"""Rubin's PMMA experiment (``rubin_pmma.toml``): its answers against the time step and the mesh.

The report compares the peak borehole pressure with the paper's breakdown
(= T0 = 6 MPa) and the time the fluid reaches gauge D (about 20 s).  Printed:

1. the shipped mesh (6.5 mm) as shipped (0.5 s first, growing to 1 s, Table 2's
   dt, each step bounded to a 2 % change of the borehole pressure), with the bound
   at 5 and 1 % and without it, and with the time step held at 1, 0.5, 0.25,
   0.125, 0.0625 and 0.03125 s (no bound);
2. the shipped steps on meshes of 12 (the scene's ``coarse``), 6.5, 4.5 and
   3.25 mm (path facets 7.5, 5, 3.5, 2.5 mm).

Per row: the peak, when the right wing has broken past D, when D's facet is
wet (the report's "D rises"), the steps and the wall time.  About 2 minutes on one
rank.

    make run CMD="python3 benchmarks/rubin_convergence.py"
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.reproduce.rubin import GAUGES, read_gauges
from hfcdem.workflows.run import run_scene

SCENE = Path(__file__).resolve().parents[1] / "meshes" / "scenes" / "rubin_pmma.toml"
COMM = MPI.COMM_WORLD


def say(text: str) -> None:
    """Print on rank 0."""
    if COMM.rank == 0:
        print(text, flush=True)


def steps(dt: str) -> dict[str, str]:
    """Overrides that hold every step at ``dt`` (no bound on the pressure's change)."""
    return {"solver.time_step": dt, "solver.max_time_step": dt} | bound(math.inf)


def bound(fraction: float) -> dict[str, float]:
    """Overrides that bound each step's change of the borehole pressure to ``fraction``."""
    return {"solver.max_pressure_change": fraction}


def mesh(size: str, path: str) -> dict[str, str]:
    """Overrides for a uniform mesh of ``size`` with path facets of ``path``."""
    return {
        "geometry.mesh.size": size,
        "geometry.mesh.size_far": size,
        "geometry.mesh.path_size": path,
    }


def row(label: str, sets: dict[str, str], where: Path, resolution: str | None = None) -> None:
    """Run the scene with ``sets`` and print its row."""
    t0 = time.perf_counter()
    scene = load_scene(SCENE, resolution, overrides=sets | {"output.pictures": False})
    summary = run_scene(scene, where, COMM, force=True, say=lambda m: None)
    seconds = time.perf_counter() - t0
    gauges = read_gauges(where, scene.geometry)
    past, wet = gauges.reached(GAUGES["D"][1]), gauges.wet_at_d()
    say(
        f"| {label} | {summary['cells']:,} | {np.nanmax(gauges.history_pressure):.3f} | "
        f"{'-' if past is None else f'{past:.1f}'} | {'-' if wet is None else f'{wet:.1f}'} | "
        f"{summary['steps']} | {seconds:.1f} |"
    )


def main() -> None:
    """Print both series."""
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        say("| run | cells | peak MPa | broken past D s | D wet s | steps | wall s |")
        say("|---|---|---|---|---|---|---|")
        row("6.5 mm, as shipped (0.5 -> 1 s, 2 % a step)", {}, where / "shipped")
        for fraction in (0.05, 0.01, math.inf):
            label = f"{100 * fraction:g} % a step" if math.isfinite(fraction) else "no bound"
            row(f"6.5 mm, 0.5 -> 1 s, {label}", bound(fraction), where / "b")
        for dt in ("1 s", "0.5 s", "0.25 s", "0.125 s", "0.0625 s", "0.03125 s"):
            row(f"6.5 mm, dt {dt}", steps(dt), where / dt.replace(" ", ""))
        row("12 mm (coarse), as shipped", {}, where / "coarse", "coarse")
        for size, path in (("4.5 mm", "3.5 mm"), ("3.25 mm", "2.5 mm")):
            row(f"{size}, as shipped", mesh(size, path), where / size)


if __name__ == "__main__":
    main()
