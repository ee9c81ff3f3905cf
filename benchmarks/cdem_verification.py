"""CDEM solid: accuracy against closed forms, and what it costs.

Prints the tables quoted in the closing notes of the CDEM-solid issue:

1. Sneddon (Table 1 parameters) on a +-50a plate: centre error vs element size,
   wall time (compare: OpenGeoSys 6.5.9 on this machine, 1.15 % in 11 s,
   0.58 % in 36 s, 0.30 % in 102 s; shared/peers/ogs-sneddon/RESULTS.md).
2. The Table 1 plate itself (1 m square, fixed edges), next to the paper's Fig. 6b.
3. Spring stiffness: springs on every facet of a box around the crack, alpha
   from 1 to 1e4: error and solve time (the accuracy-cost trade of the penalty).
4. Penny crack: centre error vs element size (3D, quarter model).
5. Hubbert-Willis: breakdown vs 3 Sh - SH + T for SH/Sh 1.0-1.7 and two sizes.

Run in the image:  make run CMD="python3 benchmarks/cdem_verification.py"
(``--quick`` for a smaller sweep).  Times are wall seconds on the current
machine, form compilation excluded (a warm-up solve runs first).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI

from hfcdem import analytic
from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.config.parts import Crack, MeshSizing, Plate, Wellbore
from hfcdem.config.plates import BoreholeSquare, CrackPlate
from hfcdem.io.sampling import evaluate_at_points
from hfcdem.mesh.build import mesh_geometry
from hfcdem.mesh.penny import PennyBlock, create_penny_block
from hfcdem.solid.cdem import CascadeStopped, CDEMSolid, Loads

MPa = 1e6
E, NU, P, A = 210e9, 0.25, 22e6, 0.1
comm = MPI.COMM_WORLD


def say(text: str) -> None:
    if comm.rank == 0:
        print(text, flush=True)


def no_zone(x):
    return np.zeros(x.shape[1], dtype=bool)


def opening(solid, point, axis):
    up, down = np.array([point], float), np.array([point], float)
    up[0, axis], down[0, axis] = 1e-10, -1e-10
    return (evaluate_at_points(solid.u, up) - evaluate_at_points(solid.u, down))[0, axis]


def crack_plate(half_width: float, size: float, size_far: float, grading: float = 0.25):
    """Half plate x >= 0 around a crack of half-length A (the verified sizing)."""
    sizing = MeshSizing(size, size_far, grading=grading, size_integration="exact")
    plate = Plate(2 * half_width, 2 * half_width)
    return CrackPlate(plate, Crack(2 * A), sizing, symmetry=("x",))


def borehole_plate(radius: float, size: float) -> BoreholeSquare:
    """The whole +-40 r plate with four structured rings of ``size`` at the wall."""
    sizing = MeshSizing(
        size, 8 * radius, grading=0.25, wall_rings=4, circle_elements=6, size_integration="exact"
    )
    return BoreholeSquare(Plate(80 * radius, 80 * radius), Wellbore(2 * radius, "z"), sizing)


def sneddon(plate, zone=no_zone, alpha=100.0, degree=2):
    t0 = time.perf_counter()
    tmesh = mesh_geometry(plate)
    solid = CDEMSolid(
        tmesh,
        ElasticMaterial(E, NU),
        InSituStress(0, 0),
        InterfaceModel(alpha=alpha),
        zone=zone,
        degree=degree,
        rollers={"symmetry_x": 0},
        fixed=tmesh.facet_groups("outer"),
    )
    solid.solve(Loads(crack_pressure=P))
    wall = time.perf_counter() - t0
    err = opening(solid, [1e-9, 0.0], 1) / analytic.sneddon_opening(0.0, A, P, E, NU) - 1
    cells = tmesh.mesh.topology.index_map(2).size_global
    dofs = solid.V.dofmap.index_map.size_global * 2
    return err, wall, solid.solve_seconds, cells, dofs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    fine = [A / 10, A / 20, A / 40] if args.quick else [A / 10, A / 20, A / 40, A / 80, A / 160]
    sneddon(crack_plate(50 * A, A / 10, 10 * A))  # compile the forms once

    say("\n## 1. Sneddon, +-50a plate, DG2 blocks, crack faces only (Nitsche glue elsewhere)")
    say("| h | cells | dofs | centre error | wall (mesh+solve) | solve |")
    say("|---|---|---|---|---|---|")
    for h in fine:
        err, wall, solve, cells, dofs = sneddon(crack_plate(50 * A, h, 10 * A))
        say(
            f"| a/{A / h:.0f} | {cells} | {dofs} | {100 * err:+.3f} % | {wall:.2f} s "
            f"| {solve:.2f} s |"
        )

    say("\n## 2. Table 1 plate (1 m square, 0.2 m crack, fixed edges), full width")
    say("| h | cells | centre error vs infinite-plate Sneddon | wall |")
    say("|---|---|---|---|")
    for h in fine[:3]:
        err, wall, _, cells, _ = sneddon(crack_plate(0.5, h, 0.05, grading=0.5))
        say(f"| a/{A / h:.0f} | {cells} | {100 * err:+.3f} % | {wall:.2f} s |")

    say("\n## 3. Spring stiffness: springs on all facets of |x| < 3a, |y| < 2a (h = a/20)")
    say("| alpha | centre error | solve |")
    say("|---|---|---|")
    box = lambda x: (np.abs(x[0]) < 3 * A) & (np.abs(x[1]) < 2 * A)  # noqa: E731
    for alpha in (1.0, 10.0, 100.0, 1e3, 1e4):
        err, _, solve, _, _ = sneddon(crack_plate(50 * A, A / 20, 10 * A), zone=box, alpha=alpha)
        say(f"| {alpha:g} | {100 * err:+.3f} % | {solve:.2f} s |")

    say("\n## 4. Penny crack (quarter model, +-10a block, DG2)")
    say("| h | cells | dofs | centre error | solve |")
    say("|---|---|---|---|---|")
    for h in [A / 4, A / 8] if args.quick else [A / 4, A / 8, A / 12]:
        tmesh = create_penny_block(PennyBlock(A, 10 * A, h, 2.5 * A))
        solid = CDEMSolid(
            tmesh,
            ElasticMaterial(E, NU),
            InSituStress(0, 0),
            InterfaceModel(),
            zone=no_zone,
            degree=2,
            rollers={"symmetry_x": 0, "symmetry_y": 1},
            fixed=tmesh.facet_groups("outer"),
        )
        solid.solve(Loads(crack_pressure=P))
        err = opening(solid, [1e-9, 1e-9, 0.0], 2) / analytic.penny_opening(0.0, A, P, E, NU) - 1
        cells = tmesh.mesh.topology.index_map(3).size_global
        dofs = solid.V.dofmap.index_map.size_global * 3
        say(
            f"| a/{A / h:.0f} | {cells} | {dofs} | {100 * err:+.2f} % "
            f"| {solid.solve_seconds:.1f} s |"
        )

    say("\n## 5. Hubbert-Willis breakdown, 2D borehole (r = 35 mm), T = 3 MPa, Sh = 10 MPa")
    say("| SH/Sh | h | breakdown | 3Sh - SH + T | error | first crack angle | mode | wall |")
    say("|---|---|---|---|---|---|---|---|")
    radius = 0.035
    for h in (radius / 10, radius / 20):
        for ratio in (1.0, 1.3, 1.5, 1.7):
            t0 = time.perf_counter()
            tmesh = mesh_geometry(borehole_plate(radius, h))
            solid = CDEMSolid(
                tmesh,
                ElasticMaterial(21.5e9, 0.25),
                InSituStress(ratio * 10 * MPa, 10 * MPa),
                InterfaceModel(tensile_strength=3 * MPa, cohesion=17 * MPa, friction_angle=40),
                zone=lambda x: np.hypot(x[0], x[1]) < 4 * radius,
                degree=2,
                fixed=tmesh.facet_groups("outer"),
            )
            note = ""
            try:
                pb = solid.ramp(
                    Loads(cavity={"wellbore_wall": 0.0}),
                    Loads(cavity={"wellbore_wall": 1.0}, in_situ_factor=0.0),
                    200 * MPa,
                )
            except CascadeStopped as stop:
                # the first break stands; the cascade after it did not settle
                pb, note = stop.first_break, f" ({stop.broken} broke, unsettled)"
            if pb is None:
                say(f"| {ratio} | a/{radius / h:.0f} | nothing broke up to 200 MPa |")
                continue
            ref = analytic.hubbert_willis_breakdown(ratio * 10 * MPa, 10 * MPa, 3 * MPa)
            ev = solid.events[0] if solid.events else None
            angle = (
                np.degrees(np.arctan2(abs(ev.midpoints[0, 1]), abs(ev.midpoints[0, 0])))
                if ev is not None and len(ev.midpoints)
                else float("nan")
            )
            angle = comm.allreduce(angle if np.isfinite(angle) else -1.0, op=MPI.MAX)
            mode = "tensile" if ev is not None and np.all(ev.modes == 1) else "shear/mixed"
            say(
                f"| {ratio} | a/{radius / h:.0f} | {pb / MPa:.2f} MPa | {ref / MPa:.2f} MPa | "
                f"{100 * (pb / ref - 1):+.1f} % | {angle:.1f} deg | {mode}{note} | "
                f"{time.perf_counter() - t0:.1f} s |"
            )


if __name__ == "__main__":
    main()
