"""The network of broken facets, its pressure groups and the wet joints beside it."""

import numpy as np
from mpi4py import MPI
from tiny_solid import break_crack, crack_facets, tiny_solid

from hfcdem.coupling.condense import cavity_vertices
from hfcdem.coupling.groups import (
    group_count,
    local_network,
    near_fluid,
    pressure_groups,
    wall_joints,
)
from hfcdem.coupling.settings import FlowSettings


def test_groups_per_facet_or_one_with_the_cavity():
    wet = np.array([True, False, True, True])
    assert pressure_groups(wet, uniform=False).tolist() == [1, -1, 2, 3]
    assert pressure_groups(wet, uniform=True).tolist() == [0, -1, 0, 0]
    assert group_count(np.array([1, -1, 2, 3])) == 4
    assert group_count(np.array([0, -1])) == 1
    assert group_count(np.zeros(0, dtype=np.int64)) == 1


def test_the_network_of_the_broken_crack():
    solid = tiny_solid()
    empty = local_network(solid, np.zeros(0, dtype=np.int64))
    assert empty.net.size == 0 and empty.keys == []
    break_crack(solid)
    network = local_network(solid, np.zeros(0, dtype=np.int64))
    assert network.net.size == 2
    assert network.is_open.tolist() == [True, True]  # tensile breaks start open
    assert network.joined.tolist() == [False, False]  # no cavity vertex on x = 1
    # every local crack facet (owned or ghost) is found at its key's place
    view = network.view
    assert sorted(view.facets.tolist()) == sorted(crack_facets(solid).tolist())
    for f, pos in zip(view.facets, view.positions, strict=True):
        assert tuple(sorted(int(v) for v in solid.vertex_ids[f])) == network.keys[pos]
    owned = solid.comm.allreduce(int(view.owned.sum()), op=MPI.SUM)
    assert owned == 2


def test_wall_joints_and_their_permeation_along_the_open_crack():
    solid = tiny_solid()
    walls = cavity_vertices(solid, ("left",), None)
    dry = FlowSettings(cavity=("left",))
    assert not wall_joints(solid, dry, walls).any()
    wet = FlowSettings(cavity=("left",), wet_wall_joints=True)
    at_wall = wall_joints(solid, wet, walls)
    x = solid.vertex_coords[:, :, 0]
    assert np.all(np.isclose(x[at_wall].min(axis=1), 0.0))
    break_crack(solid)
    network = local_network(solid, walls)
    perm = FlowSettings(cavity=("left",), wet_wall_joints=True, permeate_joints=True)
    along = wall_joints(solid, perm, walls, network, np.array([0, 0]))
    assert np.all(along[at_wall]) and along.sum() > at_wall.sum()
    assert not np.any(along & solid.is_crack)
    # joints touching the crack's vertices (x = 1) join the wall joints
    assert np.all(np.isclose(x[along & ~at_wall], 1.0).any(axis=1))
    not_feeding = wall_joints(solid, perm, walls, network, np.array([1, 2]))
    assert np.array_equal(not_feeding, at_wall)


def test_interfaces_near_fluid_share_a_vertex_with_it():
    solid = tiny_solid()
    break_crack(solid)
    network = local_network(solid, np.zeros(0, dtype=np.int64))
    none = near_fluid(solid, network.net, np.zeros(2, dtype=bool), np.zeros(0, np.int64))
    assert not none.any()
    near = near_fluid(solid, network.net, np.array([True, True]), np.zeros(0, np.int64))
    x = solid.vertex_coords[:, :, 0]
    assert np.array_equal(near, np.isclose(x, 1.0).any(axis=1))
