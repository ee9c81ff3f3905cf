"""Output fields of the coupled run on hand-made network arrays and the tiny solid."""

import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import break_crack, tiny_solid

from hfcdem.coupling.fields import (
    apertures,
    facet_fields,
    interface_fields,
    opening_at_cavity,
    saturation,
    wet_extent,
)
from hfcdem.coupling.groups import local_network
from hfcdem.flow.network import build_network
from hfcdem.solid.forms import Loads


def _line(n=3):
    # facets [i, i+1] along x, 1 m long; vertex 0 is the injection point
    keys = np.array([[i, i + 1] for i in range(n)])
    coords = np.array([[[i, 0, 0], [i + 1, 0, 0]] for i in range(n)], dtype=float)
    net, _ = build_network(MPI.COMM_SELF, keys, np.ones(n), coords, np.array([0]))
    return net


def test_saturation_and_apertures():
    sat = saturation(np.array([True, False, False]), np.array([0.0, 1.0, 3.0]), np.full(3, 2.0))
    assert sat.tolist() == [1.0, 0.5, 1.0]  # wet: 1; dry: content / volume, at most 1
    wet = np.array([True, True, True])
    lagging = saturation(wet, np.array([2.2, 1.5, 0.0]), np.array([2.0, 2.0, 0.0]), lag=True)
    assert lagging.tolist() == [1.0, 0.75, 1.0]  # full; behind its opening; closed counts as full
    w = apertures(np.array([2e-3, 0.5e-3, -1e-3]), np.array([1.0, 1.0, 1.0]), 1e-3)
    assert w == pytest.approx([2e-3, 1e-3, 1e-3])  # never below the residual aperture


def test_the_front_reaches_into_the_partly_filled_facet_ahead():
    net = _line()
    wet = np.array([True, False, False])
    sat = np.array([1.0, 0.5, 0.0])
    assert wet_extent(net, wet, sat, (0.0, 0.0), (1.0, 0.0)) == pytest.approx(1.5)
    assert wet_extent(net, wet, sat, (0.5, 0.0), (2.0, 0.0)) == pytest.approx(1.0)
    assert wet_extent(net, np.zeros(3, dtype=bool), sat, (0.0, 0.0), (1.0, 0.0)) == 0.0


def test_the_opening_at_the_cavity_is_of_the_touching_facets():
    net = _line()
    assert net.touches_cavity.tolist() == [True, False, False]
    assert opening_at_cavity(np.array([3e-3, 1.0, 1.0]), net) == pytest.approx(3e-3)


def test_fields_of_the_tiny_solid_cover_every_owned_interface():
    solid = tiny_solid()
    break_crack(solid)
    network = local_network(solid, np.zeros(0, dtype=np.int64))
    pressure, aperture, sat = np.array([1e6, 2e6]), np.array([1e-4, 2e-4]), np.array([1.0, 0.5])
    pts, data = facet_fields(solid, network.view, pressure, aperture, sat, network.is_open)
    total = solid.comm.allreduce(len(pts), op=MPI.SUM)
    assert total == 2  # each crack facet once, on its owner
    assert set(data["fluid_pressure_MPa"]) <= {1.0, 2.0}
    assert np.all(data["state"] == 1.0) and np.all(data["open"] == 1.0)
    solid.solve(Loads())
    pts, data = interface_fields(solid, Loads(), network.view, pressure, aperture, sat)
    owned = int(np.sum(solid.owned))
    assert len(pts) == owned and all(len(v) == owned for v in data.values())
    seen = solid.comm.allreduce(float(np.sum(data["fluid_pressure_MPa"])), op=MPI.SUM)
    assert seen == pytest.approx(3.0)  # 1 + 2 MPa, zero on the intact interfaces
    assert solid.comm.allreduce(int(np.sum(data["state"] > 0)), op=MPI.SUM) == 2
    assert not np.any(data["joint_pressure_MPa"])  # no joint pressure in the loads
    # pressure inside intact joints (e.g. permeated wall joints) comes from the loads
    intact = solid.state == 0
    joints = np.where(intact, 3e6, 0.0)
    loads = Loads(joint_pressure=joints)
    solid.solve(loads)
    _, data = interface_fields(solid, loads, network.view, pressure, aperture, sat)
    assert np.array_equal(data["joint_pressure_MPa"], joints[solid.owned] / 1e6)
    held = solid.comm.allreduce(int(np.sum(data["joint_pressure_MPa"] == 3.0)), op=MPI.SUM)
    assert held == solid.comm.allreduce(int(np.sum(intact & solid.owned)), op=MPI.SUM) > 0
