"""Linear elastic rock under in-situ stress and cavity pressure.

The rock starts in equilibrium under the in-situ stress ``sigma0``; excavating a
cavity and pressurising it perturbs that state.  The unknown is the perturbation
displacement ``u``; the total stress is ``sigma0 + C : eps(u)``.  On a cavity wall
with pressure ``p`` the perturbation carries the traction ``-(p I + sigma0) n``;
far boundaries are traction-free for the perturbation (the in-situ state holds
there) or on rollers.

Sign convention inside the code: *tension positive* (continuum mechanics).  The
in-situ stress is *given* compression positive, as engineers state it.

This module holds the continuous blocks; the breakable interfaces of the CDEM
solid build on it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from hfcdem.config.materials import ElasticMaterial, InSituStress
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solvers import DIRECT_LU, check_ksp, create_ksp


def strain(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Small strain tensor."""
    return ufl.sym(ufl.grad(u))


def stress(u: ufl.core.expr.Expr, material: ElasticMaterial) -> ufl.core.expr.Expr:
    """Hooke's law (plane strain in 2D)."""
    eps = strain(u)
    gdim = u.ufl_shape[0]
    return (
        material.lame_lambda * ufl.tr(eps) * ufl.Identity(gdim) + 2.0 * material.shear_modulus * eps
    )


@dataclass(frozen=True)
class ElasticSolution:
    """Perturbation displacement and total stress of an elastic solve."""

    displacement: dolfinx.fem.Function
    total_stress: ufl.core.expr.Expr
    dofs: int
    solver_iterations: int


def solve_cavity_pressure(
    tmesh: TaggedMesh,
    material: ElasticMaterial,
    in_situ: InSituStress,
    cavity_pressure: Mapping[str, float],
    rollers: Mapping[str, int] | None = None,
    degree: int = 2,
    petsc_options: Mapping[str, object] | None = None,
) -> ElasticSolution:
    """Solve for the perturbation caused by cavities at given pressures.

    ``cavity_pressure`` maps facet-group names to fluid pressure (Pa) on them;
    ``rollers`` maps facet-group names to the displacement component held at zero
    (symmetry planes).  Remaining boundaries keep the in-situ traction.
    """
    mesh = tmesh.mesh
    gdim = mesh.geometry.dim
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (gdim,)))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    sigma0 = ufl.as_matrix(in_situ.tensor(gdim).tolist())
    n = ufl.FacetNormal(mesh)

    a = ufl.inner(stress(u, material), strain(v)) * ufl.dx
    zero = dolfinx.fem.Constant(mesh, np.zeros(gdim, dtype=dolfinx.default_scalar_type))
    L = ufl.inner(zero, v) * ufl.dx
    for name, pressure in cavity_pressure.items():
        if not math.isfinite(pressure) or abs(pressure) > 1e10:
            raise ValueError(
                f"cavity pressure on {name!r} must be finite and below 10 GPa, got {pressure!r}"
            )
        p = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(pressure))
        traction = -(p * ufl.Identity(gdim) + sigma0) * n
        L += ufl.inner(traction, v) * tmesh.ds(name)

    bcs = []
    for name, component in (rollers or {}).items():
        if not 0 <= component < gdim:
            raise ValueError(
                f"roller component for {name!r} must be in [0, {gdim}), got {component}"
            )
        Vc = V.sub(component)
        dofs = dolfinx.fem.locate_dofs_topological(Vc, gdim - 1, tmesh.facets(name))
        bcs.append(dolfinx.fem.dirichletbc(dolfinx.default_scalar_type(0.0), dofs, Vc))

    uh = dolfinx.fem.Function(V, name="displacement")
    ksp = solve_linear(a, L, bcs, uh, prefix="hfcdem_elastic_", options=petsc_options)
    uh.name = "displacement"
    total = sigma0 + stress(uh, material)
    return ElasticSolution(
        displacement=uh,
        total_stress=total,
        dofs=V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
        solver_iterations=ksp.getIterationNumber(),
    )


DIRECT_SOLVER = DIRECT_LU


def solve_linear(
    a: ufl.Form,
    L: ufl.Form,
    bcs: list[dolfinx.fem.DirichletBC],
    uh: dolfinx.fem.Function,
    prefix: str,
    options: Mapping[str, object] | None = None,
) -> PETSc.KSP:
    """Assemble and solve ``a = L`` into ``uh`` with a KSP configured under ``prefix``.

    Defaults to MUMPS LU; ``options`` (without the prefix) and the command-line
    PETSc options database (with it) override.
    """
    a_form, L_form = dolfinx.fem.form(a), dolfinx.fem.form(L)
    A = dolfinx.fem.petsc.assemble_matrix(a_form, bcs=bcs)
    A.assemble()
    b = dolfinx.fem.petsc.assemble_vector(L_form)
    dolfinx.fem.petsc.apply_lifting(b, [a_form], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)

    ksp = create_ksp(A, prefix, {**DIRECT_SOLVER, **(options or {})})
    ksp.solve(b, uh.x.petsc_vec)
    uh.x.scatter_forward()
    A.destroy()
    b.destroy()
    check_ksp(ksp, f"linear solve {prefix!r}")
    if not np.all(np.isfinite(uh.x.array)):
        raise FloatingPointError(f"linear solve {prefix!r} produced non-finite values")
    return ksp


__all__ = [
    "ElasticSolution",
    "solve_cavity_pressure",
    "solve_linear",
    "strain",
    "stress",
]
