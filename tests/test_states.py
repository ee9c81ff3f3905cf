"""Interface states: initial states, breaking, contact switching, copy/restore, ghosts, stops."""

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.coupling.records import SimulationStopped
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import (
    OPEN,
    SLIP,
    STICK,
    CascadeStopped,
    InterfaceStates,
    faces_overlap,
)


def test_initial_states_cracks_open_rest_intact_and_stuck():
    s = InterfaceStates.initial(np.array([True, False, False]), 2)
    assert list(s.state) == [FacetState.TENSILE, FacetState.INTACT, FacetState.INTACT]
    assert list(s.contact) == [OPEN, STICK, STICK]
    assert s.friction_traction.shape == (3, 2) and not s.friction_traction.any()
    with pytest.raises(ValueError, match="one row per facet"):
        InterfaceStates(s.state, s.contact[:2], s.friction_traction)


def test_tensile_breaks_start_open_shear_breaks_closed():
    s = InterfaceStates.initial(np.zeros(4, dtype=bool), 3)
    s.break_facets(np.array([1, 3]), np.array([FacetState.TENSILE, FacetState.SHEAR]))
    assert list(s.state) == [0, FacetState.TENSILE, 0, FacetState.SHEAR]
    assert list(s.contact) == [STICK, OPEN, STICK, STICK]


def test_copy_is_independent_and_restore_keeps_the_arrays():
    s = InterfaceStates.initial(np.array([False, True]), 2)
    saved = s.copy()
    state_array = s.state
    s.break_facets(np.array([0]), np.array([FacetState.SHEAR]))
    s.friction_traction[0] = (1.0, 2.0)
    assert saved.state[0] == FacetState.INTACT and not saved.friction_traction.any()
    s.restore(saved)
    assert s.state is state_array  # handed-out arrays stay valid
    assert list(s.state) == list(saved.state) and not s.friction_traction.any()


def _broken(contact):
    count = len(contact)
    s = InterfaceStates(
        np.full(count, FacetState.TENSILE, dtype=np.int8),
        np.array(contact, dtype=np.int8),
        np.zeros((count, 2)),
    )
    return s, np.ones(count, dtype=bool)


def test_closed_faces_open_when_the_normal_traction_exceeds_minus_the_pressure():
    # tension positive: -5 MPa compression against 6 MPa fluid pressure opens it
    s, broken = _broken([STICK, STICK, SLIP])
    tn = np.array([-5e6, -7e6, 1e5])
    s.switch_contacts(
        broken, tn, np.zeros((3, 2)), np.array([6e6, 6e6, 0.0]), np.zeros(3, bool), 0.5
    )
    assert list(s.contact) == [OPEN, STICK, OPEN]


def test_open_faces_close_only_when_they_interpenetrate():
    s, broken = _broken([OPEN, OPEN])
    tn = np.array([-1e6, -1e6])
    s.switch_contacts(broken, tn, np.zeros((2, 2)), np.zeros(2), np.array([True, False]), 0.5)
    assert list(s.contact) == [STICK, OPEN]


def test_wet_open_faces_close_only_past_the_overlap_their_pressure_would_take():
    kn, p = 1e13, 5e6  # the springs would overlap by p / kn = 0.5 um at the fluid pressure
    gap = np.array([-0.4e-6, -0.6e-6, -1e-12, 1e-7])
    closing = faces_overlap(gap, np.array([p, p, 0.0, p]), kn)
    assert list(closing) == [False, True, True, False]
    assert faces_overlap(np.array([-1e-12]), np.array([-1e6]), kn)[0]  # suction adds no band


def _one_facet_model(closing_rule, hysteresis=False):
    """Contact states of a facet in a 1-DOF surrounding, iterated as the coupled step does.

    Separation w (spring extension from the in-situ state, opening positive) obeys
    w = d - C sigma + C T under a face compression T: spring T = sigma - kn w (stuck),
    fluid T = p (open).  Returns the states of 4 switch rounds from both starts, over
    a grid of loads d, pressures p and stiffness ratios kn C (the No. 2 chatter had
    kn C = 18, sigma = 60.25 MPa, p = 62.1 MPa).
    """
    sigma, kn = 60.25e6, 7.6e13
    d, p, knc = np.meshgrid(
        np.linspace(-2e-7, 2e-7, 21), np.linspace(50e6, 70e6, 21), [0.5, 5.0, 18.0, 200.0]
    )
    d, p, C = d.ravel(), p.ravel(), knc.ravel() / kn
    count = len(d)
    rounds = []
    for start in (OPEN, STICK):
        states = InterfaceStates(
            np.full(count, FacetState.TENSILE, np.int8),
            np.full(count, start, np.int8),
            np.zeros((count, 2)),
        )
        seen = [states.contact.copy()]
        for _ in range(4):
            stuck = states.contact != OPEN
            w = np.where(stuck, d / (1 + C * kn), d - C * sigma + C * p)
            tn = np.where(stuck, -sigma + kn * w, -p)
            gap = w - sigma / kn
            closing = closing_rule(gap, p, kn)
            states.switch_contacts(
                np.ones(count, bool), tn, np.zeros((count, 2)), p, closing, 0.6, hysteresis
            )
            seen.append(states.contact.copy())
        rounds.append(np.array(seen))
    return rounds, (d, p, C, sigma, kn)


def test_contact_switches_settle_in_one_round_on_one_quantity():
    rounds, (d, p, C, sigma, kn) = _one_facet_model(faces_overlap)
    open_ = p > sigma - kn * d / (1 + C * kn)  # the stuck state's traction is below -p
    for seen in rounds:
        assert np.all(seen[1:] == seen[1])  # one switch at most, then settled
        assert np.array_equal(seen[-1] == OPEN, open_)
    # closing on overlap alone (gap < 0) sends stiff surroundings to and fro
    chatter, _ = _one_facet_model(lambda gap, p, kn: gap < 0.0)
    flips = np.any(chatter[0][2:] != chatter[0][1:-1], axis=0)
    assert flips.any() and np.all(C[flips] * kn <= 18.0)


def test_with_hysteresis_a_closed_facet_reopens_only_past_the_pressure_it_closed_at():
    p = 62.5e6
    s, broken = _broken([OPEN, OPEN])
    none = np.zeros((2, 2))
    # facet 0's blocks press it shut; the pressure on it then is kept
    s.switch_contacts(
        broken, np.full(2, -p), none, np.full(2, p), np.array([True, False]), 0.6, True
    )
    assert list(s.contact) == [STICK, OPEN]
    assert s.shut_at[0] == p and np.isnan(s.shut_at[1])
    # closed, its springs hold less compression than the fluid: it would open again
    wants = np.array([-0.95 * p, -p])
    plain = s.copy()
    plain.switch_contacts(broken, wants, none, np.full(2, p), np.zeros(2, bool), 0.6)
    assert plain.contact[0] == OPEN and np.isnan(plain.shut_at[0])
    # with hysteresis it stays shut at the same pressure ...
    held = s.switch_contacts(broken, wants, none, np.full(2, p), np.zeros(2, bool), 0.6, True)
    assert list(s.contact) == [STICK, OPEN] and s.shut_at[0] == p
    assert list(held) == [True, False]
    # ... and opens once the pressure on it passes that one, forgetting it
    higher = np.full(2, p * (1 + 1e-9))
    held = s.switch_contacts(broken, wants, none, higher, np.zeros(2, bool), 0.6, True)
    assert not held.any()
    assert list(s.contact) == [OPEN, OPEN] and np.isnan(s.shut_at).all()
    # springs in tension open a facet whatever the pressure (a dry one: p = 0)
    s.switch_contacts(
        broken, np.array([-p, -p]), none, np.zeros(2), np.array([True, False]), 0.6, True
    )
    assert s.contact[0] == STICK and s.shut_at[0] == 0.0
    s.switch_contacts(broken, np.array([1e5, -p]), none, np.zeros(2), np.zeros(2, bool), 0.6, True)
    assert s.contact[0] == OPEN
    # a facet never closed (a shear break) opens as without hysteresis
    t, broken1 = _broken([STICK])
    t.switch_contacts(
        broken1,
        np.array([-0.95 * p]),
        np.zeros((1, 2)),
        np.array([p]),
        np.zeros(1, bool),
        0.6,
        True,
    )
    assert t.contact[0] == OPEN


def test_hysteresis_leaves_the_settled_states_of_single_facets_alone():
    plain, _ = _one_facet_model(faces_overlap)
    held, _ = _one_facet_model(faces_overlap, hysteresis=True)
    for a, b in zip(plain, held, strict=True):
        assert np.array_equal(a, b)
        assert 0 < int(np.sum(b[-1] == OPEN)) < b.shape[1]  # both states occur


def test_coulomb_decides_stick_or_slip_and_friction_opposes_nothing_else():
    # closed faces under 10 MPa normal compression, friction 0.6: limit 6 MPa
    s, broken = _broken([STICK, STICK, STICK])
    tn = np.full(3, -10e6)
    shear = np.array([[5e6, 0.0], [0.0, 8e6], [6e6, 0.0]])
    s.switch_contacts(broken, tn, shear, np.zeros(3), np.zeros(3, bool), 0.6)
    assert list(s.contact) == [STICK, SLIP, STICK]  # exactly at the limit sticks
    assert s.friction_traction[1] == pytest.approx([0.0, 6e6])
    assert not s.friction_traction[[0, 2]].any()
    # intact facets are left alone, whatever their tractions
    s.state[0] = FacetState.INTACT
    s.switch_contacts(
        ~(s.state == FacetState.INTACT), tn, 2 * shear, np.zeros(3), np.zeros(3, bool), 0.6
    )
    assert s.contact[0] == STICK and s.contact[2] == SLIP


def _square(comm):
    """A solid on a 6 x 6 unit square, every interior facet an interface, ghosted facets."""
    mesh = dolfinx.mesh.create_unit_square(
        comm, 6, 6, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    empty = np.zeros(0, dtype=np.int32)
    tags = [dolfinx.mesh.meshtags(mesh, d, empty, empty) for d in (2, 1)]
    solid = CDEMSolid(
        TaggedMesh(mesh, tags[0], tags[1], {}, {}),
        ElasticMaterial(10e9, 0.25),
        InSituStress(0.0, 0.0),
        InterfaceModel(),
    )
    return solid


def test_ghosts_take_the_owners_states_on_any_rank_count():
    comm = MPI.COMM_WORLD
    solid = _square(comm)
    # each owner breaks facets by a rule of the facet's global vertex ids; ghosts learn it
    ids = np.sort(solid.vertex_ids, axis=1)
    chosen = ids.sum(axis=1) % 3 == 0
    owned_chosen = np.flatnonzero(chosen & solid.owned)
    solid.break_facets(owned_chosen, np.full(len(owned_chosen), FacetState.SHEAR), 0.0)
    solid.states.shut_at[owned_chosen] = ids[owned_chosen].sum(axis=1) * 1e6
    solid.sync_ghost_states()
    assert np.array_equal(solid.state == FacetState.SHEAR, chosen)
    assert np.array_equal(solid.states.shut_at[chosen], ids[chosen].sum(axis=1) * 1e6)
    assert np.isnan(solid.states.shut_at[~chosen]).all()
    total = comm.allreduce(int(np.sum(chosen & solid.owned)), op=MPI.SUM)
    serial_ids = None
    if comm.rank == 0:
        m1 = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 6, 6)
        m1.topology.create_entities(1)
        m1.topology.create_connectivity(1, 2)
        f2c = m1.topology.connectivity(1, 2)
        interior = np.flatnonzero(np.diff(f2c.offsets) == 2)
        v = dolfinx.mesh.entities_to_geometry(m1, 1, interior.astype(np.int32), False)
        serial_ids = np.asarray(m1.geometry.input_global_indices)[v]
    serial_ids = comm.bcast(serial_ids, root=0)
    assert total == int(np.sum(serial_ids.sum(axis=1) % 3 == 0)) > 0


def test_a_cascade_stop_names_its_load_and_counts_and_stops_a_coupled_run_too():
    stop = CascadeStopped(2.5e6, 3, 7, first_break=2e6)
    # the coupled run catches SimulationStopped: a cascade stop ends it cleanly as well
    assert isinstance(stop, SimulationStopped)
    assert (stop.load_factor, stop.broken, stop.iterations, stop.first_break) == (2.5e6, 3, 7, 2e6)
    text = str(stop)
    assert "did not settle in 7 iterations at load factor 2.5e+06" in text
    assert "3 facets broke in the cascade, first break at 2e+06" in text
    assert "first break" not in str(CascadeStopped(1.0, 0, 1))


def _closings_kept(comm):
    """Break one set, record closings, break a second set; the facets still holding a closing."""
    solid = _square(comm)
    ids = np.sort(solid.vertex_ids, axis=1)
    key = ids.sum(axis=1)
    first = np.flatnonzero((key % 3 == 0) & solid.owned)
    solid.break_facets(first, np.full(len(first), FacetState.SHEAR), 0.0)
    solid.states.shut_at[first] = 1e6
    solid.sync_ghost_states()
    second = np.flatnonzero((key % 7 == 1) & (solid.state == FacetState.INTACT) & solid.owned)
    solid.break_facets(second, np.full(len(second), FacetState.TENSILE), 1.0)
    kept = solid.owned & np.isfinite(solid.states.shut_at)
    if comm.size == 1:  # every facet of every cell is here: the rule by hand
        assert np.array_equal(kept, (key % 3 == 0) & ~_near(solid, key))
    closed = comm.allreduce(len(first), op=MPI.SUM)
    return sorted(comm.allreduce([tuple(r) for r in ids[kept]], op=MPI.SUM)), closed


def _near(solid, key):
    """Local facets sharing a local cell with a facet of the second set (key % 7 == 1)."""
    cells = solid.interface_facets.cells
    new = (key % 7 == 1) & (solid.state == FacetState.TENSILE)
    touched = np.zeros(cells.max() + 1, dtype=bool)
    touched[cells[new].reshape(-1)] = True
    return touched[cells].any(axis=1)


def test_a_break_forgets_where_the_facets_of_its_cells_closed_on_any_rank_count():
    comm = MPI.COMM_WORLD
    kept, closed = _closings_kept(comm)
    serial = _closings_kept(MPI.COMM_SELF) if comm.rank == 0 else None
    serial = comm.bcast(serial, root=0)
    # some closings forgotten, some kept, the same ones on any rank count
    assert (kept, closed) == serial
    assert 0 < len(kept) < closed
