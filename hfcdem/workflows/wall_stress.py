"""Does the in-situ stress alone crack the cavity walls?  A closed-form check before a run.

Each wall of a perforated block (the wellbore, each tunnel) is taken as a long
circular hole in the far-field in-situ stress (generalised plane strain,
:func:`hfcdem.analytic.hole_wall_least_stress`), at the scene's initial
pressure where the fluid loads it.  Where its least principal stress is a
tension above the rock's tensile strength, a strength criterion breaks the wall
before any injection, and with no length scale in the criterion the number of
broken interfaces grows as the mesh refines around the hole.  The lab specimen
(Sv 15, SH 6, Sh 1 MPa, T0 2.59 MPa) is such a scene at 30 and 45 deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from hfcdem.analytic import hole_wall_least_stress
from hfcdem.config.geometry import PerforatedBlock, Scene


@dataclass(frozen=True)
class WallTension:
    """The largest tension (Pa, 0 for none) on one wall under the in-situ stress alone.

    ``where``: the unit vector from the hole's axis to the wall point where it
    acts; ``strength``: the rock's tensile strength (Pa).
    """

    hole: str
    tension: float
    where: tuple[float, float, float]
    strength: float

    @property
    def exceeds(self) -> bool:
        """Whether the wall is expected to crack before injection."""
        return self.tension > self.strength

    def as_dict(self) -> dict[str, Any]:
        """Return the check as ``summary.json`` keeps it (MPa)."""
        return {
            "hole": self.hole,
            "tension_MPa": self.tension / 1e6,
            "tensile_strength_MPa": self.strength / 1e6,
            "exceeds": self.exceeds,
            "where": [round(v, 4) for v in self.where],
        }


def _axis(letter: str) -> np.ndarray:
    return np.eye(3)["xyz".index(letter)]


def in_situ_wall_tension(scene: Scene) -> list[WallTension]:
    """Check the wellbore's and each tunnel's wall (empty for scenes of other kinds).

    A cased wellbore's wall is unloaded; the tunnels (and an open wellbore) carry
    the scene's initial pressure.
    """
    geo, phys = scene.geometry, scene.physics
    if not isinstance(geo, PerforatedBlock) or phys is None:
        return []
    rock = phys.rock
    strength = phys.interfaces.tensile_strength
    if not math.isfinite(strength):
        return []  # unbreakable interfaces: nothing to warn of
    stress = -phys.stress.tensor(3)  # compression positive
    p0 = phys.initial_pressure
    holes = [("wellbore", _axis(geo.wellbore.axis), 0.0 if phys.wellbore == "cased" else p0)]
    holes += [
        (f"perforation {k + 1}", np.asarray(perf.direction), p0)
        for k, perf in enumerate(geo.perforations)
    ]
    out = []
    for name, axis, pressure in holes:
        least, where = hole_wall_least_stress(stress, axis, rock.poisson_ratio, pressure)
        x, y, z = (float(v) for v in where)
        out.append(WallTension(name, max(0.0, -least), (x, y, z), strength))
    return out


def wall_tension_warning(checks: list[WallTension]) -> str | None:
    """Say which walls the in-situ stress alone cracks, or None when none."""
    over = [c for c in checks if c.exceeds]
    if not over:
        return None
    walls = ", ".join(f"{c.hole} {c.tension / 1e6:.2f} MPa" for c in over)
    strength = over[0].strength / 1e6
    return (
        f"in-situ check: the in-situ stress alone puts these walls in tension above the "
        f"tensile strength {strength:.2f} MPa (closed form, a long hole in generalised "
        f"plane strain): {walls}; interfaces there break before injection, and more of them "
        "as the mesh refines (the strength criterion has no length scale)"
    )


__all__ = ["WallTension", "in_situ_wall_tension", "wall_tension_warning"]
