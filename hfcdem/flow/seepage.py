"""Seepage through intact joints: transient cubic-law flow on a joint network.

Every interface facet of a set (the fracturable zone) is a joint of hydraulic
aperture ``a``: a cell of the :class:`~hfcdem.flow.network.Network` holding
``V = a A`` of fluid at zero pressure and ``V p / Kw`` more at pressure ``p``.
Cells exchange fluid through the network's pair transmissibilities (cubic law
``k = a^3 / 12 mu``, two-point ``t = k c / d`` per star entry, junctions
eliminated as zero-volume nodes).  Implicit Euler in time::

    (S / dt + T) p^{n+1} = S / dt p^n + sum_c t_c p_cavity

with ``S = diag(a A / Kw)`` and ``T`` the sparse transmissibility matrix (the
cavity connections on its diagonal).  The network is replicated on every rank
in a rank-independent order and solved there with a sparse LU (PETSc,
``COMM_SELF``), so every rank holds the same pressures whatever their number.
The solid does not enter yet: apertures are given, not computed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from petsc4py import PETSc

from hfcdem.config.materials import Fluid
from hfcdem.flow.network import Network, build_network
from hfcdem.solid.cdem import CDEMSolid

#: initial hydraulic aperture of the intact joints (perforation paper, Table 1), m
INITIAL_JOINT_APERTURE = 5e-6

#: PETSc options prefix of the seepage solve (the command line may override it)
PREFIX = "hfcdem_seepage_"


def joint_network(
    solid: CDEMSolid, cavity_vertices: np.ndarray, facets: Sequence[int] | np.ndarray | None = None
) -> Network:
    """Build the network of the joints ``facets`` of ``solid`` (collective).

    ``facets``: local interface indices (owned or ghost; default every
    interface of the zone); ``cavity_vertices``: global vertex ids of the cavity
    wall (e.g. :func:`hfcdem.coupling.condense.cavity_vertices`).  Only the
    owned ones are gathered, so each joint appears once.
    """
    n = solid.num_facets
    local = np.arange(n) if facets is None else np.unique(np.asarray(facets, dtype=np.int64))
    if local.size and (local[0] < 0 or local[-1] >= n):
        raise ValueError(f"facets must be local interface indices in [0, {n}), got out of range")
    owned = local[solid.owned[local]]
    net, _ = build_network(
        solid.comm,
        solid.vertex_ids[owned],  # unsorted: build_network orders ids and coordinates
        solid.areas[owned],
        solid.vertex_coords[owned],
        np.asarray(cavity_vertices, dtype=np.int64),
    )
    return net


def _finite(name: str, value: float, unit: str) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite ({unit}), got {value!r}")
    return v


class JointSeepage:
    """Transient seepage on a joint network with the cavity pressure as Dirichlet value.

    Parameters
    ----------
    net
        The joint network (the same on every rank).
    aperture
        Hydraulic aperture per facet (m), ``(n,)`` or one value for all.
    fluid
        Viscosity (Pa s) and bulk modulus ``Kw`` (Pa) of the fluid.
    pressure
        Initial facet pressure (Pa), ``(n,)`` or one value.

    """

    def __init__(
        self,
        net: Network,
        aperture: float | np.ndarray,
        fluid: Fluid,
        pressure: float | np.ndarray = 0.0,
    ) -> None:
        n = net.size
        ap = np.asarray(aperture, dtype=float)
        if ap.ndim not in (0, 1) or (ap.ndim == 1 and ap.shape != (n,)):
            raise ValueError(f"aperture must be one value or {n} values (m)")
        ap = np.broadcast_to(ap, (n,)).copy()
        if n and not (np.all(np.isfinite(ap)) and ap.min() > 0.0):
            raise ValueError(f"aperture must be finite and > 0 m on every facet, min {ap.min()!r}")
        self.net = net
        self.fluid = fluid
        self.aperture = ap
        self.storage = ap * net.area / fluid.bulk_modulus  # m^3/Pa per facet
        self.transmissibility = net.transmissibility(ap, fluid.conductivity)  # m^3/(Pa s)
        self.aperture.flags.writeable = False
        self.storage.flags.writeable = False
        self.transmissibility.flags.writeable = False
        self._pressure = self._facet_values("pressure", pressure)
        fa, fb, inner = net.pair_facets
        self._cavity = np.flatnonzero(~inner)  # connections to the cavity
        self._csr, self._diag = _csr(n, fa, fb, inner, self.transmissibility)
        self._solver: tuple[float, PETSc.KSP] | None = None
        self._injected = 0.0

    @property
    def pressure(self) -> np.ndarray:
        """Facet pressures (Pa) after the last step."""
        return self._pressure.copy()

    @property
    def cavity_facets(self) -> np.ndarray:
        """Facet of every cavity connection, in connection order."""
        return np.asarray(self.net.pair_facets[0][self._cavity])

    def stored(self) -> float:
        """Fluid stored by compression above zero pressure: ``sum V p / Kw`` (m^3)."""
        return float(self.storage @ self._pressure)

    def inflow(self, cavity_pressure: float | np.ndarray, pressure: np.ndarray) -> np.ndarray:
        """Rate into the network through every cavity connection (m^3/s) at facet ``pressure``."""
        pc = self._cavity_values(cavity_pressure)
        fa = self.cavity_facets
        return self.transmissibility[self._cavity] * (pc - pressure[fa])

    def flux_into_network(self) -> float:
        """Volume that entered from the cavity during the last step (m^3)."""
        return self._injected

    def step(self, dt: float, cavity_pressure: float | np.ndarray) -> np.ndarray:
        """Advance by ``dt`` (s) with the cavity at ``cavity_pressure`` (Pa); return pressures.

        ``cavity_pressure``: one value, or one per cavity connection
        (:attr:`cavity_facets` order).
        """
        dt = _finite("dt", dt, "s")
        if dt <= 0.0:
            raise ValueError(f"dt must be > 0 s, got {dt!r}")
        pc = self._cavity_values(cavity_pressure)
        if self.net.size == 0:
            self._injected = 0.0
            return np.zeros(0)
        rhs = self.storage / dt * self._pressure + self._cavity_load(pc)
        if self._solver is None or self._solver[0] != dt:
            self.destroy()
            self._solver = (dt, _lu(self._csr, self._diag, self.storage / dt))
        new = _solve(self._solver[1], rhs)
        self._injected = dt * float(self.inflow(pc, new).sum())
        self._pressure = new
        return new.copy()

    def steady(self, cavity_pressure: float | np.ndarray) -> np.ndarray:
        """Steady facet pressures for ``cavity_pressure`` (the state is not changed).

        Every facet must be joined to the cavity (else its pressure is undefined).
        """
        if self.net.size and np.any(self.net.components() != 0):
            raise ValueError("steady seepage needs every facet joined to the cavity")
        pc = self._cavity_values(cavity_pressure)
        if self.net.size == 0:
            return np.zeros(0)
        ksp = _lu(self._csr, self._diag, np.zeros(self.net.size))
        try:
            return _solve(ksp, self._cavity_load(pc))
        finally:
            ksp.getOperators()[0].destroy()
            ksp.destroy()

    def destroy(self) -> None:
        """Free the kept factorisation (a new time step size factorises again)."""
        if self._solver is not None:
            ksp = self._solver[1]
            ksp.getOperators()[0].destroy()
            ksp.destroy()
            self._solver = None

    def _cavity_load(self, pc: np.ndarray) -> np.ndarray:
        load = np.zeros(self.net.size)
        np.add.at(load, self.cavity_facets, self.transmissibility[self._cavity] * pc)
        return load

    def _cavity_values(self, value: float | np.ndarray) -> np.ndarray:
        count = len(self._cavity)
        arr = np.asarray(value, dtype=float)
        if arr.ndim not in (0, 1) or (arr.ndim == 1 and arr.shape != (count,)):
            raise ValueError(f"cavity_pressure must be one value or {count} values (Pa)")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"cavity_pressure must be finite (Pa), got {value!r}")
        return np.broadcast_to(arr, (count,)).copy()

    def _facet_values(self, name: str, value: float | np.ndarray) -> np.ndarray:
        arr = np.asarray(value, dtype=float)
        n = self.net.size
        if arr.ndim not in (0, 1) or (arr.ndim == 1 and arr.shape != (n,)):
            raise ValueError(f"{name} must be one value or {n} values (Pa)")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite (Pa)")
        return np.broadcast_to(arr, (n,)).copy()


def _csr(
    n: int, fa: np.ndarray, fb: np.ndarray, inner: np.ndarray, trans: np.ndarray
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    """Transmissibility matrix in CSR (duplicates summed), and its diagonal positions.

    Inner pairs couple their two facets; a cavity pair adds to its facet's
    diagonal only (its pressure is known).  Every diagonal is stored.
    """
    a, b, t = fa[inner], fb[inner], trans[inner]
    diag = np.arange(n, dtype=np.int64)
    rows = np.concatenate([a, b, a, b, fa[~inner], diag])
    cols = np.concatenate([a, b, b, a, fa[~inner], diag])
    vals = np.concatenate([t, t, -t, -t, trans[~inner], np.zeros(n)])
    key = rows * n + cols
    uniq, inverse = np.unique(key, return_inverse=True)
    data = np.bincount(inverse, weights=vals, minlength=len(uniq))
    indptr = np.concatenate([[0], np.cumsum(np.bincount(uniq // n, minlength=n))])
    return (indptr, uniq % n, data), np.searchsorted(uniq, diag * n + diag)


def _lu(
    csr: tuple[np.ndarray, np.ndarray, np.ndarray], diag: np.ndarray, shift: np.ndarray
) -> PETSc.KSP:
    """Factorise ``T + diag(shift)`` on this rank alone (sparse LU; the same on every rank)."""
    indptr, indices, data = csr
    values = data.copy()
    values[diag] += shift
    n = len(indptr) - 1
    itype = PETSc.IntType
    mat = PETSc.Mat().createAIJ(
        (n, n), csr=(indptr.astype(itype), indices.astype(itype), values), comm=PETSc.COMM_SELF
    )
    mat.assemble()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOptionsPrefix(PREFIX)
    ksp.setOperators(mat)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.setFromOptions()  # e.g. -hfcdem_seepage_pc_factor_mat_solver_type mumps
    ksp.setUp()
    return ksp


def _solve(ksp: PETSc.KSP, rhs: np.ndarray) -> np.ndarray:
    b = PETSc.Vec().createWithArray(rhs.copy(), comm=PETSc.COMM_SELF)
    x = b.duplicate()
    ksp.solve(b, x)
    if ksp.getConvergedReason() < 0:
        raise RuntimeError(f"seepage solve failed (KSP reason {ksp.getConvergedReason()})")
    out = x.getArray().copy()
    b.destroy()
    x.destroy()
    return out


__all__ = [
    "INITIAL_JOINT_APERTURE",
    "PREFIX",
    "JointSeepage",
    "joint_network",
]
