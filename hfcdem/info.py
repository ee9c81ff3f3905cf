"""Versions of the stack hfcdem runs on, for run records and bug reports."""

from __future__ import annotations

import platform

from mpi4py import MPI

import hfcdem
from hfcdem.solvers import mumps_orderings


def versions(comm: MPI.Comm = MPI.COMM_WORLD) -> dict[str, object]:
    """Return the versions of hfcdem, DOLFINx, PETSc, Gmsh, MPI and the rank count.

    ``mumps_orderings`` names the external orderings MUMPS was built with: the
    ordering changes the factor, so round-off differs between builds.
    """
    import basix
    import dolfinx
    import gmsh
    import numpy
    import ufl
    from petsc4py import PETSc

    petsc = ".".join(str(v) for v in PETSc.Sys.getVersion())
    # Open MPI ends the string with a NUL, which would land in summary.json
    mpi_library = MPI.Get_library_version().replace("\x00", "").splitlines()[0].strip()
    return {
        "hfcdem": hfcdem.__version__,
        "dolfinx": dolfinx.__version__,
        "basix": basix.__version__,
        "ufl": ufl.__version__,
        "petsc": petsc,
        "petsc_scalar": str(PETSc.ScalarType.__name__),
        "mumps_orderings": ", ".join(mumps_orderings()) or "none",
        "gmsh": gmsh.__version__,
        "numpy": numpy.__version__,
        "mpi": mpi_library,
        "mpi4py": __import__("mpi4py").__version__,
        "python": platform.python_version(),
        "ranks": comm.size,
    }


__all__ = [
    "versions",
]
