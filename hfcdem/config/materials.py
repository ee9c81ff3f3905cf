"""Material and loading data: the rock, the in-situ stress, the interfaces, the fluid and the pump.

Frozen, validated dataclasses in SI units with no dependency on DOLFINx, so a
scene can be read and checked without a solver.  The physics that uses them
lives downstream: :mod:`hfcdem.solid.elastic` (Hooke's law under the in-situ
stress), :mod:`hfcdem.solid.interfaces` (failure checks), :mod:`hfcdem.flow`
(cubic law, mass balance).  Stresses are given compression positive, as
engineers state them; inside the solver tension is positive.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hfcdem.config.fingerprint import added_field, fingerprinted
from hfcdem.config.units import show_stress


def _check_positive(name: str, value: float, unit: str, upper: float = math.inf) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value) and 0.0 < value < upper):
        raise ValueError(f"{name} must be in (0, {upper:g}) {unit}, got {value!r}")


#: permeability coefficient of the joints (perforation paper, Tables 1 and 3), m^2/(Pa s)
PERMEABILITY_COEFFICIENT = 8.33e-11

#: hydraulic aperture whose cubic-law coefficient a^2 / (12 mu) is the paper's
#: permeability coefficient with water (1 mPa s): sqrt(12e-3 * 8.33e-11) = 1.0e-6 m.
#: The paper's 5 um initial opening is mechanical; the flow needs the hydraulic one.
JOINT_HYDRAULIC_APERTURE = 1.0e-6


@fingerprinted
@dataclass(frozen=True)
class JointAperture:
    """The intact joints' aperture ``value`` (m), held at cells of ``reference_size`` (m).

    ``reference_size=None``: the same aperture on every facet whatever the mesh
    (the equivalent medium then follows the mesh size); otherwise each facet's
    apertures follow its cells' size (:mod:`hfcdem.flow.apertures` says why).
    """

    value: float
    reference_size: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.value) and self.value > 0.0):
            raise ValueError(f"joint aperture must be > 0 m, got {self.value!r}")
        ref = self.reference_size
        if ref is not None and not (math.isfinite(ref) and ref > 0.0):
            raise ValueError(f"joint reference size must be a cell size > 0 m, got {ref!r}")

    def scaled(self, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Hydraulic and void apertures (m) of facets whose two cells measure ``h`` (m)."""
        h = np.asarray(h, dtype=float)
        if self.reference_size is None:
            same = np.full(h.shape, self.value)
            return same, same.copy()
        ratio = h / self.reference_size
        return self.value * np.cbrt(ratio), self.value * ratio


@fingerprinted
@dataclass(frozen=True)
class ElasticMaterial:
    """Isotropic linear elastic rock (Pa, -)."""

    youngs_modulus: float
    poisson_ratio: float

    def __post_init__(self) -> None:
        # 1e13 Pa is ten times diamond: anything above is a unit slip
        _check_positive("youngs_modulus", self.youngs_modulus, "Pa", 1e13)
        if not (math.isfinite(self.poisson_ratio) and -1.0 < self.poisson_ratio < 0.5):
            raise ValueError(f"poisson_ratio must be in (-1, 0.5), got {self.poisson_ratio!r}")

    @property
    def shear_modulus(self) -> float:
        """Lame's mu."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def lame_lambda(self) -> float:
        """Lame's lambda (plane strain and 3D)."""
        e, nu = self.youngs_modulus, self.poisson_ratio
        return e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


@fingerprinted
@dataclass(frozen=True)
class InSituStress:
    """Principal in-situ stresses, compression positive, in Pa.

    SH acts along ``azimuth_sh`` (degrees from the x axis, in the x-y plane), Sh
    perpendicular to it in that plane, Sv along z (3D only).
    """

    sh_max: float
    sh_min: float
    sv: float = 0.0
    azimuth_sh: float = 0.0

    def __post_init__(self) -> None:
        for key in ("sh_max", "sh_min", "sv", "azimuth_sh"):
            value = getattr(self, key)
            if not math.isfinite(value):
                raise ValueError(f"{key} must be finite, got {value!r}")
        for key in ("sh_max", "sh_min", "sv"):
            if abs(getattr(self, key)) > 1e10:
                raise ValueError(
                    f"{key} must be a stress below 10 GPa, got {show_stress(getattr(self, key))}"
                )
        if self.sh_max < self.sh_min:
            raise ValueError(
                f"sh_max ({show_stress(self.sh_max)}) must be >= "
                f"sh_min ({show_stress(self.sh_min)})"
            )

    def tensor(self, gdim: int) -> np.ndarray:
        """Return the in-situ stress as a tension-positive ``gdim x gdim`` tensor."""
        b = math.radians(self.azimuth_sh)
        c, s = math.cos(b), math.sin(b)
        rot = np.array([[c, -s], [s, c]])
        plane = rot @ np.diag([self.sh_max, self.sh_min]) @ rot.T
        if gdim == 2:
            return -plane
        full = np.zeros((3, 3))
        full[:2, :2] = plane
        full[2, 2] = self.sv
        return -full


BREAK_RULES = ("all", "most_overstressed", "cap")


@fingerprinted
@dataclass(frozen=True)
class InterfaceModel:
    """Spring stiffness, strength and post-failure behaviour of the interfaces.

    - ``alpha``: normal stiffness per area ``kn = alpha E / h`` (h: facet's mean
      cell diameter); ``shear_ratio`` gives ``ks = shear_ratio * kn`` (default
      ``1 / (2 (1 + nu))``, the ratio G/E, when None).
    - ``tensile_strength`` T0 and ``cohesion`` c0 in Pa, ``friction_angle`` phi in
      degrees: intact interfaces break in tension when ``t_n >= T0`` and in shear
      when ``|tau| >= c0 + sigma_n tan(phi)`` (sigma_n compression positive).
      A tensile check wins when both hold.
    - ``weibull_modulus`` m > 0 scatters T0 and c0 per facet with a Weibull law of
      the same mean, reproducibly for ``seed`` and independent of the rank count.
    - ``break_rule``: ``"all"`` breaks every overstressed interface at once,
      ``"most_overstressed"`` only the worst one and then re-solves,
      ``"cap"`` the ``max_breaks`` worst ones.
    - ``strength_length``: the length (m) over which the rock resists; when
      positive, the failure check reads the stress filtered over it
      (:mod:`hfcdem.solid.nonlocal_strength`), not the springs' own traction.
      0 (the default): strength at a point, as CDEM.
    - ``residual_stiffness``: open faces keep this fraction of kn and ks, so a
      block whose every face has broken stays attached (numerically) instead of
      making the system singular.  Its relative effect on an opening is about
      ``residual_stiffness * alpha * 4 a / h`` (crack length a): 1e-10 is negligible.
    """

    alpha: float = 100.0
    shear_ratio: float | None = None
    tensile_strength: float = math.inf
    cohesion: float = math.inf
    friction_angle: float = 30.0
    weibull_modulus: float | None = None
    seed: int = 0
    break_rule: str = "most_overstressed"
    max_breaks: int = 1
    residual_stiffness: float = 1e-10
    strength_length: float = added_field(0.0, since="2026-12-05")

    def __post_init__(self) -> None:
        if not (math.isfinite(self.strength_length) and 0.0 <= self.strength_length <= 10.0):
            raise ValueError(
                "strength_length must be a length in [0, 10] m (0: strength at a point), "
                f"got {self.strength_length!r}"
            )
        if not (math.isfinite(self.alpha) and 0.0 < self.alpha <= 1e12):
            raise ValueError(f"alpha must be in (0, 1e12] (kn = alpha E / h), got {self.alpha!r}")
        if self.shear_ratio is not None and not (
            math.isfinite(self.shear_ratio) and 0.0 <= self.shear_ratio <= 10.0
        ):
            raise ValueError(f"shear_ratio must be in [0, 10], got {self.shear_ratio!r}")
        for key in ("tensile_strength", "cohesion"):
            value = getattr(self, key)
            if math.isnan(value) or value < 0.0 or (math.isfinite(value) and value > 1e10):
                raise ValueError(f"{key} must be in [0, 10 GPa] (or inf), got {show_stress(value)}")
        if not (math.isfinite(self.friction_angle) and 0.0 <= self.friction_angle < 90.0):
            raise ValueError(f"friction_angle must be in [0, 90) deg, got {self.friction_angle!r}")
        if self.weibull_modulus is not None and not (
            math.isfinite(self.weibull_modulus) and 0.1 <= self.weibull_modulus <= 1e3
        ):
            raise ValueError(
                f"weibull_modulus must be in [0.1, 1000], got {self.weibull_modulus!r}"
            )
        if self.break_rule not in BREAK_RULES:
            raise ValueError(f"break_rule must be one of {BREAK_RULES}, got {self.break_rule!r}")
        if self.max_breaks < 1:
            raise ValueError(f"max_breaks must be >= 1, got {self.max_breaks!r}")
        if not (math.isfinite(self.residual_stiffness) and 0.0 <= self.residual_stiffness < 1.0):
            raise ValueError(
                "residual_stiffness must be in [0, 1) (fraction of kn), "
                f"got {self.residual_stiffness!r}"
            )

    @property
    def friction(self) -> float:
        """Friction coefficient tan(phi)."""
        return math.tan(math.radians(self.friction_angle))

    def shear_stiffness_ratio(self, poisson_ratio: float) -> float:
        """Return ks / kn."""
        if self.shear_ratio is not None:
            return self.shear_ratio
        return 1.0 / (2.0 * (1.0 + poisson_ratio))


def _check_range(name: str, value: float, low: float, high: float, unit: str) -> None:
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(f"{name} must be in [{low:g}, {high:g}] {unit}, got {value:g} {unit}")


@fingerprinted
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


@fingerprinted
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


__all__ = [
    "BREAK_RULES",
    "JOINT_HYDRAULIC_APERTURE",
    "PERMEABILITY_COEFFICIENT",
    "ElasticMaterial",
    "Fluid",
    "InSituStress",
    "Injection",
    "InterfaceModel",
    "JointAperture",
]
