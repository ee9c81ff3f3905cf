"""Strength over a material length (``rock.strength_length``): mesh convergence and what it does.

1. Seed 001's dry borehole (``borehole_plate.toml``: a = 30 mm, SH 20, Sh 12,
   T0 5 MPa) pumped to breakdown at wall elements a/5, a/10, a/20, with the
   strength at a point (l = 0, Hubbert-Willis 21 MPa) and over l = 3 and 6 mm
   (the filtered Kirsch field's closed form, :func:`filtered_wall_breakdown`).
   Printed per row: first break, its error against the reference, the
   breakdown (peak confirmed by a drop) and the wall time; then the observed
   order of the first break and its Richardson limit per l.
2. The lab specimen (coarse, dry joints as shipped, 8 s of pumping) at 30 / 45 /
   60 deg with l = 0, 0.5, 1 and 2 mm: interfaces failing before injection and
   the first break.

    make run CMD="mpirun -n 2 python3 benchmarks/strength_length.py"
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from hfcdem.analytic import filtered_wall_breakdown, hubbert_willis_breakdown
from hfcdem.config.scene import load_scene
from hfcdem.workflows.run import run_scene

ROOT = Path(__file__).resolve().parents[1] / "meshes" / "scenes"
COMM = MPI.COMM_WORLD


def say(text: str) -> None:
    """Print on rank 0."""
    if COMM.rank == 0:
        print(text, flush=True)


def run(
    path: Path, sets: dict[str, str], where: Path, resolution: str | None = None
) -> tuple[dict, float]:
    """Run a scene with overrides; return its summary and wall time."""
    t0 = time.perf_counter()
    scene = load_scene(path, resolution, overrides=sets)
    summary = run_scene(scene, where, COMM, force=True, say=lambda m: None)
    return summary, time.perf_counter() - t0


def borehole(where: Path) -> None:
    """Part 1: the borehole's first break against the closed forms, three meshes."""
    say("| l | wall h | first break MPa | error | breakdown MPa | wall s |")
    say("|---|---|---|---|---|---|")
    for length in (0.0, 3e-3, 6e-3):
        ref = (
            filtered_wall_breakdown(0.03, 20e6, 12e6, 5e6, length)
            if length
            else hubbert_willis_breakdown(20e6, 12e6, 5e6)
        )
        firsts = []
        for size in ("6 mm", "3 mm", "1.5 mm"):
            sets = {"geometry.mesh.size": size, "injection.duration": "60 s"}
            if length:
                sets["rock.strength_length"] = f"{length * 1e3:g} mm"
            s, wall = run(ROOT / "borehole_plate.toml", sets, where / "bh")
            first = s["first_crack_pressure_MPa"]
            firsts.append(first)
            bd = s["breakdown_pressure_MPa"]
            say(
                f"| {length * 1e3:g} mm | {size} | {first:.3f} | {first * 1e6 / ref - 1:+.1%} | "
                f"{bd if bd is None else f'{bd:.2f}'} | {wall:.1f} |"
            )
        d1, d2 = firsts[0] - firsts[1], firsts[1] - firsts[2]
        # a negative order (the changes growing) gives no extrapolation
        order = math.log2(d1 / d2) if d1 * d2 > 0 and abs(d1) > abs(d2) else float("nan")
        limit = firsts[2] - d2 / (2**order - 1) if math.isfinite(order) else float("nan")
        say(
            f"  l = {length * 1e3:g} mm: reference {ref / 1e6:.3f} MPa; "
            f"observed order {order:.2f}, Richardson limit {limit:.3f} MPa "
            f"({limit * 1e6 / ref - 1:+.1%})"
        )


def lab(where: Path) -> None:
    """Part 2: the lab specimen at the coarse mesh, several lengths."""
    say("| azimuth | l | failed before injection | first break MPa | peak MPa | wall s |")
    say("|---|---|---|---|---|---|")
    for azimuth in (30, 45, 60):
        for length in ("0 mm", "0.5 mm", "1 mm", "2 mm"):
            sets = {"injection.duration": "8 s", "rock.strength_length": length}
            path = ROOT / f"lab_specimen_{azimuth}deg.toml"
            s, wall = run(path, sets, where / "lab", "coarse")
            first = s["first_crack_pressure_MPa"]
            say(
                f"| {azimuth} deg | {length} | {s['initial_failures']} | "
                f"{'none' if first is None else f'{first:.2f}'} | "
                f"{s['peak_pressure_MPa']:.2f} | {wall:.1f} |"
            )


def main() -> None:
    """Run both parts in a scratch directory."""
    scratch = Path(tempfile.mkdtemp()) if COMM.rank == 0 else None
    where = Path(COMM.bcast(str(scratch), root=0))
    borehole(where)
    lab(where)


if __name__ == "__main__":
    main()
