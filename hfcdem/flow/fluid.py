"""The fracturing fluid, the pump schedule and Carter leak-off.

All quantities are SI.  In 2D (plane strain) volumes and rates are per metre of
thickness: a rate in m^3/s means m^3/s per metre.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


def _check_range(name: str, value: float, low: float, high: float, unit: str) -> None:
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(f"{name} must be in [{low:g}, {high:g}] {unit}, got {value!r}")


@dataclass(frozen=True)
class Fluid:
    """A Newtonian, slightly compressible fluid.

    ``residual_aperture`` (m) is added to the mechanical opening of every fracture
    facet, for storage and conductivity: it lets fluid enter closed fractures.
    ``gravity`` (m/s^2, a vector in the mesh axes) is applied only when given.
    """

    viscosity: float = 1e-3
    bulk_modulus: float = 2.2e9
    density: float = 1000.0
    residual_aperture: float = 0.0
    gravity: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        _check_range("viscosity", self.viscosity, 1e-6, 1e6, "Pa s")
        _check_range("bulk_modulus (Kw)", self.bulk_modulus, 1e3, 1e12, "Pa")
        _check_range("density", self.density, 1.0, 2e4, "kg/m^3")
        _check_range("residual_aperture", self.residual_aperture, 0.0, 1e-2, "m")
        if self.gravity is not None:
            g = tuple(float(c) for c in self.gravity)
            if len(g) not in (2, 3) or not all(math.isfinite(c) for c in g):
                raise ValueError(f"gravity must be a 2 or 3 component vector in m/s^2, got {g!r}")
            object.__setattr__(self, "gravity", g)

    def conductivity(self, aperture: np.ndarray) -> np.ndarray:
        """Cubic law: w^3 / (12 mu), per unit width (m^2/(Pa s) times m)."""
        return aperture**3 / (12.0 * self.viscosity)


def _schedule(name: str, points: Sequence[Sequence[float]], unit: str) -> tuple:
    pts = tuple((float(t), float(v)) for t, v in points)
    if not pts:
        raise ValueError(f"{name} needs at least one (time, value) point")
    times = [t for t, _ in pts]
    if any(not math.isfinite(t) or t < 0 for t in times) or times != sorted(times):
        raise ValueError(f"{name} times must be finite, >= 0 s and increasing, got {times}")
    if any(not math.isfinite(v) for _, v in pts):
        raise ValueError(f"{name} values must be finite {unit}")
    return pts


@dataclass(frozen=True)
class Injection:
    """Fluid delivered into the cavity: a rate schedule or a pressure schedule.

    Schedules are ``(time s, value)`` points, interpolated linearly and held
    constant after the last point.  Build one with :meth:`constant_rate`,
    :meth:`rate_schedule` or :meth:`pressure_schedule`.
    """

    kind: str
    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if self.kind not in ("rate", "pressure"):
            raise ValueError(f"injection kind must be 'rate' or 'pressure', got {self.kind!r}")
        unit = "m^3/s" if self.kind == "rate" else "Pa"
        object.__setattr__(self, "points", _schedule(f"injection {self.kind}", self.points, unit))
        if self.kind == "rate":
            for _, q in self.points:
                _check_range("injection rate", q, 0.0, 10.0, "m^3/s")

    @classmethod
    def constant_rate(cls, rate: float) -> Injection:
        """Inject ``rate`` m^3/s from t = 0."""
        return cls("rate", ((0.0, rate),))

    @classmethod
    def rate_schedule(cls, points: Sequence[Sequence[float]]) -> Injection:
        """Inject at a piecewise-linear rate given as ``(time s, rate m^3/s)`` points."""
        return cls("rate", tuple((float(t), float(q)) for t, q in points))

    @classmethod
    def pressure_schedule(cls, points: Sequence[Sequence[float]]) -> Injection:
        """Hold the cavity at a piecewise-linear pressure ``(time s, pressure Pa)``."""
        return cls("pressure", tuple((float(t), float(v)) for t, v in points))

    @property
    def rate_controlled(self) -> bool:
        """True for a rate schedule, False for a pressure schedule."""
        return self.kind == "rate"

    def value_at(self, t: float) -> float:
        """Rate (m^3/s) or pressure (Pa) at time ``t``."""
        times = [p[0] for p in self.points]
        values = [p[1] for p in self.points]
        return float(np.interp(t, times, values))

    def volume_between(self, t0: float, t1: float) -> float:
        """Volume injected in ``[t0, t1]`` (rate schedules; exact for the linear pieces)."""
        if not self.rate_controlled:
            raise ValueError("a pressure schedule has no prescribed volume")
        knots = [t for t, _ in self.points if t0 < t < t1]
        ts = np.array([t0, *knots, t1])
        qs = np.array([self.value_at(t) for t in ts])
        return float(np.sum(0.5 * (qs[1:] + qs[:-1]) * np.diff(ts)))


@dataclass(frozen=True)
class CarterLeakOff:
    """Carter leak-off: each wetted face loses ``C_L / sqrt(t - t0)`` (m/s).

    ``t0`` is the time fluid first reached the facet; both faces leak.
    """

    coefficient: float

    def __post_init__(self) -> None:
        _check_range("leak-off coefficient C_L", self.coefficient, 0.0, 1e-2, "m/s^0.5")

    def volume(
        self, area: np.ndarray, wetted_since: np.ndarray, t0: float, t1: float
    ) -> np.ndarray:
        """Volume lost through both faces of facets of ``area`` during ``[t0, t1]``."""
        start = np.maximum(t0 - wetted_since, 0.0)
        end = np.maximum(t1 - wetted_since, 0.0)
        return 4.0 * self.coefficient * area * (np.sqrt(end) - np.sqrt(start))


__all__ = [
    "CarterLeakOff",
    "Fluid",
    "Injection",
]
