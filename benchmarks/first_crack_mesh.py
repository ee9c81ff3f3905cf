"""The perforation scenes' first crack against the mesh (and the strength length).

Runs each scene to its first crack (``injection.until = "first crack"``) on each
mesh of ``--meshes`` (named resolutions, or ``[geometry.mesh]`` fields over the
default resolution, e.g. ``"size=4.5 mm;circle_elements=43"``) and each
``--strength-lengths`` value (``rock.strength_length``; ``0 mm``: strength at
a point, as the scenes ship), and prints one row per run: the cells, the
interfaces failed on excavation, the first crack (pressure, time, place,
distance from the wellbore wall and as a share L of the tunnel, mode), each
part's highest failure ratio then (1: at its strength), the wall time and the
ranks' summed peak memory.
Then, per scene, how far the first-crack pressure moved from one mesh to the
next, and the scenes' spread on each mesh.

    make run CMD="python3 benchmarks/first_crack_mesh.py"
    make run CMD="python3 benchmarks/first_crack_mesh.py --ranks 1 \\
        meshes/scenes/perforation_no2.toml --meshes 'default,size=4.5 mm;circle_elements=43' \\
        --strength-lengths '0 mm,6 mm' --set solver.linear_solver=direct"
"""

from __future__ import annotations

import argparse
import itertools
import json
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

CHARGES = [f"meshes/scenes/perforation_no{k}.toml" for k in range(1, 5)]
SHAPES = [f"meshes/scenes/shape_{s}.toml" for s in
          ("1-1", "1-2", "1-3", "2-1", "2-2", "3-1", "3-2", "4-1", "4-2")]  # fmt: skip
PARTS = ("root", "middle", "far end", "beyond the tip")


def say(text: str) -> None:
    """Print a line at once."""
    print(text, flush=True)


def run_to_first_crack(
    scene_path: str, mesh: str, length: str, out: Path, extra: dict[str, str], ranks: int
) -> tuple[dict[str, Any], float]:
    """Run one scene on one mesh to its first crack; return its summary and wall time.

    Each run is its own ``hfcdem run`` process, so one run's memory is not
    held into the next (a dozen default-mesh runs in one process ran out of
    24 GB).
    """
    sets = extra | {
        "injection.until": '"first crack"',
        "rock.strength_length": f'"{length}"',
        "output.pictures": "false",
    }
    command = [*(["mpirun", "-n", str(ranks)] if ranks > 1 else []), "hfcdem", "run",
               scene_path, "-o", str(out), "--force"]  # fmt: skip
    if "=" in mesh:  # fields of [geometry.mesh] over the default resolution
        for item in mesh.split(";"):
            key, value = item.split("=", 1)
            sets[f"geometry.mesh.{key.strip()}"] = (
                value.strip() if value.strip()[:1].isdigit() and " " not in value.strip()
                else f'"{value.strip()}"'
            )  # fmt: skip
    else:
        command += ["--resolution", mesh]
    for key, value in sets.items():
        command += ["--set", f"{key}={value}"]
    t0 = time.perf_counter()
    done = subprocess.run(command, check=False, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    if done.returncode != 0:  # e.g. out of memory: the row says so, the table goes on
        return {"failed": done.returncode}, wall
    return json.loads((out / "summary.json").read_text()), wall


def row(name: str, mesh: str, length: str, s: dict[str, Any], wall: float) -> str:
    """One table row of a run's first crack."""
    if "failed" in s:
        return f"| {name} | {mesh} | {length} | the run failed (exit {s['failed']}) |"
    first = s.get("first_crack") or {}
    if s.get("first_crack_pressure_MPa") is None:
        crack = "none | | | | |"
    else:
        share = first.get("fraction_of_tunnel")
        crack = (
            f"{s['first_crack_pressure_MPa']:.2f} | {s['first_crack_time_s']:.2f} | "
            f"{first.get('place', '-')} | {1e3 * first['distance_from_wellbore_wall_m']:.1f}"
            f"{f' ({share:.2f} L)' if share is not None else ''} | {first.get('mode', '-')} |"
        )
    ratios = first.get("ratio_by_place") or {}
    listed = " / ".join(f"{ratios[p]:.2f}" if p in ratios else "-" for p in PARTS)
    return (
        f"| {name} | {mesh} ({s['cells']:,} cells) | {length} | {s['initial_failures']} | "
        f"{crack} {listed} | {wall:.0f} | {s['peak_memory_MB'] / 1024:.1f} |"
    )


def main() -> None:
    """Run every scene on every mesh and strength length; print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=CHARGES + SHAPES)
    parser.add_argument("--meshes", default="coarse,default")
    parser.add_argument("--strength-lengths", default="0 mm")
    parser.add_argument("--ranks", type=int, default=2, help="each run's MPI ranks")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="a scene field for every run, e.g. solver.linear_solver=direct",
    )  # fmt: skip
    args = parser.parse_args()
    extra = dict(item.split("=", 1) for item in args.set)  # TOML values, as hfcdem run --set
    meshes = [m.strip() for m in args.meshes.split(",")]
    lengths = [v.strip() for v in args.strength_lengths.split(",")]
    say(
        "| scene | mesh | strength length | failed on excavation | first crack MPa | time s | "
        "place | from the wellbore wall mm | mode | highest failure ratio then: root / middle / "
        "far end / beyond the tip | wall s | memory GB |"
    )
    say("|---|---|---|---|---|---|---|---|---|---|---|---|")
    found: dict[tuple[str, str], dict[str, float | None]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        for k, path in enumerate(args.scenes):
            name = Path(path).stem.removeprefix("perforation_")
            for length in lengths:
                for j, mesh in enumerate(meshes):
                    out = base / f"run_{k}_{j}"
                    s, wall = run_to_first_crack(path, mesh, length, out, extra, args.ranks)
                    say(row(name, mesh, length, s, wall))
                    found.setdefault((name, length), {})[mesh] = s.get("first_crack_pressure_MPa")
    say("")
    say("| scene | strength length | first crack MPa, mesh by mesh | change per refinement |")
    say("|---|---|---|---|")
    for (name, length), by_mesh in found.items():
        values = [by_mesh[m] for m in meshes]
        changes = [f"{b / a - 1:+.1%}" if a and b else "-" for a, b in itertools.pairwise(values)]
        shown = " / ".join(f"{v:.2f}" if v else "none" for v in values)
        say(f"| {name} | {length} | {shown} | {', '.join(changes)} |")
    say("")
    for length in lengths:
        for mesh in meshes:
            values = [v[mesh] for (n, ln), v in found.items() if ln == length and v[mesh]]
            if len(values) > 1:
                say(
                    f"spread over the scenes, {mesh}, strength length {length}: "
                    f"{min(values):.2f} - {max(values):.2f} MPa ({max(values) - min(values):.2f})"
                )


if __name__ == "__main__":
    main()
