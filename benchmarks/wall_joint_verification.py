"""First crack of a pressurised borehole with dry and with wet wall joints, against closed forms.

Seed 001's set-up (60 mm borehole in a 1 m block, E 20 GPa, SH 20 MPa, T0 5 MPa)
at Sh 12 and 15 MPa, uniform pressure, the first break located in time.
Dry joints: Hubbert-Willis, 3 Sh - SH + T0.  Wet wall joints (the cavity
pressure also inside the joints that meet the wall): (3 Sh - SH + T0) / 2.
Printed: one row per wall element size h, with the slope dp/dSh.

    make run CMD="python3 benchmarks/wall_joint_verification.py"
"""

from __future__ import annotations

import time

import numpy as np
from mpi4py import MPI

from hfcdem.config.materials import ElasticMaterial, Fluid, Injection, InSituStress, InterfaceModel
from hfcdem.config.parts import MeshSizing, Plate, Wellbore
from hfcdem.config.plates import BoreholeSquare
from hfcdem.coupling.hydrofrac import FlowSettings, HydraulicFracture
from hfcdem.mesh.build import mesh_geometry
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid

A, SH, T0 = 0.03, 20e6, 5e6


def borehole_mesh(size: float) -> TaggedMesh:
    """The whole 1 m plate, four structured rings of the wall ``size`` (borehole_plate.toml)."""
    sizing = MeshSizing(
        size, 0.1, grading=0.25, wall_rings=4, circle_elements=6, size_integration="exact"
    )
    return mesh_geometry(BoreholeSquare(Plate(1.0, 1.0), Wellbore(2 * A, "z"), sizing))


def borehole_solid(tmesh: TaggedMesh, sh_min: float) -> CDEMSolid:
    """Seed 001's rock and stresses, springs in r < 6 a, the outer edges fixed."""
    return CDEMSolid(
        tmesh,
        ElasticMaterial(20e9, 0.25),
        InSituStress(sh_max=SH, sh_min=sh_min, sv=SH),
        InterfaceModel(
            alpha=100, tensile_strength=T0, cohesion=60e6, friction_angle=30, break_rule="all"
        ),
        zone=lambda x: np.hypot(x[0], x[1]) < 6 * A,
        fixed=tmesh.facet_groups("outer"),
    )


def first_break(sh_min: float, size: float, wet: bool) -> float:
    """Cavity pressure of the state located on the first break."""
    solid = borehole_solid(borehole_mesh(size), sh_min)
    hf = HydraulicFracture(
        solid,
        Fluid(),
        Injection.constant_rate(2e-6),
        FlowSettings(
            cavity=("wellbore_wall",),
            fidelity="uniform",
            dt_initial=0.5,
            dt_max=1.0,
            wet_wall_joints=wet,
        ),
    )
    hf.settle()
    while hf.first_break_time is None and hf.t < 120.0:
        hf.step()
    return max(r.injection_pressure for r in hf.history if r.time < hf.first_break_time)


def main() -> None:
    say = print if MPI.COMM_WORLD.rank == 0 else (lambda *a, **k: None)
    say("| joints | h | Sh 12 MPa | Sh 15 MPa | slope dp/dSh | wall |")
    say("|---|---|---|---|---|---|")
    for wet in (True, False):
        for div in (5, 10, 20, 40):
            t0 = time.perf_counter()
            p = [first_break(sh, A / div, wet) for sh in (12e6, 15e6)]
            exact = [(3 * sh - SH + T0) / (2 if wet else 1) for sh in (12e6, 15e6)]
            err = [
                f"{pi / 1e6:.3f} MPa ({pi / ei - 1:+.1%})" for pi, ei in zip(p, exact, strict=True)
            ]
            slope = (p[1] - p[0]) / 3e6
            wall = time.perf_counter() - t0
            say(
                f"| {'wet' if wet else 'dry'} | a/{div} | {err[0]} | {err[1]} | "
                f"{slope:.3f} (closed form {1.5 if wet else 3.0}) | {wall:.1f} s |"
            )


if __name__ == "__main__":
    main()
