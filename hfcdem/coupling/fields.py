"""What the coupled run shows: per-facet output fields, the fluid front and openings.

Plain functions of the network's arrays (void volume, fluid content, wet flags,
in network order), so the problem class stays the stepping and the results are
testable on hand-made numbers.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hfcdem.coupling.condense import NetworkView
from hfcdem.flow.network import Network
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads


def saturation(
    wet: np.ndarray, content: np.ndarray, volumes: np.ndarray, lag: bool = False
) -> np.ndarray:
    """Saturation of every facet: 1 where wet, else content / void volume in [0, 1].

    With ``lag`` (groups may lag behind their opening, see
    :class:`~hfcdem.flow.balance.GroupBalance`) an open wet facet is also
    content / void: below 1 when its group holds less than its void.
    """
    frac = np.clip(content / np.maximum(volumes, 1e-300), 0.0, 1.0)
    if lag:
        return np.where(wet & (volumes <= 0.0), 1.0, frac)
    return np.where(wet, 1.0, frac)


def apertures(volumes: np.ndarray, area: np.ndarray, residual: float) -> np.ndarray:
    """Hydraulic aperture of every facet (m): void volume over area, at least ``residual``."""
    w = np.maximum(volumes / np.maximum(area, 1e-300) - residual, 0.0)
    return w + residual


def opening_at_cavity(volumes: np.ndarray, net: Network) -> float:
    """Mean opening of the facets that touch the cavity or injection point (m)."""
    touch = net.touches_cavity
    if not touch.any():
        return 0.0
    return float(np.sum(volumes[touch]) / np.sum(net.area[touch]))


def wet_extent(
    net: Network,
    wet: np.ndarray,
    sat: np.ndarray,
    origin: Sequence[float],
    direction: Sequence[float],
) -> float:
    """Return the fluid front along ``direction`` from ``origin`` (m).

    The far end of the wet facets, plus the filled share ``sat`` of a dry facet
    just beyond.
    """
    o = np.zeros(3)
    o[: len(origin)] = origin
    d = np.zeros(3)
    d[: len(direction)] = direction
    d /= np.linalg.norm(d)
    if not wet.any():
        return 0.0
    proj = (net.centroid - o) @ d
    half = 0.5 * net.area  # 2D: facet length
    reach = float(np.max(proj[wet] + half[wet]))
    ahead = ~wet & (np.abs(proj - half - reach) < 1e-6 * max(reach, 1.0))
    if ahead.any():
        reach += float(np.max(sat[ahead] * 2 * half[ahead]))
    return reach


def facet_fields(
    solid: CDEMSolid,
    view: NetworkView,
    pressure: np.ndarray,
    aperture: np.ndarray,
    sat: np.ndarray,
    is_open: np.ndarray,
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Vertex coordinates (F, nv, 3) and fluid data of this rank's owned network facets.

    The network arrays (pressure in Pa, aperture in m, saturation, open flags)
    are given in network order.  Data: fluid pressure (MPa), hydraulic aperture
    (m), saturation, failure state (1 tensile, 2 shear), open (1) or closed (0);
    for :func:`hfcdem.io.files.write_interfaces`.
    """
    pos = view.positions[view.owned]
    facets = view.facets[view.owned]
    data = {
        "fluid_pressure_MPa": pressure[pos] / 1e6,
        "aperture_m": aperture[pos],
        "saturation": sat[pos],
        "state": solid.state[facets].astype(float),
        "open": is_open[pos].astype(float),
    }
    return solid.vertex_coords[facets], data


def interface_fields(
    solid: CDEMSolid,
    loads: Loads,
    view: NetworkView,
    pressure: np.ndarray,
    aperture: np.ndarray,
    sat: np.ndarray,
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Vertex coordinates (F, nv, 3) and data of every owned interface facet.

    Data: failure state (0 intact, 1 tensile, 2 shear), mechanical opening (m),
    normal traction (MPa, tension positive), and the fluid's pressure (MPa),
    saturation and hydraulic aperture (m) from the network arrays, zero where no
    fluid cell is; ``joint_pressure_MPa``: the pressure inside intact joints
    that the loads carry (e.g. permeated wall joints at the cavity pressure),
    which the network arrays do not hold.  ``loads`` must be the loads of the
    solid's current displacement.
    """
    snap = solid.snapshot(loads)
    n = solid.num_facets
    local = {"pressure": np.zeros(n), "saturation": np.zeros(n), "aperture": np.zeros(n)}
    if view.size:
        loc, pos = view.facets, view.positions
        local["pressure"][loc] = pressure[pos] / 1e6
        local["saturation"][loc] = sat[pos]
        local["aperture"][loc] = aperture[pos]
    own = solid.owned
    joints = np.zeros(n) if loads.joint_pressure is None else np.asarray(loads.joint_pressure)
    data = {
        "state": solid.state[own].astype(float),
        "opening_m": snap.opening[own],
        "normal_traction_MPa": snap.normal_traction[own] / 1e6,
        "fluid_pressure_MPa": local["pressure"][own],
        "joint_pressure_MPa": joints[own] / 1e6,
        "saturation": local["saturation"][own],
        "aperture_m": local["aperture"][own],
    }
    return solid.vertex_coords[own], data


__all__ = [
    "apertures",
    "facet_fields",
    "interface_fields",
    "opening_at_cavity",
    "saturation",
    "wet_extent",
]
