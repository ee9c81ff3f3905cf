"""Mesh every standard scene and check its size against ``meshes/reference_counts.json``.

The meshes themselves are not kept in git (they are regenerated in seconds);
their cell and vertex counts are.  Run inside the image::

    python3 meshes/generate.py                       # default resolution -> results/meshes/
    python3 meshes/generate.py --resolution coarse   # the small meshes the tests use
    python3 meshes/generate.py --update              # rewrite the reference counts
    mpirun -n 2 python3 meshes/generate.py --no-picture

It prints a table (scene, cells, vertices, seconds, volume and area checks)
and exits with 1 when a count moved by more than ``--tolerance`` from the
reference (a Gmsh upgrade or a geometry change: look, then ``--update``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import gmsh
from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.io.files import write_atomic
from hfcdem.mesh.build import mesh_scene

HERE = Path(__file__).resolve().parent
REFERENCE = HERE / "reference_counts.json"


def _pct(value: float | None) -> str:
    return "" if value is None else f"{value:+.2%}"


def main(argv: list[str] | None = None) -> int:
    """Mesh the scenes, print the table, compare or update the reference; return the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", default="results/meshes")
    parser.add_argument("--resolution", default="default")
    parser.add_argument("--update", action="store_true", help="rewrite the reference counts")
    parser.add_argument("--tolerance", type=float, default=0.02, help="relative, default 2%%")
    parser.add_argument("--no-picture", action="store_true")
    parser.add_argument("scenes", nargs="*", help="scene names (default: all)")
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    files = sorted((HERE / "scenes").glob("*.toml"))
    if args.scenes:
        files = [f for f in files if f.stem in args.scenes]
    reference = json.loads(REFERENCE.read_text()) if REFERENCE.exists() else {}
    counts = reference.setdefault(args.resolution, {})
    rows, moved, changed = [], [], False
    for path in files:
        scene = load_scene(path, None if args.resolution == "default" else args.resolution)
        report = mesh_scene(scene, Path(args.output) / scene.name, comm, not args.no_picture)
        perf = report.get("perforations") or [{}]
        volume = perf[0].get("volume", {}).get("rel_error")
        areas = report["areas"]
        wall = areas.get("perforation_1_wall", areas.get("wellbore_wall", {})).get("rel_error")
        rows.append(
            (
                scene.name,
                report["cells"],
                report["vertices"],
                report["seconds_to_mesh"],
                report["element_quality"]["min"],
                volume,
                wall,
            )
        )
        ref = counts.get(scene.name)
        if ref and not args.update:
            for key in ("cells", "vertices"):
                if abs(report[key] - ref[key]) > args.tolerance * ref[key]:
                    moved.append(f"{scene.name}: {key} {report[key]} (reference {ref[key]})")
        if args.update or ref is None:
            counts[scene.name] = {"cells": report["cells"], "vertices": report["vertices"]}
            changed = True
    if comm.rank == 0:
        print(
            f"| scene | cells | vertices | s to mesh ({comm.size} rank) | min quality "
            "| tunnel 1 volume err | wall area err |"
        )
        print("|---|---|---|---|---|---|---|")
        for name, cells, verts, sec, q, vol, wall in rows:
            print(
                f"| {name} | {cells} | {verts} | {sec:.1f} | {q:.2f} | {_pct(vol)} | {_pct(wall)} |"
            )
        for line in moved:
            print(f"count moved: {line}", file=sys.stderr)
        if changed:
            reference["gmsh"] = gmsh.__version__
            write_atomic(REFERENCE, json.dumps(reference, indent=2, sort_keys=True) + "\n")
    comm.barrier()
    return 1 if moved else 0


if __name__ == "__main__":
    raise SystemExit(main())
