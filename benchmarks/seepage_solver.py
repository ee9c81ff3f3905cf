"""The joints' seepage around perforation No. 2: the cost of its sparse LU, by solver.

Builds No. 2's joints (the intact interfaces of its fracturable zone, dry) at
one resolution, holds the tunnel wall at 60 MPa of water and takes implicit
steps of saturation filling (:class:`hfcdem.flow.seepage.JointSeepage`), once
per LU solver named (PETSc's ``-hfcdem_seepage_pc_factor_mat_solver_type``).
Every Newton iteration of a step refactorises the joints' matrix on its kept
pattern, so the seconds per step are mostly factorisations.  Prints, per
solver: joints, steps, Newton iterations, seconds, and the largest gap of
the joints' pressures from the first solver's (the same answer to round-off).

    make run CMD="python3 benchmarks/seepage_solver.py --resolution default"
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.scene import load_scene
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.seepage import PREFIX, JointSeepage, joint_network
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.interfaces import FacetState
from hfcdem.workflows.run import build_solid, pressurised_groups

ROOT = Path(__file__).resolve().parents[1]
APERTURE = 1e-6  # m: the perforation paper's permeability coefficient with water
PRESSURE = 60e6  # Pa at the tunnel wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolution", default="coarse")
    ap.add_argument("--solvers", nargs="+", default=["petsc", "mumps"])
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--dt", type=float, default=0.05, help="step (s)")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    scene = load_scene(ROOT / "meshes/scenes/perforation_no2.toml", args.resolution)
    tmesh = create_scene_mesh(scene).tmesh
    solid = build_solid(scene, tmesh)
    cavity = pressurised_groups(tmesh.facet_names, scene.physics.wellbore)
    joints = np.flatnonzero((solid.state == FacetState.INTACT) & ~solid.is_crack)
    net = joint_network(solid, cavity_vertices(solid, cavity, None), joints)
    fluid = scene.physics.fluid
    rows, first = [], None
    for solver in args.solvers:
        PETSc.Options()[PREFIX + "pc_factor_mat_solver_type"] = solver
        seep = JointSeepage(net, APERTURE, fluid, filling="saturation", saturation=0.0)
        iterations = 0
        t0 = time.perf_counter()
        for _ in range(args.steps):
            seep.step(args.dt, PRESSURE)
            iterations += seep.newton_iterations
        seconds = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
        pressure = seep.pressure
        first = pressure if first is None else first
        gap = float(np.abs(pressure - first).max()) / PRESSURE
        rows.append((solver, net.size, args.steps, iterations, seconds, gap))
        seep.destroy()
    del PETSc.Options()[PREFIX + "pc_factor_mat_solver_type"]
    if comm.rank == 0:
        print(f"No. 2, {args.resolution}: {args.steps} steps of {args.dt} s, wall at 60 MPa")
        print("| solver | joints | steps | Newton iterations | s | s per iteration | gap |")
        print("|---|---|---|---|---|---|---|")
        for solver, n, steps, its, s, gap in rows:
            print(f"| {solver} | {n} | {steps} | {its} | {s:.2f} | {s / its:.3f} | {gap:.1e} |")


if __name__ == "__main__":
    main()
