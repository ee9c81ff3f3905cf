"""Where the time of a 3D pumped run with seepage goes: Perforation No. 2, one rank.

No. 2's scene with the joints seeping (``wall_joints = "seepage"``), no wall
film, water's stiffness (the seepage model's cavity is the mesh's), pumped
for a few seconds under cProfile, with a time limit.  Prints the steps done
and the share of the wall time in the seepage network's linear solves, the
trial seepage steps of the cavity balance, the solid's solves and the form
compilation (issue 14: "3D pumped seepage cost", profile first).  Each
cavity balance is one Newton on the joints and the cavity pressure together;
trial seepage steps appear only where that Newton failed and the secant
took over.  It also shows what an interface event costs: the joints' network
rebuilt, MUMPS's back-substitutions and numeric refactorisations of the
solid, and the low-rank (Woodbury) columns.  The KSP set-ups are split by
their caller: the solid's factorisations (``solvers.py:attempt`` the first,
``operator.py:_update`` the numeric ones after events) and the joints' LU
(``seepage.py``).

    make run CMD="python3 benchmarks/seepage_profile.py --seconds 600"
    make run CMD="python3 benchmarks/seepage_profile.py --resolution default --duration 38 \
        --joint-pressure '30 MPa' --landing tolerance --seconds 1800"
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import re
import signal
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.workflows.run import run_scene

ROOT = Path(__file__).resolve().parents[1]


class _TimeUp(Exception):
    pass


def _time_up(*_: object) -> None:
    raise _TimeUp


def _scene_text(duration: float, bulk_modulus: str) -> str:
    text = (ROOT / "meshes/scenes/perforation_no2.toml").read_text()
    text = re.sub(r"(?m)^wall_film = .*\n", "", text)
    text = re.sub(r'(?m)^wall_joints = "[a-z]+"', 'wall_joints = "seepage"', text)
    text = re.sub(r"(?m)^max_pressure_change = .*\n", "", text)  # not taken by seepage
    text = re.sub(r'(?m)^duration = "[^"]*"', f'duration = "{duration:g} s"', text)
    text = re.sub(r'(?m)^bulk_modulus = "[^"]*"', f'bulk_modulus = "{bulk_modulus}"', text)
    return text.replace('name = "perforation_no2"', 'name = "no2_seepage_profile"')


def _cumulative(stats: pstats.Stats, pattern: str) -> tuple[float, int]:
    """Cumulative time and calls of the functions whose ``file:line(name)`` matches."""
    total, calls = 0.0, 0
    for (file, line, name), (_, ncalls, _, cum, _) in stats.stats.items():  # type: ignore[attr-defined]
        if re.search(pattern, f"{file}:{line}({name})"):
            total += cum
            calls += ncalls
    return total, calls


def _setups_by_caller(stats: pstats.Stats) -> dict[str, tuple[float, int]]:
    """Seconds and calls of ``KSP.setUp`` by the module that called it."""
    out: dict[str, tuple[float, int]] = {}
    for (_, _, name), entry in stats.stats.items():  # type: ignore[attr-defined]
        if "'setUp' of 'petsc4py.PETSc.KSP'" not in name:
            continue
        for (cfile, _, cname), (_, ncalls, _, cum) in entry[4].items():
            where = f"{Path(cfile).name}:{cname}"
            seconds, calls = out.get(where, (0.0, 0))
            out[where] = (seconds + cum, calls + ncalls)
    return dict(sorted(out.items(), key=lambda item: -item[1][0]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=int, default=600, help="time limit of the run (s)")
    ap.add_argument("--resolution", default="coarse")
    ap.add_argument("--duration", type=float, default=4.0, help="pumping time (s)")
    ap.add_argument("--bulk-modulus", default="2.2 GPa")
    ap.add_argument(
        "--joint-pressure", default=None, help="joints start full at this pressure, e.g. '30 MPa'"
    )
    ap.add_argument("--landing", default=None, help="solver.break_landing (exact, step, tolerance)")
    args = ap.parse_args()
    overrides = {}
    if args.joint_pressure is not None:
        overrides["injection.joint_pressure"] = args.joint_pressure
    if args.landing is not None:
        overrides["solver.break_landing"] = args.landing
    if MPI.COMM_WORLD.size != 1:
        raise SystemExit("one rank: the profile is of one process")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "no2_seepage.toml"
        path.write_text(_scene_text(args.duration, args.bulk_modulus))
        scene = load_scene(path, args.resolution, overrides=overrides)
        signal.signal(signal.SIGALRM, _time_up)
        signal.alarm(args.seconds)
        prof = cProfile.Profile()
        t0 = time.perf_counter()
        prof.enable()
        try:
            summary = run_scene(scene, Path(tmp) / "out", force=True, say=print)
            ended = f"finished: {summary.get('stopped') or 'the whole duration'}"
        except _TimeUp:
            ended = f"stopped by the {args.seconds} s limit"
        prof.disable()
        signal.alarm(0)
        wall = time.perf_counter() - t0
    stats = pstats.Stats(prof)
    print(f"\n{ended}; {wall:.1f} s of wall time")
    parts = [
        ("pumped steps", r"pumping\.py:\d+\(step\)"),
        ("cavity balances (joints + cavity Newton)", r"seepage\.py:\d+\(step_pumped\)"),
        ("trial seepage steps (secant fallback)", r"seepage\.py:\d+\(step\)"),
        ("seepage Newton matrices set", r"seepage\.py:\d+\(_factorise\)"),
        ("seepage network solves (LU inside)", r"seepage\.py:\d+\(_solve\)"),
        ("solid solves", r"cdem\.py:\d+\(solve\)"),
        ("MUMPS back-substitutions (all solvers)", r"'matSolve' of"),
        ("KSP set-ups (MUMPS factorisations, all)", r"'setUp' of 'petsc4py\.PETSc\.KSP'"),
        ("low-rank columns of the solid's events", r"lowrank\.py:\d+\(add\)"),
        ("joint network rebuilt after breaks", r"pumping\.py:\d+\(_network\)"),
        ("debris search (loose blocks)", r"fragments\.py:\d+\(debris\)"),
        ("form compilation (ffcx)", r"jit\.py:\d+\(ffcx_jit\)"),
        ("checkpoints offered (built, written)", r"pumped_checkpoint\.py:\d+\(offer\)"),
    ]
    for label, pattern in parts:
        cum, calls = _cumulative(stats, pattern)
        print(f"{label:40s} {calls:6d} calls {cum:8.1f} s {cum / wall:6.1%}")
    # the set-ups by who asked: the solid's factorisations, or the joints' LU
    for where, (cum, calls) in _setups_by_caller(stats).items():
        print(f"  set-ups from {where:27s} {calls:6d} calls {cum:8.1f} s {cum / wall:6.1%}")
    stats.sort_stats("tottime").print_stats(12)


if __name__ == "__main__":
    main()
