"""How far a run's accepted states leave broken faces in a contact state they should leave.

After one round of contact switches a coupled step lets faces only close (the
chatter cut-off, :func:`hfcdem.coupling.events.switch_contacts`), so a state
accepted after later breaks can hold a broken face stuck while its shear is past
Coulomb, or shut while its springs hold less compression than the fluid on it
(or are in tension).  After every accepted step this prints how many such faces
there are and by how much:

    make run CMD="python3 benchmarks/contact_states.py meshes/scenes/lab_specimen_45deg.toml"

Columns: time, cavity pressure, broken faces closed (stick or slip), stuck ones,
stuck past Coulomb and the largest shear over its limit (a limit below 1 Pa is
taken as 1 Pa), closed ones that should open and the most their fluid pressure
exceeds their compression (MPa), and what contact hysteresis held shut at the
last check (``CDEMSolid.held_shut``).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

import numpy as np
from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.coupling.hydrofrac import HydraulicFracture, StepRecord
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import OPEN, STICK
from hfcdem.workflows.observers import StepObserver
from hfcdem.workflows.run import run_scene


class ContactStates(StepObserver):
    """One row per accepted step: faces left in a contact state they should leave."""

    def __init__(self) -> None:
        self.rows: list[tuple[float, ...]] = []

    def step(self, frac: HydraulicFracture, rec: StepRecord) -> None:
        """Measure the accepted state (collective)."""
        solid, comm = frac.solid, frac.solid.comm
        loads = frac.current_loads()
        snap = solid.snapshot(loads)
        broken = (
            (solid.state != FacetState.INTACT) & ~solid.is_crack & ~solid.states.released
        ) & solid.owned
        closed = broken & (solid.contact != OPEN)
        stuck = broken & (solid.contact == STICK)
        limit = solid.model.friction * np.maximum(-snap.normal_traction, 0.0)
        past = stuck & (snap.shear_traction > limit * (1.0 + 1e-6))
        over = np.where(past, snap.shear_traction / np.maximum(limit, 1.0), 0.0)
        p = np.broadcast_to(np.asarray(loads.crack_pressure, dtype=float), (solid.num_facets,))
        shut = closed & (snap.normal_traction > -p)
        excess = np.where(shut, snap.normal_traction + p, 0.0)
        counts = [int(closed.sum()), int(stuck.sum()), int(past.sum()), int(shut.sum())]
        counts = [comm.allreduce(c) for c in counts]
        most_over = comm.allreduce(float(over.max(initial=0.0)), op=MPI.MAX)
        most_excess = comm.allreduce(float(excess.max(initial=0.0)), op=MPI.MAX) / 1e6
        self.rows.append(
            (rec.time, rec.injection_pressure / 1e6, counts[0], counts[1], counts[2],
             most_over, counts[3], most_excess, solid.held_shut.count)
        )  # fmt: skip


def main() -> None:
    """Run the scene with the observer and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scene")
    parser.add_argument("--resolution", default="coarse")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    overrides = dict(item.split("=", 1) for item in args.set) or None
    scene = load_scene(args.scene, args.resolution, overrides=overrides)
    out = Path(comm.bcast(tempfile.mkdtemp(prefix="hfcdem_contact_") if comm.rank == 0 else None))
    states = ContactStates()
    summary = run_scene(scene, out / "run", comm, observers=[states], force=True)
    if comm.rank == 0:
        print(
            f"{scene.name} ({args.resolution}): {len(states.rows)} steps, peak "
            f"{summary['peak_pressure_MPa']:.2f} MPa, stopped: {summary['stopped'] or 'no'}"
        )
        print("   t (s)   p (MPa)  closed  stuck  past  most over   shut  excess (MPa)  held")
        for r in states.rows:
            print(
                f"{r[0]:8.4g} {r[1]:9.3f} {r[2]:7d} {r[3]:6d} {r[4]:5d} {r[5]:10.3g} "
                f"{r[6]:6d} {r[7]:13.3g} {r[8]:5d}"
            )
        shutil.rmtree(out)


if __name__ == "__main__":
    main()
