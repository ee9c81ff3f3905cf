"""The fluid held by every fracture facet: the one record of the flow state per facet.

Facets are keyed by their sorted global vertex ids, so the record survives
network rebuilds (a break renumbers the network) and a resume on another
number of ranks.  A facet missing from the record is dry and empty: content 0,
never wet, pressure 0.  The coupled problem works on arrays in network order
(:meth:`FluidState.on`) and writes them back (:meth:`FluidState.store`) before
every rebuild; a rejected step attempt puts back a :meth:`FluidState.copy`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

#: a facet's key: its global vertex ids, sorted
Key = tuple[int, ...]


def facet_keys(vertex_ids: np.ndarray) -> list[Key]:
    """Keys of facets given by rows of global vertex ids (in any order)."""
    return [tuple(int(v) for v in row) for row in np.sort(np.asarray(vertex_ids), axis=1)]


@dataclass
class FluidState:
    """Fluid content (m^3 at reference density), wetting time (s) and pressure (Pa) per facet."""

    content: dict[Key, float] = field(default_factory=dict)
    wet_since: dict[Key, float] = field(default_factory=dict)  # inf: not wet
    pressure: dict[Key, float] = field(default_factory=dict)

    def copy(self) -> FluidState:
        """Return an independent copy (what a step attempt saves)."""
        return FluidState(dict(self.content), dict(self.wet_since), dict(self.pressure))

    def restore(self, saved: FluidState) -> None:
        """Put back a :meth:`copy` (a rejected step attempt)."""
        self.content = dict(saved.content)
        self.wet_since = dict(saved.wet_since)
        self.pressure = dict(saved.pressure)

    def on(self, keys: Sequence[Key]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Content, wetting time and pressure of the facets ``keys``, in their order."""
        content = np.array([self.content.get(k, 0.0) for k in keys], dtype=float)
        wet_since = np.array([self.wet_since.get(k, math.inf) for k in keys], dtype=float)
        pressure = np.array([self.pressure.get(k, 0.0) for k in keys], dtype=float)
        return content, wet_since, pressure

    def store(
        self,
        keys: Sequence[Key],
        content: np.ndarray,
        wet_since: np.ndarray,
        pressure: np.ndarray,
    ) -> None:
        """Record the per-facet arrays of the facets ``keys`` (others keep their values)."""
        if not len(keys) == len(content) == len(wet_since) == len(pressure):
            raise ValueError(
                f"store needs one content, wet_since and pressure per key: {len(keys)} keys, "
                f"{len(content)}, {len(wet_since)}, {len(pressure)} values"
            )
        for i, k in enumerate(keys):
            self.content[k] = float(content[i])
            self.wet_since[k] = float(wet_since[i])
            self.pressure[k] = float(pressure[i])


__all__ = ["FluidState", "Key", "facet_keys"]
