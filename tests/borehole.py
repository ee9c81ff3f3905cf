"""Seed 001's borehole at a coarse wall size a/5, for the seepage coupling tests.

Not a test module: imported by test_penetration and test_pumping.  A 60 mm
borehole in a 1 m plate (E 20 GPa, nu 0.25, SH 20 MPa, Sh 12 MPa, T0 5 MPa,
alpha 100), springs in the fracturable zone r < 6 a, the outer edges fixed.
"""

import numpy as np
from mpi4py import MPI

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.config.parts import MeshSizing, Plate, Wellbore
from hfcdem.config.plates import BoreholeSquare
from hfcdem.mesh.build import mesh_geometry
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid

A, SH, SHMIN, T0 = 0.03, 20e6, 12e6, 5e6
WALL = ("wellbore_wall",)


def borehole_plate(comm: MPI.Comm = MPI.COMM_WORLD, wall_division: int = 5) -> TaggedMesh:
    """Mesh the plate with wall elements a/5 (a / ``wall_division``) on ``comm``."""
    sizing = MeshSizing(
        A / wall_division,
        0.1,
        grading=0.25,
        wall_rings=4,
        circle_elements=6,
        size_integration="exact",
    )
    return mesh_geometry(BoreholeSquare(Plate(1.0, 1.0), Wellbore(2 * A, "z"), sizing), comm=comm)


def borehole_solid(
    tmesh: TaggedMesh,
    mode: str = "full",
    walls: dict[str, float] | None = None,
    weibull_modulus: float | None = None,
) -> CDEMSolid:
    """Return the CDEM solid of the borehole (``mode`` full or reduced; drilled ``walls``).

    ``weibull_modulus``: strengths scattered per facet (seed 0, the same mean).
    """
    return CDEMSolid(
        tmesh,
        ElasticMaterial(20e9, 0.25),
        InSituStress(sh_max=SH, sh_min=SHMIN, sv=SH),
        InterfaceModel(
            alpha=100,
            tensile_strength=T0,
            cohesion=60e6,
            friction_angle=30,
            weibull_modulus=weibull_modulus,
            break_rule="all",
        ),
        zone=lambda x: np.hypot(x[0], x[1]) < 6 * A,
        fixed=tmesh.facet_groups("outer"),
        mode=mode,
        walls=walls,
    )
