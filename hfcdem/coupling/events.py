"""Interface events within a coupled step: contact switches, breaks, blocks cut loose.

The coupled problem repeats a step until the interface states settle; these
functions change the solid's states and say how many changed (global counts),
and the problem recondenses when any did.  A broken face that moved apart by
more than its cells' size ends a run at the model's validity limit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from mpi4py import MPI

from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads
from hfcdem.solid.fragments import Fragments
from hfcdem.solid.interfaces import FacetState, select_breaking
from hfcdem.solid.states import OPEN
from hfcdem.solvers import ValidityLimit

#: a broken interface whose faces moved apart by more than this times its cells' size has
#: left the small-displacement solid behind (a block sliding or lifting out of the wall)
LOOSE_JUMP = 1.0


def switch_contacts(
    solid: CDEMSolid, loads: Loads, only_closing: bool, hysteresis: bool = False
) -> int:
    """Switch contacts at ``loads``; return the global number switched (0: settled).

    ``only_closing``: switches that open a face are undone (the opening waits
    for the next step).  The coupled step sets it after one round of switches,
    which cuts off contact chatter (a facet that keeps opening and closing under
    the same pressure), so the loop ends, and no face is left open while its
    blocks interpenetrate (an open face has only the residual stiffness: a block
    it frees would fly).  (Two free rounds cost No. 2 coarse 34 more rebuilds for
    the same breakdown to 10 digits.)  ``hysteresis``: see
    :meth:`~hfcdem.solid.states.InterfaceStates.switch_contacts`.  Ghost states
    follow their owners.
    """
    saved = solid.states.copy()
    switched = solid.update_contact(loads, hysteresis)
    if switched and only_closing:
        keep = ~((saved.contact == OPEN) & (solid.contact != OPEN))
        solid.contact[keep] = saved.contact[keep]
        solid.friction_traction[keep] = saved.friction_traction[keep]
        solid.states.shut_at[keep] = saved.shut_at[keep]
        changed = np.count_nonzero((solid.contact != saved.contact) & solid.owned)
        switched = int(solid.comm.allreduce(int(changed), op=MPI.SUM))
    if switched:
        solid.sync_ghost_states()
    return switched


def facets_to_break(solid: CDEMSolid, ratio: np.ndarray, cap: int | None) -> np.ndarray:
    """Local facets to break at failure ``ratio`` (collective).

    The solid's break rule picks them, or with ``cap`` the most overstressed
    ``cap`` facets (fewer new fluid cells per solve keep Newton in its basin).
    """
    if cap is None:
        rule, count = solid.model.break_rule, solid.model.max_breaks
    else:
        rule, count = "cap", cap
    return select_breaking(ratio, solid.midpoints, rule, count, solid.comm)


def most_overstressed(
    solid: CDEMSolid, ratio: np.ndarray, mode: np.ndarray
) -> tuple[int, np.ndarray]:
    """Mode and midpoint of the facet with the highest failure ``ratio`` (collective).

    The same on every rank; ties (symmetric facets) go to the lowest midpoint,
    whatever the number of ranks.  Mode 0 and the origin when no facet is at its
    strength.
    """
    mine = (-math.inf, 0, np.zeros(solid.gdim))
    if ratio.size and float(ratio.max()) >= 1.0:
        f = int(np.argmax(ratio))
        mine = (float(ratio[f]), int(mode[f]), solid.midpoints[f, : solid.gdim].copy())
    best = max(
        solid.comm.allgather(mine),
        key=lambda item: (round(item[0], 12), *(-float(x) for x in item[2])),
    )
    return best[1], np.asarray(best[2])


def release_debris(
    solid: CDEMSolid, fragments: Fragments, supports: Sequence[str] = ()
) -> tuple[int, int, int]:
    """Hold open the faces of blocks newly cut loose from the cavity walls (collective).

    Such a block has no static equilibrium on its broken faces (a wedge at the
    wall slides out along them); the cavity's fluid surrounds it instead, and
    its faces, and the rock behind them, take the cavity pressure.  A loose
    cell with a face on a supporting wall (``supports``: a cased wellbore's,
    which keeps its in-situ traction) is held in place by it
    (:meth:`CDEMSolid.hold_cells`): only there does the fluid not surround it.
    Returns the global counts of faces released now, of the debris' cells in
    all and of cells newly held.
    """
    loose = fragments.loose_cells()  # the same on every rank; found once for both uses
    facets, cells = fragments.debris(loose)
    count = int(solid.comm.allreduce(int(np.count_nonzero(solid.owned[facets])), MPI.SUM))
    if count:
        solid.release_facets(facets)
    held = solid.hold_cells(fragments.loose_cells_on(supports, loose)) if supports else 0
    return count, cells, held


def check_small_displacement(solid: CDEMSolid, t: float) -> None:
    """Raise :class:`ValidityLimit` where a broken interface opened or slid past its size.

    A block cut out of the wall by broken faces, held by residual springs only,
    slides or lifts out of it when the loads push it (no static equilibrium):
    the small-displacement solid then reports metres of motion and cavity
    volumes far beyond the rock's (collective).
    """
    broken = np.flatnonzero((solid.state != FacetState.INTACT) & solid.owned)
    mine = (0.0, np.zeros(solid.gdim), 0.0)
    if broken.size:
        x, cells = solid.midpoints[broken], solid.cells[broken]
        jump = np.asarray(solid.u.eval(x, cells[:, 0]) - solid.u.eval(x, cells[:, 1]))
        size = np.linalg.norm(jump.reshape(len(broken), -1), axis=1)
        k = int(np.argmax(size / solid.h[broken]))
        f = broken[k]
        where = solid.midpoints[f, : solid.gdim].copy()
        mine = (float(size[k] / solid.h[f]), where, float(size[k]))
    ratio, where, size = max(solid.comm.allgather(mine), key=lambda item: item[0])
    if ratio > LOOSE_JUMP:
        at = ", ".join(f"{v:.4g}" for v in where)
        raise ValidityLimit(
            f"at t = {t:.6g} s a broken interface at ({at}) m moved {size:.3g} m apart, "
            f"{ratio:.3g} times its cells' size: a block cut out by broken faces slides or "
            "lifts out of the rock, beyond what the small-displacement solid represents; "
            "the history up to the last step stands"
        )


__all__ = [
    "LOOSE_JUMP",
    "check_small_displacement",
    "facets_to_break",
    "most_overstressed",
    "release_debris",
    "switch_contacts",
]
