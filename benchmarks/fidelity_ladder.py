"""The fidelity ladder on Perforation No. 2: the answer and the cost of each rung.

Runs No. 2 (``meshes/scenes/perforation_no2.toml``) for its whole injection at
one resolution, one rung after another, and prints a table: breakdown (by the
rung's own rule, and by the uniform rung's for all: ``shared_breakdown``), peak
pressure, first tensile break, failures, steps, solid solves, stiffness
factorisations and re-balances (seepage), wall time.  For the seepage rungs a
second table splits the cost between steps in which interfaces broke and quiet
ones (from the run's ``step_costs.csv``).  The rungs:

- ``uniform``: the scene as shipped (one pressure in the cavity and its
  cracks; the calibrated 5 um wall film, the paper's Kw = 10 MPa, joints along
  the walls and cracks "permeated": at the cavity pressure from the start);
- ``uniform-water``: the same with water's Kw = 2.2 GPa and no film: what the
  calibration of the film and Kw does;
- ``viscous``: one pressure per wet facet (``solver.fidelity = "viscous"``),
  otherwise as shipped;
- ``seepage``: the joints of the fracturable zone fill in time from dry
  (``wall_joints = "seepage"``, 1 um hydraulic aperture), water, no film: no
  knob of the joints' fluid left;
- ``seepage-kw``: the same with the paper's fluid stiffness Kw = 10 MPa
  (Tables 1 and 3) in the cavity and the joints instead of water's;
- ``seepage-reduced``: ``seepage`` on the reduced solid (``solver.solid``):
  springs on every interface of the zone, the rock outside it continuous;
- ``seepage-step``: ``seepage`` with ``solver.break_landing = "step"``: no step
  shortened onto a break, the interfaces overstressed at a step's end break
  then (at most a step late);
- ``seepage-tolerance``: ``seepage`` with ``solver.break_landing = "tolerance"``:
  a step is shortened onto its first break only when it moved the cavity
  pressure by more than ``solver.break_tolerance`` (1 %) of it;
- ``seepage-wet``: ``seepage`` with the joints full at the cavity's starting
  30 MPa (``injection.joint_pressure``: the rock's pore pressure, the well
  balanced), not dry.

    make run CMD="python3 benchmarks/fidelity_ladder.py --rungs uniform uniform-water viscous"
    make run CMD="python3 benchmarks/fidelity_ladder.py --rungs seepage"   # about 15 min coarse
    make run CMD="python3 benchmarks/fidelity_ladder.py --rungs seepage \
        --resolution default --duration '0.1 s'"
    make run CMD="python3 benchmarks/fidelity_ladder.py --rungs seepage seepage-step \
        seepage-tolerance --resolution default --duration '1.5 s'"
"""

from __future__ import annotations

import argparse
import csv
import functools
import re
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.coupling.breakdown import detect_breakdown
from hfcdem.workflows.run import run_scene

ROOT = Path(__file__).resolve().parents[1]
RUNGS = (
    "uniform",
    "uniform-water",
    "viscous",
    "seepage",
    "seepage-kw",
    "seepage-reduced",
    "seepage-step",
    "seepage-tolerance",
    "seepage-wet",
)
SEEPAGE = tuple(rung for rung in RUNGS if rung.startswith("seepage"))
LANDING = {"seepage-step": "step", "seepage-tolerance": "tolerance"}


def scene_text(rung: str) -> str:
    """No. 2's scene file for ``rung``."""
    text = (ROOT / "meshes/scenes/perforation_no2.toml").read_text()
    if rung in ("uniform-water", *SEEPAGE) and rung != "seepage-kw":
        text = re.sub(r"(?m)^wall_film = .*\n", "", text)
        text = re.sub(r'(?m)^bulk_modulus = "[^"]*"', 'bulk_modulus = "2.2 GPa"', text)
    if rung == "seepage-kw":
        text = re.sub(r"(?m)^wall_film = .*\n", "", text)
    if rung in SEEPAGE:
        text = re.sub(r'(?m)^wall_joints = "[a-z]+"', 'wall_joints = "seepage"', text)
        # its steps go back to time_step after every break: it takes no pressure bound
        text = re.sub(r"(?m)^max_pressure_change = .*\n", "", text)
    if rung in LANDING:
        text = text.replace("[solver]\n", f'[solver]\nbreak_landing = "{LANDING[rung]}"\n', 1)
    if rung == "seepage-wet":
        text = re.sub(
            r'(?m)^(initial_pressure = "([^"]*)".*)$', r'\1\njoint_pressure = "\2"', text, count=1
        )
    if rung == "seepage-reduced":
        text = text.replace("[solver]\n", '[solver]\nsolid = "reduced"\n', 1)
    if rung == "viscous":
        text = re.sub(r'(?m)^fidelity = "[a-z]+"', 'fidelity = "viscous"', text)
    return text.replace('name = "perforation_no2"', f'name = "no2_{rung.replace("-", "_")}"')


def _pressure(summary: dict, key: str) -> str:
    v = summary.get(key)
    return f"{v:.2f}" if isinstance(v, int | float) else "-"


def shared_breakdown(path: Path, initial_pressure: float) -> str:
    """The breakdown of a run's ``history.csv`` by the uniform and viscous rungs' rule (MPa).

    Every rung takes the highest peak followed by a sustained fall of 5 % of
    the rise (:func:`~hfcdem.coupling.breakdown.detect_breakdown`; a pumped
    seepage run took the first peak followed by a 1 % fall until 2026-12-06).
    A pumped seepage run reads it on each step's highest pressure and only
    after its first break; this column reads every rung's step-end pressures
    from the run's start.
    """
    if not path.exists():
        return "-"
    with path.open() as f:
        rows = list(csv.DictReader(f))
    key = "cavity_pressure_Pa" if rows and "cavity_pressure_Pa" in rows[0] else "injection_pressure"
    times = [0.0] + [float(r.get("time_s") or r["time"]) for r in rows]
    pressures = [initial_pressure] + [float(r[key]) for r in rows]
    found = detect_breakdown(times, pressures)
    return "-" if found is None else f"{found.pressure / 1e6:.2f}"


def cost_split(path: Path) -> list[tuple[str, ...]]:
    """Steps with breaks and quiet ones: steps, solves, factorisations, seconds (rows)."""
    if not path.exists():
        return []
    with path.open() as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    out = []
    for name, breaks in (("breaks", True), ("quiet", False)):
        part = [r for r in rows if (r["broken"] > 0) == breaks]
        total = {k: sum(r[k] for r in part) for k in rows[0]} if part else {}
        out.append(
            (
                name,
                str(len(part)),
                f"{total.get('solid_solves', 0):.0f}",
                f"{total.get('factorisations', 0):.0f}",
                f"{total.get('low_rank_events', 0):.0f}",
                f"{total.get('factorise_s', 0):.0f}",
                f"{total.get('low_rank_s', 0):.0f}",
                f"{total.get('wall_s', 0):.0f}",
            )
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rungs", nargs="+", choices=RUNGS, default=list(RUNGS[:3]))
    ap.add_argument("--resolution", default="coarse")
    ap.add_argument("--progress", action="store_true", help="print the runs' progress")
    ap.add_argument(
        "--duration", help="pump for this long instead of the scene's 120 s (e.g. '2 s')"
    )
    ap.add_argument(
        "--linear-solver",
        choices=("auto", "direct", "iterative"),
        help="the solid's linear solver instead of the scene's (auto: direct up to 600k unknowns)",
    )
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    # flushed: a run of hours is followed through a redirected file
    say = functools.partial(print, flush=True) if args.progress and comm.rank == 0 else None
    rows, splits = [], []
    for rung in args.rungs:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = comm.bcast(tmp, root=0)
            path = Path(tmp) / f"{rung}.toml"
            if comm.rank == 0:
                path.write_text(scene_text(rung))
            comm.barrier()
            t0 = time.perf_counter()
            over = {"injection.duration": args.duration} if args.duration else {}
            if args.linear_solver:
                over["solver.linear_solver"] = args.linear_solver
            scene = load_scene(path, args.resolution, overrides=over)
            s = run_scene(scene, Path(tmp) / "out", force=True, say=say)
            wall = time.perf_counter() - t0
            splits += [(rung, *row) for row in cost_split(Path(tmp) / "out/step_costs.csv")]
            p0 = scene.physics.initial_pressure
            shared = shared_breakdown(Path(tmp) / "out/history.csv", p0)
            comm.barrier()
        rows.append(
            (
                rung,
                _pressure(s, "breakdown_pressure_MPa"),
                shared,
                _pressure(s, "peak_pressure_MPa") + (" (cut off)" if s.get("peak_cut_off") else ""),
                _pressure(s, "first_crack_pressure_MPa"),
                f"{s.get('tensile_failures', '-')} / {s.get('shear_failures', '-')}",
                str(s.get("steps", "-")),
                str(s.get("solid_solves", "-")),
                str(s.get("factorisations", "-")),
                str(s.get("low_rank_events", "-")),
                str(s.get("rebalances", "-")),
                f"{wall:.0f}",
                str(s.get("stopped") or ""),
            )
        )
        if comm.rank == 0:
            print(f"{rung}: done in {wall:.0f} s: " + " | ".join(rows[-1][1:]), flush=True)
    if comm.rank == 0:
        head = ("rung", "breakdown MPa", "breakdown, 5 % of the rise MPa", "peak MPa",
                "first break MPa", "tensile / shear",
                "steps", "solid solves", "factorisations", "low-rank events", "re-balances",
                "wall s",
                "stopped")  # fmt: skip
        _table(head, rows)
        if splits:
            print()
            head = ("rung", "steps", "count", "solid solves", "factorisations",
                    "low-rank events", "factorise s", "low-rank s", "wall s")  # fmt: skip
            _table(head, splits)


def _table(head: tuple[str, ...], rows: list) -> None:
    """Print ``rows`` as a Markdown table under ``head``."""
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
