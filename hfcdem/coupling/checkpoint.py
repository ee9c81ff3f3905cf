"""The coupled run's state as JSON: the content of ``checkpoint.json``.

Interfaces (failure state, contact, friction traction, released as the faces
of debris, the pressure a facet last closed at) and the fluid record
(:class:`~hfcdem.coupling.fluidstate.FluidState`) are keyed by global vertex
ids, so a run may resume on another number of ranks; the scalars are the
problem's own (time, step size, volumes, counters).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from hfcdem.coupling.fluidstate import FluidState, Key
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState

#: the problem's attributes a checkpoint holds, in this order, under "scalars"
SCALARS = (
    "t",
    "dt",
    "injected",
    "leaked",
    "cavity_content",
    "p_cavity",
    "initial_fluid",
    "first_break_time",
    "first_break_pressure",  # absent from checkpoints before 2026-12-07
    "_last_ratio",
    "initial_failures",
    "rebuilds",
    "rebuild_seconds",
)


def interface_rows(solid: CDEMSolid) -> list[list[Any]]:
    """Key, state, contact, friction traction, release and shut pressure of every broken facet.

    Collective.  The shut pressure is None where the facet has not closed.
    """
    sel = np.flatnonzero((solid.state != FacetState.INTACT) & solid.owned)
    rows = [
        [
            sorted(int(v) for v in solid.vertex_ids[i]),
            int(solid.state[i]),
            int(solid.contact[i]),
            [float(x) for x in solid.friction_traction[i]],
            bool(solid.released[i]),
            None if math.isnan(solid.states.shut_at[i]) else float(solid.states.shut_at[i]),
        ]
        for i in sel
    ]
    return sorted(r for part in solid.comm.allgather(rows) for r in part)


def restore_interfaces(solid: CDEMSolid, rows: list[list[Any]]) -> None:
    """Set the states of this rank's facets among ``rows`` (of :func:`interface_rows`)."""
    ids = np.sort(np.asarray(solid.vertex_ids, dtype=np.int64), axis=1)
    local: dict[Key, int] = {tuple(int(v) for v in ids[i]): i for i in range(len(ids))}
    for key, state, contact, friction, *rest in rows:  # older checkpoints: 4 or 5 items
        i = local.get(tuple(key))
        if i is not None:
            solid.state[i] = state
            solid.contact[i] = contact
            solid.friction_traction[i] = friction
            solid.released[i] = bool(rest and rest[0])
            shut = rest[1] if len(rest) > 1 else None
            solid.states.shut_at[i] = math.nan if shut is None else shut


def band_rows(solid: CDEMSolid) -> list[list[int]]:
    """Keys of the free interfaces of a reduced solid (empty for the full one; collective)."""
    if solid.mode == "full":
        return []
    sel = np.flatnonzero(solid.band.free & solid.owned)
    rows = [sorted(int(v) for v in solid.vertex_ids[i]) for i in sel]
    return sorted(r for part in solid.comm.allgather(rows) for r in part)


def restore_band(solid: CDEMSolid, rows: list[list[int]]) -> None:
    """Free the interfaces among ``rows`` (of :func:`band_rows`); collective."""
    ids = np.sort(np.asarray(solid.vertex_ids, dtype=np.int64), axis=1)
    keys = {tuple(int(v) for v in row) for row in rows}
    flags = np.array([tuple(int(v) for v in ids[i]) in keys for i in range(len(ids))], dtype=bool)
    solid.free_interfaces(flags)


def _table(values: dict[Key, float]) -> list[list[Any]]:
    return [[list(k), v] for k, v in sorted(values.items())]


def fluid_tables(fluid: FluidState) -> dict[str, list[list[Any]]]:
    """Return the fluid record as JSON-ready tables ``[[key], value]`` (never wet: None)."""
    return {
        "content": _table(fluid.content),
        "wet_since": [[k, (v if math.isfinite(v) else None)] for k, v in _table(fluid.wet_since)],
        "pressure": _table(fluid.pressure),
    }


def fluid_from_tables(data: Mapping[str, Any]) -> FluidState:
    """Return the fluid record of :func:`fluid_tables` (a checkpoint's top-level tables)."""
    for name in ("content", "wet_since", "pressure"):
        if name not in data:
            raise KeyError(f"the checkpoint has no {name!r} table")
    return FluidState(
        content={tuple(k): float(v) for k, v in data["content"]},
        wet_since={tuple(k): (math.inf if v is None else float(v)) for k, v in data["wet_since"]},
        pressure={tuple(k): float(v) for k, v in data["pressure"]},
    )


def checkpoint_data(
    scalars: Mapping[str, Any], solid: CDEMSolid, fluid: FluidState
) -> dict[str, Any]:
    """Return the checkpoint (the same on every rank, JSON-ready; collective)."""
    return {
        "scalars": dict(scalars),
        "interfaces": interface_rows(solid),
        "band": band_rows(solid),
    } | fluid_tables(fluid)


def read_checkpoint(data: Mapping[str, Any], solid: CDEMSolid) -> tuple[dict, FluidState]:
    """Set the solid's interface states from ``data``; return its scalars and fluid record."""
    restore_interfaces(solid, data["interfaces"])
    restore_band(solid, data.get("band", []))  # older checkpoints: regrown by screening
    return dict(data["scalars"]), fluid_from_tables(data)


__all__ = [
    "SCALARS",
    "band_rows",
    "checkpoint_data",
    "fluid_from_tables",
    "fluid_tables",
    "interface_rows",
    "read_checkpoint",
    "restore_band",
    "restore_interfaces",
]
