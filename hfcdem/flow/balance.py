"""Mass balance of the pressure groups on the fracture network (plain NumPy).

Fluid content is volume at the reference density, ``M = V (1 + p / Kw)``.  Each
wet group ``g`` (0: the cavity with every facet joined to it in one group under
uniform fidelity) satisfies, over one implicit Euler step ``dt``::

    M_g(p) - M_g^n + dt (outflows - inflows) + leaked - injected = 0

with the void volumes linear in the group pressures (:class:`VoidVolumes`, the
condensed solid) and fluxes by the cubic law on the
:class:`~hfcdem.flow.network.Network`.  A dry facet (group -1) is at zero
pressure with saturation ``S = M / V``; its neighbours feed it through the
relative permeability ``S^2 (3 - 2S)``.  Pressures may be ``(m,)`` or a batch
``(m, k)`` (columns of a finite-difference Jacobian).

With ``lag`` (uniform rung, saturation filling), water carries no tension: a
group's unknown ``q`` below zero is a group whose void has grown past its fluid
(fluid lag, as cracks that open faster than the pump fills them).  It then holds
``V (1 + q / Kw)`` at zero pressure, saturation ``1 + q / Kw``, and the faces
and fluxes see ``max(q, 0)`` (seed eqs. (18)-(19), the joints' saturation
filling, applied to the groups).  Without it a group may hold suction: the
zero-lag viscous solutions (KGD) that the viscous rung is verified against
carry it near the tip.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hfcdem.config.materials import Fluid
from hfcdem.flow.network import Network

#: a floor on storage and aperture keeps a closed, dry facet's equations regular (m)
APERTURE_FLOOR = 1e-9

#: round-off of a residual relative to the void volumes it sums (64 machine epsilons)
ROUNDOFF = 64.0 * float(np.finfo(float).eps)


def relative_permeability(saturation: np.ndarray) -> np.ndarray:
    """Seed eq. (14): ks = S^2 (3 - 2S), S clipped to [0, 1]."""
    s = np.clip(saturation, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


def col(values: np.ndarray, like: np.ndarray) -> np.ndarray:
    """Broadcast a per-item array against a (m,) or (m, k) pressure array."""
    return values.reshape(values.shape + (1,) * (like.ndim - 1))


def gravity_drive(net: Network, fluid: Fluid, cavity_point: np.ndarray) -> np.ndarray:
    """Hydrostatic head of every connection, from its first to its second end (Pa)."""
    fa, fb, inner = net.pair_facets
    g = fluid.gravity
    if g is None:
        return np.zeros(len(fa))
    gv = np.zeros(3)
    gv[: len(g)] = g
    xa = net.centroid[fa]
    xb = np.where(inner[:, None], net.centroid[fb], cavity_point[None, :])
    return fluid.density * (xb - xa) @ gv


@dataclass(frozen=True, eq=False)
class VoidVolumes:
    """Void volumes linear in the group pressures: ``v0 + h p`` per facet, ``vc0 + hc p``."""

    v0: np.ndarray  # (n,) void volume of each facet at zero pressure
    h: np.ndarray  # (n, m) d void / d group pressure
    vc0: float  # cavity volume at zero pressure
    hc: np.ndarray  # (m,) d cavity volume / d group pressure

    def at(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Facet and cavity void volumes at group pressures ``p``."""
        return self.v0.reshape(-1, *([1] * (p.ndim - 1))) + self.h @ p, self.vc0 + self.hc @ p

    def filling_pressure(self, wet: np.ndarray, held: float) -> float | None:
        """Uniform pressure at which the ``wet`` facets and the cavity hold ``held`` (m^3).

        Compressibility is ignored (a starting guess); None when they do not deform.
        """
        stiff = float(self.h[wet].sum() + self.hc.sum())
        volume = float(self.v0[wet].sum()) + self.vc0
        return (held - volume) / stiff if stiff > 0 else None


@dataclass(frozen=True, eq=False)
class StepBalance:
    """Fluid state after an accepted step (see :meth:`GroupBalance.advance`)."""

    content: np.ndarray  # fluid content per facet
    cavity_content: float
    pressure: np.ndarray  # per facet, dry facets 0
    injected: float  # volume injected over the step
    mismatch: float  # sum of |residual| (m^3): solver error, corrected by the next step
    facet_volumes: np.ndarray  # void volume per facet


@dataclass(frozen=True, eq=False)
class GroupBalance:
    """The finite-volume balance of the pressure groups of one network and solid state."""

    net: Network
    fluid: Fluid
    volumes: VoidVolumes
    group: np.ndarray  # (n,) pressure group per facet: 0 the cavity, -1 dry, else 1..
    drive: np.ndarray  # (P,) gravity head per connection (:func:`gravity_drive`)
    cavity_volume: float  # the cavity's storage (m^3)
    rate_controlled: bool  # injection by rate (else the cavity pressure is prescribed)
    lag: bool = False  # groups may lag behind their opening (no suction, see the module)

    def __post_init__(self) -> None:
        if len(self.group) != self.net.size:
            raise ValueError("group needs one entry per network facet")

    @property
    def size(self) -> int:
        """Number of pressure groups (the cavity's group 0 always counts)."""
        group = self.group
        return 1 + (int(group.max()) if group.size and group.max() > 0 else 0)

    def load(self, q: np.ndarray) -> np.ndarray:
        """Pressure on the faces for group unknowns ``q`` (with ``lag``: no tension)."""
        return np.maximum(q, 0.0) if self.lag else q

    def facet_pressure(self, p: np.ndarray) -> np.ndarray:
        """Pressure of every facet (dry facets 0) for group pressures (m,) or (m, k)."""
        pf = np.zeros((self.net.size, *p.shape[1:]))
        wet = self.group >= 0
        pf[wet] = p[self.group[wet]]
        return pf

    def fluxes(
        self,
        p: np.ndarray,
        vf: np.ndarray,
        content: np.ndarray,
        frozen: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Flux of every connection (from its first to its second end), and saturation.

        With ``frozen`` group pressures, apertures and saturations are taken from
        that state (a Picard linearisation): the flux is then linear in ``p``.
        """
        net, fl = self.net, self.fluid
        if frozen is not None:
            vf_k, _ = self.volumes.at(self.load(frozen))
            vf = col(vf_k, p) * np.ones((1,) * p.ndim)
        area = net.area.reshape(-1, *([1] * (p.ndim - 1)))
        aperture = np.maximum(vf / area - fl.residual_aperture, 0.0) + max(
            fl.residual_aperture, APERTURE_FLOOR
        )
        trans = net.transmissibility(aperture, fl.conductivity)
        q = self.facet_pressure(p)
        pf = self.load(q)
        pc = self.load(p[0])
        sat = np.clip(1.0 + q / fl.bulk_modulus, 0.0, 1.0) if self.lag else np.ones_like(vf)
        dry = self.group < 0
        sat[dry] = np.clip(
            content[dry].reshape(-1, *([1] * (p.ndim - 1))) / np.maximum(vf[dry], 1e-300),
            0.0,
            1.0,
        )
        fa, fb, inner = net.pair_facets
        pa = pf[fa]
        pb = np.where(col(inner, p), pf[fb], pc)
        sa = sat[fa]
        sb = np.where(col(inner, p), sat[fb], 1.0)
        kr = relative_permeability(0.5 * (sa + sb))
        drive = pa - pb + col(self.drive, p)
        return trans * kr * drive, sat

    def residual(
        self,
        p: np.ndarray,
        dt: float,
        source: float,
        leak: np.ndarray,
        content: np.ndarray,
        cavity_content: float,
        control: bool = True,
        frozen: np.ndarray | None = None,
    ) -> np.ndarray:
        """Group residuals (volume, m^3) for group pressures (m,) or (m, k).

        ``source``: the volume injected over the step, or the prescribed cavity
        pressure (``control`` with a pressure schedule).  ``frozen``:
        conductivities and compressed volumes from that state, which makes the
        residual linear in ``p`` (a Picard step).
        """
        kw = self.fluid.bulk_modulus
        vf, vc = self.volumes.at(self.load(p))
        flux, _ = self.fluxes(p, vf, content, frozen)
        pf = self.facet_pressure(p)
        r = np.zeros(p.shape)
        wet = self.group >= 0
        area = self.net.area.reshape(-1, *([1] * (p.ndim - 1)))
        floor = area * APERTURE_FLOOR
        if frozen is None:
            stored = vf + np.maximum(vf, floor) * pf / kw
            cav_stored = vc + np.maximum(vc, 0.0) * p[0] / kw
        else:
            vf_k, vc_k = self.volumes.at(self.load(frozen))
            floor_k = np.maximum(vf_k, self.net.area * APERTURE_FLOOR)
            stored = vf + col(floor_k, p) * pf / kw
            cav_stored = vc + max(float(vc_k), 0.0) * p[0] / kw
        np.add.at(r, self.group[wet], stored[wet] - content[wet].reshape(-1, *([1] * (p.ndim - 1))))
        r[0] += cav_stored - cavity_content
        fa, fb, inner = self.net.pair_facets
        ga = self.group[fa]
        gb = np.where(inner, self.group[fb], 0)
        ok = ga >= 0
        np.add.at(r, ga[ok], dt * flux[ok])
        ok = gb >= 0
        np.add.at(r, gb[ok], -dt * flux[ok])
        np.add.at(r, self.group[wet], col(leak[wet], p))
        if self.rate_controlled or not control:
            r[0] -= source
        else:
            scale = max(self.cavity_volume / kw + abs(self.volumes.hc[0]), 1e-30)
            r[0] = (p[0] - source) * scale
        return r

    def tolerance(
        self,
        content: np.ndarray,
        cavity_content: float,
        source: float,
        relative: float,
        p: np.ndarray | None = None,
    ) -> float:
        """Absolute residual tolerance: ``relative`` times the fluid held (m^3).

        With group pressures ``p``, at least the round-off of the residual's sum
        of void volumes there: where open faces of detached blocks hold voids far
        above the fluid (up to 1e10 of it seen), the fluid held is below what the
        residual can resolve.  The books stay exact (:meth:`advance`).
        """
        scale = max(
            cavity_content + float(content.sum()) + abs(source if self.rate_controlled else 0.0),
            float(self.net.area.sum()) * APERTURE_FLOOR,
            1e-30,
        )
        floor = 0.0
        if p is not None:
            vf, vc = self.volumes.at(self.load(p))
            voids = float(np.abs(vf[self.group >= 0]).sum()) + abs(float(vc))
            floor = ROUNDOFF * voids
        return max(relative * scale, floor)

    def dry_gain(self, p: np.ndarray, vf: np.ndarray, content: np.ndarray, dt: float) -> np.ndarray:
        """Volume each facet receives over the step from its connections (dry ones keep it)."""
        net = self.net
        flux, _ = self.fluxes(p, vf, content)
        fa, fb, inner = net.pair_facets
        gain = np.zeros(net.size)
        np.add.at(gain, fa, -dt * flux)
        np.add.at(gain, fb[inner], dt * flux[inner])
        return gain

    def wet_changes(
        self, p: np.ndarray, dt: float, content: np.ndarray, may_drain: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Facets that drain (wet, below zero pressure) and that fill (dry, full by the end).

        ``may_drain``: facets wet before this step (one that filled during it may
        hold suction until it ends).  Dry facets that fill during the step join
        the wet set at once, so the front is not limited to one facet per step.
        """
        drained = (self.group > 0) & (self.facet_pressure(p) < 0.0) & may_drain
        vf, _ = self.volumes.at(self.load(p))
        gain = self.dry_gain(p, vf, content, dt)
        full = (self.group < 0) & (gain > 0.0) & (content + gain >= vf)
        return drained, full

    def advance(
        self,
        p: np.ndarray,
        dt: float,
        source: float,
        leak: np.ndarray,
        content: np.ndarray,
        cavity_content: float,
    ) -> StepBalance:
        """Fluid content after a step solved to ``p``: exact finite-volume bookkeeping.

        Each group's content changes by what flowed in, was injected and leaked;
        the solver residual (content against the compressed void volume) is
        reported as the mismatch and corrected by the next step.
        """
        kw = self.fluid.bulk_modulus
        vf, vc = self.volumes.at(self.load(p))
        pf = self.facet_pressure(p)
        wet = self.group >= 0
        gain = self.dry_gain(p, vf, content, dt)
        floor = self.net.area * APERTURE_FLOOR
        stored = vf + np.maximum(vf, floor) * pf / kw
        cav_stored = float(vc) + max(float(vc), 0.0) * float(p[0]) / kw
        injected = source if self.rate_controlled else 0.0
        if not self.rate_controlled:
            # the balance of the cavity group gives the volume pumped in this step
            balance = self.residual(p, dt, 0.0, leak, content, cavity_content, control=False)
            injected = float(balance[0])
        resid = self.residual(p, dt, injected, leak, content, cavity_content, control=False)
        m = self.size
        exact = np.zeros(m)
        np.add.at(exact, self.group[wet], stored[wet])
        exact[0] += cav_stored
        share = np.zeros(m)
        np.add.at(share, self.group[wet], stored[wet])
        share[0] += cav_stored
        target = exact - resid
        factor = np.where(share != 0.0, target / np.where(share != 0.0, share, 1.0), 1.0)
        return StepBalance(
            content=np.where(wet, stored * factor[np.maximum(self.group, 0)], content + gain),
            cavity_content=cav_stored * float(factor[0]),
            pressure=np.where(wet, self.load(pf), 0.0),
            injected=injected,
            mismatch=float(np.sum(np.abs(resid))),
            facet_volumes=vf,
        )


__all__ = [
    "APERTURE_FLOOR",
    "ROUNDOFF",
    "GroupBalance",
    "StepBalance",
    "VoidVolumes",
    "col",
    "gravity_drive",
    "relative_permeability",
]
