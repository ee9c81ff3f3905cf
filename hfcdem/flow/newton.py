"""Solution of the small nonlinear system of group pressures.

PETSc SNES (Newton with line search, finite-difference Jacobian, options prefix
``hfcdem_flow_``) from the last state; when Newton fails from there, frozen-
conductivity (Picard) iterations bring it into its basin and SNES tries again.
The system is the same on every rank (the network is gathered), so every rank
solves it alone (``COMM_SELF``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from hfcdem.solvers import petsc_options

#: ``residual(p, frozen)``: group residuals at pressures ``p`` (m,) or (m, k); with
#: ``frozen`` pressures the conductivities and storage are taken from that state
Residual = Callable[[np.ndarray, np.ndarray | None], np.ndarray]

#: SNES defaults under the prefix (the command line may override any of them)
SNES_DEFAULTS: dict[str, object] = {"snes_type": "newtonls", "ksp_type": "preonly", "pc_type": "lu"}


@dataclass(frozen=True, eq=False)
class GroupSolution:
    """Group pressures reached, Newton iterations, and whether they solve the system."""

    pressure: np.ndarray
    iterations: int
    converged: bool
    failure: str = ""  # the last failed attempt, for the diagnostic of a stopped run


def solve_groups(
    residual: Residual,
    guess: np.ndarray,
    atol: float,
    max_iterations: int,
    prefix: str = "hfcdem_flow_",
) -> GroupSolution:
    """Solve ``residual(p) = 0`` with SNES, Picard-started if Newton fails first."""
    first = snes_solve(residual, guess, atol, max_iterations, prefix)
    if first.converged:
        return first
    start = picard(residual, guess, atol)
    second = snes_solve(residual, start, atol, max_iterations, prefix)
    return GroupSolution(
        second.pressure,
        first.iterations + second.iterations + 100,
        second.converged,
        second.failure or first.failure,
    )


def picard(residual: Residual, guess: np.ndarray, atol: float) -> np.ndarray:
    """Fixed-point iterations with frozen conductivity (robust, linearly convergent).

    Used to bring Newton into its basin when it fails from the last state.
    """
    p = guess.copy()
    m = len(p)
    scale = np.maximum(np.abs(p), 1e5)
    for _ in range(100):
        r0 = residual(np.zeros(m), p)
        cols = residual(np.diag(scale), p)
        jac = (cols - r0[:, None]) / scale[None, :]
        try:
            p_new = np.linalg.solve(jac, -r0)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(p_new)):
            break
        p = 0.5 * p + 0.5 * p_new
        if np.max(np.abs(residual(p, None))) < atol:
            break
    return p


def snes_solve(
    residual: Residual, guess: np.ndarray, atol: float, max_iterations: int, prefix: str
) -> GroupSolution:
    """Solve the group equations with SNES from ``guess``."""
    m = len(guess)
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    snes.setOptionsPrefix(prefix)
    x = PETSc.Vec().createSeq(m)
    f = PETSc.Vec().createSeq(m)
    jac = PETSc.Mat().createDense((m, m), comm=PETSc.COMM_SELF)
    jac.setUp()

    def function(_snes, xv, fv) -> None:
        fv.array[:] = residual(xv.array_r.copy(), None)

    def jacobian(_snes, xv, J, _P) -> None:
        p = xv.array_r.copy()
        step = 1e-7 * np.maximum(np.abs(p), 1e3)
        batch = p[:, None] + np.diag(step)
        r0 = residual(p, None)
        rb = residual(batch, None)
        jac = (rb - r0[:, None]) / step[None, :]
        # a group with no storage and no flow (the zero-volume cavity of a point injection
        # at dt = 0) is a zero row and column: keep its pressure, solve the others
        idle = ~jac.any(axis=0) & ~jac.any(axis=1)
        jac[idle, idle] = 1.0
        J.getDenseArray()[:] = jac
        J.assemble()

    snes.setFunction(function, f)
    snes.setJacobian(jacobian, jac)
    snes.setTolerances(rtol=1e-14, atol=atol, stol=1e-14, max_it=max_iterations)
    with petsc_options(prefix, SNES_DEFAULTS):
        snes.setFromOptions()
    x.array[:] = guess
    try:
        with np.errstate(all="ignore"):
            snes.solve(None, x)
        ok = snes.getConvergedReason() > 0
    except PETSc.Error:  # a singular Jacobian: cut the step
        ok = False
    p = x.array_r.copy()
    its = snes.getIterationNumber()
    if not ok and np.all(np.isfinite(p)):
        # stagnation just above the tolerance (finite-difference Jacobian near a
        # closing facet) still leaves a usable state: content is conserved exactly
        ok = float(np.max(np.abs(residual(p, None)))) <= 1e4 * atol
    ok = ok and bool(np.all(np.isfinite(p)))
    failure = ""
    if not ok:
        r = residual(p, None) if np.all(np.isfinite(p)) else p
        failure = (
            f"SNES reason {snes.getConvergedReason()} after {its} iterations, "
            f"|R| {np.max(np.abs(r)):.3g} m^3 vs tolerance {atol:.3g}, "
            f"worst group {int(np.argmax(np.abs(r)))} of {m}"
        )
    for obj in (snes, x, f, jac):
        obj.destroy()
    return GroupSolution(p, its, ok, failure)


__all__ = ["SNES_DEFAULTS", "GroupSolution", "Residual", "picard", "snes_solve", "solve_groups"]
