"""Interface events: contact switches with chatter cut off, and the facets picked to break."""

import numpy as np
from mpi4py import MPI
from tiny_solid import break_crack, crack_facets, tiny_solid

from hfcdem.coupling.events import facets_to_break, switch_contacts
from hfcdem.solid.forms import Loads
from hfcdem.solid.states import OPEN


def _open_crack_under_compression():
    solid = tiny_solid(stress=5e6)
    break_crack(solid)
    solid.solve(Loads())  # the in-situ stress presses the open crack shut
    return solid


def test_a_closing_switch_is_kept_and_synced():
    solid = _open_crack_under_compression()
    crack = crack_facets(solid)
    assert np.all(solid.contact[crack] == OPEN)
    switched = switch_contacts(solid, Loads(), only_closing=True)
    assert switched == 2
    assert not np.any(solid.contact[crack] == OPEN)  # ghosts follow their owners
    assert switch_contacts(solid, Loads(), only_closing=True) == 0


def test_openings_wait_when_only_closings_are_allowed():
    solid = _open_crack_under_compression()
    switch_contacts(solid, Loads(), only_closing=False)
    crack = crack_facets(solid)
    closed = solid.contact[crack].copy()
    # a high crack pressure would open the crack again: held back after the first round
    loads = Loads(crack_pressure=50e6)
    solid.solve(loads)
    assert switch_contacts(solid, loads, only_closing=True) == 0
    assert np.array_equal(solid.contact[crack], closed)
    assert switch_contacts(solid, loads, only_closing=False) == 2


def test_the_cap_picks_the_most_overstressed():
    solid = tiny_solid()
    ratio = np.where(solid.owned, 0.5, 0.0)
    crack = crack_facets(solid)
    ratio[crack] = np.where(solid.owned[crack], [2.0, 3.0][: len(crack)], 0.0)
    chosen = facets_to_break(solid, ratio, cap=1)
    picked = solid.comm.allgather([tuple(solid.midpoints[i]) for i in chosen])
    flat = [m for part in picked for m in part]
    assert len(flat) == 1 and np.isclose(flat[0][0], 1.0)
    wide = facets_to_break(solid, ratio, cap=5)  # only the two over 1 qualify
    assert solid.comm.allreduce(len(wide), op=MPI.SUM) == 2
    assert solid.model.break_rule == "most_overstressed"
    rule = facets_to_break(solid, ratio, cap=None)  # the model's rule: the worst alone
    assert solid.comm.allreduce(len(rule), op=MPI.SUM) == 1
