"""How the fluid of a coupled run is modelled and stepped: :class:`FlowSettings`."""

from __future__ import annotations

import math
from dataclasses import dataclass

from hfcdem.flow.fluid import CarterLeakOff


@dataclass(frozen=True)
class FlowSettings:
    """How the fluid is modelled and stepped (SI units).

    ``cavity``: facet groups of the cavity walls (wellbore, tunnels); fluid is
    injected into the cavity.  ``injection_point``: a point (a mesh vertex is
    chosen) where fluid enters when there is no cavity, e.g. a KGD inlet.
    ``cavity_volume`` defaults to the volume the walls enclose in the mesh
    (symmetry planes through the origin); ``extra_volume`` adds storage outside
    the model (the rest of the wellbore and lines).
    ``breaks_need_fluid``: an interface may break only next to fluid (a wet
    fracture facet or the cavity), the pressurisation rule of seed 000.
    ``wet_wall_joints``: the intact interfaces that meet the cavity wall along an
    edge (a vertex in 2D) hold fluid at the cavity pressure, so they break on
    effective stress (p - sigma_n >= T0); the paper's CDEM lets fluid into its
    wall joints through their initial opening.
    ``permeate_joints`` (with ``wet_wall_joints``): the fluid also stands in the
    intact interfaces along every open crack at the cavity pressure, so it
    permeates the joints ahead of the fracture as it grows (the paper's
    saturation front through its joints, taken as instantaneous).
    ``debris``: ``"released"``: blocks cut loose at the cavity walls join the
    cavity's fluid (:func:`~hfcdem.coupling.events.release_debris`);
    ``"stay"``: they are held by contact and friction alone, and a run ends at
    the validity limit when one slides out (or, in viscous flow, when the fluid
    balance around one has no solution once its faces open).  Not the default: with a thin
    calibrated cavity (a wall film) the debris' expansion on release swings the
    pressure (the lab specimen: 5 to 9 MPa and back between steps).
    ``max_pressure_change``: a step that moves the cavity pressure by more than
    this fraction of it (at least of 1 MPa) is retried at half length, so a steep
    peak is sampled by the pressure rather than the clock (Rubin's peak: 6.23 MPa
    with steps of a second, 7.66 MPa bounded to 2 %, 7.72 MPa at 0.03125 s).
    ``supports``: exterior facet groups that support the rock without being
    part of the cavity (a cased wellbore's wall, which keeps its in-situ
    traction): a block cut loose against one is held in place by it.
    ``rigid_cavity``: the stored cavity volume ignores the wall motion (the
    pressure still loads the wall): the paper's CDEM stores fluid only in its
    joints, so its pressurisation rate is Kw Q / V alone.
    ``contact_hysteresis``: a broken facet that closed opens again only once
    the fluid pressure on it passes the one it closed at
    (:meth:`~hfcdem.solid.states.InterfaceStates.switch_contacts`); taken by
    the ``uniform`` fidelity only, not yet by ``viscous`` flow.
    """

    cavity: tuple[str, ...] = ()
    supports: tuple[str, ...] = ()
    debris: str = "stay"
    injection_point: tuple[float, ...] | None = None
    fidelity: str = "viscous"
    filling: str = "saturation"
    cavity_volume: float | None = None
    extra_volume: float = 0.0
    initial_pressure: float = 0.0
    breaks_need_fluid: bool = True
    wet_wall_joints: bool = False
    permeate_joints: bool = False
    rigid_cavity: bool = False
    leak_off: CarterLeakOff | None = None
    dt_initial: float = 0.01
    dt_min: float = 1e-9
    dt_max: float = math.inf
    dt_growth: float = 1.5
    max_state_iterations: int = 100
    break_tolerance: float = 0.01
    max_pressure_change: float = math.inf
    max_breaks_per_iteration: int | None = None
    newton_tolerance: float = 1e-10
    max_newton_iterations: int = 40
    contact_hysteresis: bool = True

    def __post_init__(self) -> None:
        if self.fidelity not in ("viscous", "uniform"):
            raise ValueError(f"fidelity must be 'viscous' or 'uniform', got {self.fidelity!r}")
        if self.debris not in ("stay", "released"):
            raise ValueError(f"debris must be 'stay' or 'released', got {self.debris!r}")
        if self.filling not in ("saturation", "no_lag"):
            raise ValueError(f"filling must be 'saturation' or 'no_lag', got {self.filling!r}")
        if not self.cavity and self.injection_point is None:
            raise ValueError(
                "give the cavity wall groups or an injection_point: fluid needs a way in"
            )
        both = sorted(set(self.supports) & set(self.cavity))
        if both:
            raise ValueError(f"supports must not be cavity walls too: {', '.join(both)}")
        for name in ("dt_initial", "dt_min", "dt_max"):
            value = getattr(self, name)
            if not value > 0.0:
                raise ValueError(f"{name} must be a positive time in s, got {value!r}")
        if self.dt_min > self.dt_initial:
            raise ValueError("dt_min must not exceed dt_initial")
        if not 1.0 <= self.dt_growth <= 10.0:
            raise ValueError(f"dt_growth must be in [1, 10], got {self.dt_growth!r}")
        if self.cavity_volume is not None and not self.cavity_volume >= 0.0:
            raise ValueError(f"cavity_volume must be >= 0 m^3, got {self.cavity_volume!r}")
        if not (math.isfinite(self.extra_volume) and self.extra_volume >= 0.0):
            raise ValueError(f"extra_volume must be >= 0 m^3, got {self.extra_volume!r}")
        if not math.isfinite(self.initial_pressure):
            raise ValueError("initial_pressure must be a finite pressure in Pa")
        if not 0.0 < self.newton_tolerance < 1e-3:
            raise ValueError("newton_tolerance must be in (0, 1e-3) (relative volume)")


__all__ = ["FlowSettings"]
