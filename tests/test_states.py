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
from hfcdem.solid.states import OPEN, SLIP, STICK, CascadeStopped, InterfaceStates


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


def test_ghosts_take_the_owners_states_on_any_rank_count():
    comm = MPI.COMM_WORLD
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
    # each owner breaks facets by a rule of the facet's global vertex ids; ghosts learn it
    ids = np.sort(solid.vertex_ids, axis=1)
    chosen = ids.sum(axis=1) % 3 == 0
    owned_chosen = np.flatnonzero(chosen & solid.owned)
    solid.break_facets(owned_chosen, np.full(len(owned_chosen), FacetState.SHEAR), 0.0)
    solid.sync_ghost_states()
    assert np.array_equal(solid.state == FacetState.SHEAR, chosen)
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
