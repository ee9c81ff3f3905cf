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


def _largest_jump_over_size(solid) -> float:
    crack = crack_facets(solid)
    crack = crack[solid.state[crack] != 0]
    if not crack.size:  # this rank holds none of the crack
        return solid.comm.allreduce(0.0, op=MPI.MAX)
    x, cells = solid.midpoints[crack], solid.cells[crack]
    jump = np.asarray(solid.u.eval(x, cells[:, 0]) - solid.u.eval(x, cells[:, 1]))
    ratio = np.linalg.norm(jump.reshape(len(crack), -1), axis=1) / solid.h[crack]
    return solid.comm.allreduce(float(ratio.max(initial=0.0)), op=MPI.MAX)


def test_a_block_cut_loose_is_the_models_validity_limit():
    """Half the crack broken: an elastic opening; all of it: the left half is loose."""
    import pytest

    from hfcdem.coupling import events
    from hfcdem.solvers import ValidityLimit

    loads = Loads(crack_pressure=5e6)
    half = tiny_solid()
    lower = crack_facets(half)
    lower = lower[half.owned[lower] & (half.midpoints[lower, 1] < 0.5)]
    half.break_facets(lower, np.ones(len(lower), dtype=np.int8), 0.0)
    half.solve(loads)
    held = _largest_jump_over_size(half)
    assert 0.0 < held < 2e-3 * events.LOOSE_JUMP  # measured 1.01e-3
    events.check_small_displacement(half, 1.0)  # quiet

    loose = tiny_solid()  # x = 1 broken top to bottom: only residual springs hold x < 1
    break_crack(loose)
    loose.solve(loads)
    assert _largest_jump_over_size(loose) > 1e3 * events.LOOSE_JUMP  # measured 4.0e4
    with pytest.raises(ValidityLimit, match=r"at t = 2 s a broken interface at .* moved"):
        events.check_small_displacement(loose, 2.0)
