"""Carter leak-off (the fluid and the pump schedule are data: :mod:`hfcdem.config.materials`).

All quantities are SI.  In 2D (plane strain) volumes and rates are per metre of
thickness: a rate in m^3/s means m^3/s per metre.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CarterLeakOff:
    """Carter leak-off: each wetted face loses ``C_L / sqrt(t - t0)`` (m/s).

    ``t0`` is the time fluid first reached the facet; both faces leak.
    """

    coefficient: float

    def __post_init__(self) -> None:
        c = self.coefficient
        if not (math.isfinite(c) and 0.0 <= c <= 1e-2):
            raise ValueError(f"leak-off coefficient C_L must be in [0, 0.01] m/s^0.5, got {c!r}")

    def volume(
        self, area: np.ndarray, wetted_since: np.ndarray, t0: float, t1: float
    ) -> np.ndarray:
        """Volume lost through both faces of facets of ``area`` during ``[t0, t1]``."""
        start = np.maximum(t0 - wetted_since, 0.0)
        end = np.maximum(t1 - wetted_since, 0.0)
        return 4.0 * self.coefficient * area * (np.sqrt(end) - np.sqrt(start))


__all__ = [
    "CarterLeakOff",
]
