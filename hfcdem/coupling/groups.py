"""The fracture network on this rank, its pressure groups, and the wet joints beside it.

Rebuilt at every interface event: the broken facets form the
:class:`~hfcdem.flow.network.Network` (the same on every rank), each wet facet
is a pressure group of its own (or one with the cavity under uniform
fidelity), and the solid is condensed onto those groups
(:func:`condense_network`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import dolfinx
import numpy as np

from hfcdem.coupling.condense import (
    NetworkView,
    closure_offsets,
    condense,
    group_volumes,
    touching_joints,
)
from hfcdem.coupling.fluidstate import Key, facet_keys
from hfcdem.coupling.settings import FlowSettings
from hfcdem.flow.network import Network, build_network
from hfcdem.flow.seepage import network_positions
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import OPEN


@dataclass(frozen=True, eq=False)
class LocalNetwork:
    """The network of all broken facets, and where they are among this rank's interfaces."""

    net: Network
    view: NetworkView
    keys: list[Key]  # facet keys in network order
    is_open: np.ndarray  # open (fluid-loaded) facets, network order
    joined: np.ndarray  # facets joined to the cavity, network order


def local_network(solid: CDEMSolid, cavity_vertices: np.ndarray) -> LocalNetwork:
    """Build the network of the solid's broken facets (collective)."""
    comm = solid.comm
    local = np.flatnonzero(solid.state != FacetState.INTACT)
    owned = local[solid.owned[local]]
    net, _ = build_network(
        comm,
        solid.vertex_ids[owned],  # unsorted: build_network orders ids and coordinates
        solid.areas[owned],
        solid.vertex_coords[owned],
        cavity_vertices,
    )
    positions = network_positions(solid, net, local)
    owned_sel = solid.owned[local]
    view = NetworkView(local, positions, owned_sel, net.size)
    contact_open = (solid.contact[local] == OPEN).astype(float)
    is_open = view.gather(contact_open[owned_sel], comm) > 0.5
    # the faces of debris are joined: the cavity's fluid surrounds the block
    released = view.gather(solid.released[local][owned_sel].astype(float), comm) > 0.5
    joined = (net.components() == 0) | released
    return LocalNetwork(net, view, facet_keys(net.keys), is_open, joined)


def joined_cracks(solid: CDEMSolid, cavity_vertices: np.ndarray) -> np.ndarray:
    """Per local facet: broken and joined to the cavity through broken facets (collective).

    The faces of debris are joined: the cavity's fluid surrounds it.
    """
    local = local_network(solid, cavity_vertices)
    out = np.zeros(solid.num_facets, dtype=bool)
    out[local.view.facets] = local.joined[local.view.positions]
    return out


def pressure_groups(wet: np.ndarray, uniform: bool) -> np.ndarray:
    """Pressure group of each facet: 0 the cavity, -1 dry, else 1, 2, .. in order.

    ``uniform``: every wet facet shares the cavity's group 0.
    """
    group = np.full(len(wet), -1, dtype=np.int64)
    if uniform:
        group[wet] = 0
    else:
        group[wet] = 1 + np.arange(int(wet.sum()))
    return group


def group_count(group: np.ndarray) -> int:
    """Return the number of pressure groups (the cavity's group 0 always counts)."""
    return 1 + (int(group.max()) if group.size and group.max() > 0 else 0)


def wall_joints(
    solid: CDEMSolid,
    settings: FlowSettings,
    cavity_vertices: np.ndarray,
    network: LocalNetwork | None = None,
    group: np.ndarray | None = None,
) -> np.ndarray:
    """Flag the interfaces that share an edge (2D: a vertex) with the cavity wall.

    With ``permeate_joints``, also those along the open facets of the cavity's
    group 0 in ``network`` (``group`` per network facet).
    """
    if not (settings.wet_wall_joints and settings.cavity):
        return np.zeros(solid.num_facets, dtype=bool)
    ids = cavity_vertices
    if settings.permeate_joints and network is not None and group is not None:
        feeding = (group == 0) & (network.is_open > 0)
        if feeding.any():
            ids = np.union1d(ids, network.net.keys[feeding].reshape(-1))
    return touching_joints(solid, ids)


def near_fluid(
    solid: CDEMSolid, net: Network, pressurised: np.ndarray, cavity_vertices: np.ndarray
) -> np.ndarray:
    """Interfaces touching a ``pressurised`` network facet or the cavity (a vertex shared)."""
    wet_ids = np.unique(net.keys[pressurised].reshape(-1)) if net.size else np.zeros(0, np.int64)
    ids = np.union1d(wet_ids, cavity_vertices)
    return np.asarray(np.isin(solid.vertex_ids, ids).any(axis=1), dtype=bool)


def condense_network(
    solid: CDEMSolid,
    cavity: Sequence[str],
    network: LocalNetwork,
    group: np.ndarray,
    wet_joints: np.ndarray,
) -> tuple[dolfinx.fem.Function, list[dolfinx.fem.Function]]:
    """Condense the solid onto the pressure ``group`` of each network facet.

    Returns the base state and one unit-pressure response per group (see
    :func:`~hfcdem.coupling.condense.condense`).
    """
    view = network.view
    local_group = np.full(solid.num_facets, -2, dtype=np.int64)
    local_group[view.facets] = group[view.positions]
    local_open = np.zeros(solid.num_facets, dtype=bool)
    local_open[view.facets] = network.is_open[view.positions]
    return condense(solid, cavity, wet_joints, local_group, local_open, group_count(group))


def network_volumes(
    solid: CDEMSolid,
    network: LocalNetwork,
    condensed: tuple[dolfinx.fem.Function, list[dolfinx.fem.Function]],
    residual_aperture: float,
    cavity_form: dolfinx.fem.Form | None,
    group: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """Void volumes of the network's facets and the cavity, linear in the group pressures.

    ``condensed``: the base state and group responses of :func:`condense_network`.
    Returns v0, h, hc and the base state's wall motion (see
    :func:`~hfcdem.coupling.condense.group_volumes`), and the closure stress of
    every network facet (in-situ normal stress, compression positive).  With the
    pressure ``group`` of each facet, an open broken facet also counts its
    contact compliance: ``area / kn`` per pascal of its group's pressure
    (:func:`~hfcdem.coupling.condense.closure_offsets`).
    """
    offsets, closure, compliance = closure_offsets(solid, network.view)
    base, columns = condensed
    v0, h, hc, wall = group_volumes(
        solid,
        network.view,
        base,
        columns,
        offsets,
        (network.is_open, network.net.area, residual_aperture),
        cavity_form,
    )
    if group is not None:
        rows = np.flatnonzero(network.is_open & (group >= 0) & (compliance > 0.0))
        h[rows, group[rows]] += network.net.area[rows] * compliance[rows]
    return v0, h, hc, wall, closure


__all__ = [
    "LocalNetwork",
    "condense_network",
    "group_count",
    "joined_cracks",
    "local_network",
    "near_fluid",
    "network_volumes",
    "pressure_groups",
    "wall_joints",
]
