"""Closed-form references that hfcdem is verified against.

Conventions: SI units; stresses *compression positive* (rock-mechanics sign), as
in the references; ``theta`` is measured from the direction of SH.  The plane
strain modulus is ``E' = E / (1 - nu^2)``.  Sources: docs/design.md "Verification
references" and the seed papers (Sneddon, Kirsch, Hubbert-Willis, KGD).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]


def plane_strain_modulus(youngs_modulus: float, poisson_ratio: float) -> float:
    """Return E' = E / (1 - nu^2)."""
    return youngs_modulus / (1.0 - poisson_ratio**2)


# ---------------------------------------------------------------------------
# Pressurised cracks
# ---------------------------------------------------------------------------


def sneddon_opening(
    x: ArrayLike, half_length: float, pressure: float, youngs_modulus: float, poisson_ratio: float
) -> FloatArray:
    """Return the opening w(x) = (4 p / E') sqrt(a^2 - x^2) of a 2D plane-strain crack.

    With a background stress sigma0 normal to the crack (compression positive) the
    opening is that of the net pressure ``p - sigma0`` (Griffith, seed 000 eq. 17).
    """
    x = np.asarray(x, dtype=float)
    e_prime = plane_strain_modulus(youngs_modulus, poisson_ratio)
    return 4.0 * pressure / e_prime * np.sqrt(np.clip(half_length**2 - x**2, 0.0, None))


def sneddon_area(
    half_length: float, pressure: float, youngs_modulus: float, poisson_ratio: float
) -> float:
    """Cross-section area of the opened 2D crack: 2 pi p a^2 / E'."""
    return (
        2.0
        * np.pi
        * pressure
        * half_length**2
        / plane_strain_modulus(youngs_modulus, poisson_ratio)
    )


def penny_opening(
    r: ArrayLike, radius: float, pressure: float, youngs_modulus: float, poisson_ratio: float
) -> FloatArray:
    """Return the opening of a penny-shaped crack, 8 (1 - nu^2) p a / (pi E) sqrt(1 - r^2/a^2)."""
    r = np.asarray(r, dtype=float)
    w0 = 8.0 * (1.0 - poisson_ratio**2) * pressure * radius / (np.pi * youngs_modulus)
    return w0 * np.sqrt(np.clip(1.0 - (r / radius) ** 2, 0.0, None))


def penny_volume(
    radius: float, pressure: float, youngs_modulus: float, poisson_ratio: float
) -> float:
    """Volume of the opened penny-shaped crack: 16 p a^3 / (3 E')."""
    return 16.0 * pressure * radius**3 / (3.0 * plane_strain_modulus(youngs_modulus, poisson_ratio))


# ---------------------------------------------------------------------------
# Borehole in an infinite plate (Kirsch) and breakdown criteria
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class KirschStress:
    """Polar stress components around a borehole, compression positive."""

    rr: FloatArray
    tt: FloatArray
    rt: FloatArray


def kirsch_stress(
    r: ArrayLike,
    theta: ArrayLike,
    radius: float,
    sh_max: float,
    sh_min: float,
    wellbore_pressure: float,
) -> KirschStress:
    """Kirsch field around a pressurised hole of ``radius`` under far-field (SH, Sh).

    ``theta`` is measured from the SH direction, stresses are compression positive.
    """
    r = np.asarray(r, dtype=float)
    theta = np.asarray(theta, dtype=float)
    s = 0.5 * (sh_max + sh_min)
    d = 0.5 * (sh_max - sh_min)
    q2 = (radius / r) ** 2
    q4 = q2**2
    c2 = np.cos(2.0 * theta)
    s2 = np.sin(2.0 * theta)
    rr = s * (1.0 - q2) + d * (1.0 - 4.0 * q2 + 3.0 * q4) * c2 + wellbore_pressure * q2
    tt = s * (1.0 + q2) - d * (1.0 + 3.0 * q4) * c2 - wellbore_pressure * q2
    rt = -d * (1.0 + 2.0 * q2 - 3.0 * q4) * s2
    return KirschStress(rr=rr, tt=tt, rt=rt)


def kirsch_wall_hoop_stress(
    theta: ArrayLike, sh_max: float, sh_min: float, wellbore_pressure: float
) -> FloatArray:
    """Hoop stress at the wall: SH + Sh - 2 (SH - Sh) cos 2theta - Pw (compression positive)."""
    theta = np.asarray(theta, dtype=float)
    return sh_max + sh_min - 2.0 * (sh_max - sh_min) * np.cos(2.0 * theta) - wellbore_pressure


def hole_wall_principal_stresses(
    stress: ArrayLike,
    axis: ArrayLike,
    poisson_ratio: float,
    pressure: float = 0.0,
    points: int = 720,
) -> tuple[FloatArray, FloatArray]:
    """Principal stresses on the wall of a circular hole of any direction.

    ``stress``: the far-field 3 x 3 tensor, compression positive; ``axis``: the
    hole's direction; ``pressure``: the fluid pressure on its wall.  Generalised
    plane strain about the axis (Hiramatsu and Oka 1962; Fairhurst 1968): at the
    wall angle theta from the first cross-axis direction,

        s_tt = sx + sy - 2 (sx - sy) cos 2t - 4 txy sin 2t - p,
        s_zz = sz - 2 nu ((sx - sy) cos 2t + 2 txy sin 2t),
        t_tz = 2 (tyz cos t - txz sin t),  s_rr = p,

    with x, y across the axis and z along it.  Returns the unit vectors from the
    axis to the wall points, (points, 3), and the principal stresses there,
    (points, 3), ascending.
    """
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    seed = np.eye(3)[int(np.argmin(np.abs(a)))]
    e1 = np.cross(a, seed)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    rot = np.array([e1, e2, a])
    local = rot @ np.asarray(stress, dtype=float) @ rot.T
    sx, sy, sz = local[0, 0], local[1, 1], local[2, 2]
    txy, txz, tyz = local[0, 1], local[0, 2], local[1, 2]
    t = np.linspace(0.0, 2.0 * np.pi, points, endpoint=False)
    c2, s2 = np.cos(2.0 * t), np.sin(2.0 * t)
    tt = sx + sy - 2.0 * (sx - sy) * c2 - 4.0 * txy * s2 - pressure
    zz = sz - 2.0 * poisson_ratio * ((sx - sy) * c2 + 2.0 * txy * s2)
    tz = 2.0 * (tyz * np.cos(t) - txz * np.sin(t))
    half = np.sqrt(0.25 * (tt - zz) ** 2 + tz**2)
    principal = np.sort(
        np.stack([0.5 * (tt + zz) - half, 0.5 * (tt + zz) + half, np.full_like(t, pressure)], 1),
        axis=1,
    )
    where = np.outer(np.cos(t), e1) + np.outer(np.sin(t), e2)
    return where, principal


def hole_wall_least_stress(
    stress: ArrayLike,
    axis: ArrayLike,
    poisson_ratio: float,
    pressure: float = 0.0,
    points: int = 720,
) -> tuple[float, FloatArray]:
    """Least principal stress on the wall of a circular hole (negative: tension).

    See :func:`hole_wall_principal_stresses`; returns the least over the wall and
    the unit vector from the axis to where it acts.  Reduces to Kirsch's
    ``3 Sh - SH`` for a vertical hole.
    """
    where, principal = hole_wall_principal_stresses(stress, axis, poisson_ratio, pressure, points)
    k = int(np.argmin(principal[:, 0]))
    return float(principal[k, 0]), where[k]


def mohr_coulomb_ratio(principal: ArrayLike, cohesion: float, friction_angle: float) -> FloatArray:
    """Mohr-Coulomb demand over capacity on the worst plane: >= 1 fails in shear.

    ``principal``: (..., 3) ascending principal stresses, compression positive;
    ``friction_angle`` in degrees.  The ratio of the largest shear, ``(s1 - s3) / 2``,
    to ``c0 cos phi + (s1 + s3) / 2 sin phi`` (infinite when that is not positive:
    then the tension cut-off decides).
    """
    p = np.asarray(principal, dtype=float)
    phi = np.radians(friction_angle)
    radius = 0.5 * (p[..., 2] - p[..., 0])
    capacity = cohesion * np.cos(phi) + 0.5 * (p[..., 2] + p[..., 0]) * np.sin(phi)
    with np.errstate(divide="ignore"):
        return np.where(capacity > 0.0, radius / np.where(capacity > 0.0, capacity, 1.0), np.inf)


def filtered_wall_breakdown(
    radius: float,
    sh_max: float,
    sh_min: float,
    tensile_strength: float,
    length: float,
    points: int = 1200,
) -> float:
    """Wellbore pressure at which the Kirsch stress filtered over ``length`` reaches T0.

    The strength over a length of :mod:`hfcdem.solid.nonlocal_strength`: the
    stress normal to the radial plane along SH, filtered by the 2D Helmholtz
    kernel ``K0(d / l) / (2 pi l^2)`` with an image across the wall's tangent at
    the wall point (the zero-flux condition of a straight wall; a source on the
    wall is its own image), normalised over the rock, taken at the wall and set
    equal to ``tensile_strength``.  It is
    Hubbert-Willis' ``3 Sh - SH + T0`` as ``l -> 0``; for ``l > 0`` the wall's
    curvature is only approximated (the image kernel's weight over the rock is
    1.05 at ``l = a / 10``).  Plane strain, stresses compression positive.
    """
    from scipy.special import k0

    if not 0.0 < length < radius:
        raise ValueError(f"length must be in (0, radius), got {length!r}")
    reach = 12.0 * length
    xs = np.linspace(radius - reach, radius + reach, points)
    ys = np.linspace(-reach, reach, points)
    x, y = np.meshgrid(xs, ys)
    rock = np.hypot(x, y) > radius
    # the source on the wall is its own image: the kernel doubles, and the
    # normalisation over the rock takes the factor out
    w = np.where(rock, k0(np.maximum(np.hypot(x - radius, y), 1e-12) / length), 0.0)

    def normal_y(pressure: float) -> float:
        r, theta = np.hypot(x, y), np.arctan2(y, x)
        k = kirsch_stress(np.where(rock, r, radius), theta, radius, sh_max, sh_min, pressure)
        s, c = np.sin(theta), np.cos(theta)
        yy = k.rr * s**2 + k.tt * c**2 + 2.0 * k.rt * s * c
        return float((w * -yy).sum() / w.sum())  # tension positive

    at_zero = normal_y(0.0)
    per_pascal = (normal_y(1e6) - at_zero) / 1e6
    return (tensile_strength - at_zero) / per_pascal


def hubbert_willis_breakdown(
    sh_max: float, sh_min: float, tensile_strength: float, pore_pressure: float = 0.0
) -> float:
    """Breakdown pressure of an impermeable borehole: 3 Sh - SH - P0 + T."""
    return 3.0 * sh_min - sh_max - pore_pressure + tensile_strength


def haimson_fairhurst_breakdown(
    sh_max: float,
    sh_min: float,
    tensile_strength: float,
    pore_pressure: float,
    biot: float,
    poisson_ratio: float,
) -> float:
    """Breakdown pressure with fluid penetrating the wall (Haimson-Fairhurst)."""
    eta = biot * (1.0 - 2.0 * poisson_ratio) / (2.0 * (1.0 - poisson_ratio))
    return (3.0 * sh_min - sh_max + tensile_strength - 2.0 * eta * pore_pressure) / (
        2.0 * (1.0 - eta)
    )


# ---------------------------------------------------------------------------
# Plane-strain hydraulic fractures (KGD) and radial fractures
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class KGDState:
    """Half-length, inlet opening and inlet net pressure of a KGD fracture at time t."""

    half_length: float
    inlet_opening: float
    net_pressure: float


def kgd_viscosity(
    time: float, rate: float, youngs_modulus: float, poisson_ratio: float, viscosity: float
) -> KGDState:
    """Zero-toughness, no-leak-off KGD solution (``rate`` per unit height, total).

    eps = (mu'/(E' t))^(1/3), L = (E' Q0^3 t^4 / mu')^(1/6), l = 0.61524 L,
    w(0) = 1.8302 eps l (Omega scaled by l), p_net(0) = 0.54495 eps E'.
    """
    e_prime = plane_strain_modulus(youngs_modulus, poisson_ratio)
    mu_prime = 12.0 * viscosity
    eps = (mu_prime / (e_prime * time)) ** (1.0 / 3.0)
    scale = (e_prime * rate**3 * time**4 / mu_prime) ** (1.0 / 6.0)
    half_length = 0.61524 * scale
    return KGDState(
        half_length=half_length,
        inlet_opening=1.8302 * eps * half_length,
        net_pressure=0.54495 * eps * e_prime,
    )


def toughness_scale(fracture_toughness: float) -> float:
    """K' = 4 sqrt(2/pi) KIc."""
    return 4.0 * np.sqrt(2.0 / np.pi) * fracture_toughness


def kgd_toughness(
    time: float, rate: float, youngs_modulus: float, poisson_ratio: float, fracture_toughness: float
) -> KGDState:
    """Toughness-dominated KGD: l = 0.9324 (E' Q0 t / K')^(2/3), p_net = KIc / sqrt(pi l).

    The inlet opening is that of a uniformly pressurised crack, (4 p_net / E') l.
    """
    e_prime = plane_strain_modulus(youngs_modulus, poisson_ratio)
    k_prime = toughness_scale(fracture_toughness)
    half_length = 0.9324 * (e_prime * rate * time / k_prime) ** (2.0 / 3.0)
    p_net = fracture_toughness / np.sqrt(np.pi * half_length)
    return KGDState(
        half_length=half_length,
        inlet_opening=4.0 * p_net / e_prime * half_length,
        net_pressure=p_net,
    )


def radial_toughness_radius(
    time: float, rate: float, youngs_modulus: float, poisson_ratio: float, fracture_toughness: float
) -> float:
    """Toughness-dominated radial fracture: R = 0.8546 (E' Q0 t / K')^(2/5)."""
    e_prime = plane_strain_modulus(youngs_modulus, poisson_ratio)
    k_prime = toughness_scale(fracture_toughness)
    return float(0.8546 * (e_prime * rate * time / k_prime) ** 0.4)


# ---------------------------------------------------------------------------
# Perforation tunnels as stacks of conical frustums
# ---------------------------------------------------------------------------


def frustum_volume(diameters: ArrayLike, stations: ArrayLike) -> float:
    """Volume of circular sections ``diameters`` at axial ``stations`` joined by frustums."""
    d = np.asarray(diameters, dtype=float)
    z = np.asarray(stations, dtype=float)
    if d.shape != z.shape or d.ndim != 1 or d.size < 2:
        raise ValueError("diameters and stations must be 1D arrays of equal length >= 2")
    r0, r1, dz = 0.5 * d[:-1], 0.5 * d[1:], np.diff(z)
    return float(np.sum(np.pi * dz * (r0**2 + r0 * r1 + r1**2) / 3.0))


def frustum_lateral_area(diameters: ArrayLike, stations: ArrayLike) -> float:
    """Lateral (wall) area of the same stack of frustums, end caps excluded."""
    d = np.asarray(diameters, dtype=float)
    z = np.asarray(stations, dtype=float)
    r0, r1, dz = 0.5 * d[:-1], 0.5 * d[1:], np.diff(z)
    return float(np.sum(np.pi * (r0 + r1) * np.sqrt(dz**2 + (r1 - r0) ** 2)))


def equal_volume_cylinder_diameter(diameters: ArrayLike, stations: ArrayLike) -> float:
    """Diameter of the cylinder of the same length and volume as the frustum stack."""
    z = np.asarray(stations, dtype=float)
    length = float(z[-1] - z[0])
    return float(2.0 * np.sqrt(frustum_volume(diameters, stations) / (np.pi * length)))


__all__ = [
    "ArrayLike",
    "FloatArray",
    "KGDState",
    "KirschStress",
    "equal_volume_cylinder_diameter",
    "filtered_wall_breakdown",
    "frustum_lateral_area",
    "frustum_volume",
    "haimson_fairhurst_breakdown",
    "hole_wall_least_stress",
    "hole_wall_principal_stresses",
    "hubbert_willis_breakdown",
    "kgd_toughness",
    "kgd_viscosity",
    "kirsch_stress",
    "kirsch_wall_hoop_stress",
    "mohr_coulomb_ratio",
    "penny_opening",
    "penny_volume",
    "plane_strain_modulus",
    "radial_toughness_radius",
    "sneddon_area",
    "sneddon_opening",
    "toughness_scale",
]
