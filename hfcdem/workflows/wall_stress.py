"""Does the in-situ stress alone crack the cavity walls?  A closed-form check before a run.

Each wall of a perforated block (the wellbore, each tunnel) is taken as a long
circular hole in the far-field in-situ stress (generalised plane strain,
:func:`hfcdem.analytic.hole_wall_least_stress`), at the scene's initial
pressure where the fluid loads it.  Where its least principal stress is a
tension above the rock's tensile strength, a strength criterion breaks the wall
before any injection, and with no length scale in the criterion the number of
broken interfaces grows as the mesh refines around the hole.  The lab specimen
(Sv 15, SH 6, Sh 1 MPa, T0 2.59 MPa) is such a scene at every azimuth.  Where
the wall is compressed, a Mohr-Coulomb ratio says whether a plane there fails
in shear: No. 2's wellbore drilled at 30 MPa does not (0.76: 3 Sv - SH - 30 =
125 MPa of hoop stress against 30 MPa radial, c0 = 17 MPa); unloaded, it
would (1.23, a breakout).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from hfcdem.analytic import hole_wall_principal_stresses, mohr_coulomb_ratio
from hfcdem.config.geometry import PerforatedBlock, Scene


@dataclass(frozen=True)
class WallTension:
    """The largest tension (Pa, 0 for none) on one wall under the in-situ stress alone.

    ``where``: the unit vector from the hole's axis to the wall point where it
    acts; ``strength``: the rock's tensile strength (Pa); ``shear_ratio``: the
    largest Mohr-Coulomb demand over capacity on the wall where no principal
    stress is a tension (>= 1: a plane there fails in shear).
    """

    hole: str
    tension: float
    where: tuple[float, float, float]
    strength: float
    shear_ratio: float = 0.0

    @property
    def exceeds(self) -> bool:
        """Whether the wall is expected to crack in tension before injection."""
        return self.tension > self.strength

    @property
    def shears(self) -> bool:
        """Whether the wall is expected to fail in shear before injection."""
        return self.shear_ratio >= 1.0

    def as_dict(self) -> dict[str, Any]:
        """Return the check as ``summary.json`` keeps it (MPa)."""
        return {
            "hole": self.hole,
            "tension_MPa": self.tension / 1e6,
            "tensile_strength_MPa": self.strength / 1e6,
            "exceeds": self.exceeds,
            "shear_ratio": self.shear_ratio,
            "where": [round(v, 4) for v in self.where],
        }


def _axis(letter: str) -> np.ndarray:
    return np.eye(3)["xyz".index(letter)]


def in_situ_wall_tension(scene: Scene) -> list[WallTension]:
    """Check the wellbore's and each tunnel's wall (empty for scenes of other kinds).

    A drilled (or open) wellbore is checked at the scene's initial pressure, as
    are the tunnels.  A cased one is left out: the solid keeps its wall at the
    in-situ traction (a tube set before the rock was stressed), so the rock
    around it carries no concentration of a hole.
    """
    geo, phys = scene.geometry, scene.physics
    if not isinstance(geo, PerforatedBlock) or phys is None:
        return []
    rock, model = phys.rock, phys.interfaces
    strength = model.tensile_strength
    if not math.isfinite(strength):
        return []  # unbreakable interfaces: nothing to warn of
    stress = -phys.stress.tensor(3)  # compression positive
    p0 = phys.initial_pressure
    # a cased wall keeps its in-situ traction in the solid: no hole in the stress to check
    holes = [] if phys.wellbore == "cased" else [("wellbore", _axis(geo.wellbore.axis), p0)]
    holes += [
        (f"perforation {k + 1}", np.asarray(perf.direction), p0)
        for k, perf in enumerate(geo.perforations)
    ]
    out = []
    for name, axis, pressure in holes:
        where, principal = hole_wall_principal_stresses(stress, axis, rock.poisson_ratio, pressure)
        k = int(np.argmin(principal[:, 0]))
        compressed = principal[:, 0] >= 0.0  # elsewhere the tension cut-off decides
        ratio = mohr_coulomb_ratio(principal[compressed], model.cohesion, model.friction_angle)
        x, y, z = (float(v) for v in where[k])
        tension = max(0.0, -float(principal[k, 0]))
        out.append(WallTension(name, tension, (x, y, z), strength, float(ratio.max(initial=0.0))))
    return out


def wall_tension_warning(checks: list[WallTension]) -> str | None:
    """Say which walls the in-situ stress alone cracks, or None when none."""
    over = [c for c in checks if c.exceeds]
    sheared = [c for c in checks if c.shears]
    if not over and not sheared:
        return None
    parts = []
    if over:
        walls = ", ".join(f"{c.hole} {c.tension / 1e6:.2f} MPa" for c in over)
        parts.append(f"in tension above the tensile strength {over[0].strength / 1e6:.2f} MPa: "
                     f"{walls}")  # fmt: skip
    if sheared:
        walls = ", ".join(f"{c.hole} {c.shear_ratio:.2f}x" for c in sheared)
        parts.append(f"in shear beyond Mohr-Coulomb (demand over capacity): {walls}")
    return (
        "in-situ check (closed form, a long hole in generalised plane strain): the in-situ "
        f"stress alone puts walls {'; and '.join(parts)}; interfaces there break before "
        "injection, and more of them as the mesh refines (a strength criterion at a point "
        "has no length scale: see rock.strength_length)"
    )


__all__ = ["WallTension", "in_situ_wall_tension", "wall_tension_warning"]
