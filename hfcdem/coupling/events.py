"""Interface events within a coupled step: contact switches (chatter cut off) and breaks.

The coupled problem repeats a step until the interface states settle; these
functions change the solid's states and say how many changed (global counts),
and the problem recondenses when any did.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads
from hfcdem.solid.interfaces import select_breaking
from hfcdem.solid.states import OPEN


def switch_contacts(solid: CDEMSolid, loads: Loads, only_closing: bool) -> int:
    """Switch contacts at ``loads``; return the global number switched (0: settled).

    ``only_closing``: switches that open a face are undone (the opening waits
    for the next step).  The coupled step sets it after one round of switches,
    which cuts off contact chatter (a facet that keeps opening and closing under
    the same pressure), so the loop ends, and no face is left open while its
    blocks interpenetrate (an open face has only the residual stiffness: a block
    it frees would fly).  (Two free rounds cost No. 2 coarse 34 more rebuilds for
    the same breakdown to 10 digits.)  Ghost states follow their owners.
    """
    saved = solid.states.copy()
    switched = solid.update_contact(loads)
    if switched and only_closing:
        keep = ~((saved.contact == OPEN) & (solid.contact != OPEN))
        solid.contact[keep] = saved.contact[keep]
        solid.friction_traction[keep] = saved.friction_traction[keep]
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


__all__ = ["facets_to_break", "switch_contacts"]
