"""checkpoint.json content: the fluid tables and interface rows read back exactly."""

import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import break_crack, crack_facets, tiny_solid

from hfcdem.coupling.checkpoint import (
    SCALARS,
    band_rows,
    checkpoint_data,
    fluid_from_tables,
    fluid_tables,
    interface_rows,
    read_checkpoint,
)
from hfcdem.coupling.fluidstate import FluidState


def _fluid():
    state = FluidState()
    state.store([(3, 4), (1, 2)], np.array([1e-4, 0.1 / 3]), np.array([math.inf, 2.5]), np.ones(2))
    return state


def test_fluid_tables_are_sorted_json_and_read_back_exactly():
    tables = fluid_tables(_fluid())
    assert tables["content"] == [[[1, 2], 0.1 / 3], [[3, 4], 1e-4]]
    assert tables["wet_since"] == [[[1, 2], 2.5], [[3, 4], None]]  # never wet: null
    back = fluid_from_tables(json.loads(json.dumps(tables)))
    assert back == _fluid()


def test_a_missing_table_is_named():
    tables = fluid_tables(_fluid())
    del tables["pressure"]
    with pytest.raises(KeyError, match="pressure"):
        fluid_from_tables(tables)


def test_the_checkpoint_layout():
    assert SCALARS[0] == "t" and "_last_ratio" in SCALARS and len(SCALARS) == 13
    assert "first_break_pressure" in SCALARS  # the first crack's upper bound survives a resume
    solid = tiny_solid()
    data = checkpoint_data({"t": 1.0}, solid, _fluid())
    assert list(data) == ["scalars", "interfaces", "band", "content", "wet_since", "pressure"]
    assert data["scalars"] == {"t": 1.0} and data["interfaces"] == []
    assert data["band"] == []  # the full solid: every interface free, nothing to keep


def test_interfaces_round_trip_through_a_fresh_solid():
    broken = tiny_solid()
    break_crack(broken)
    rows = interface_rows(broken)
    assert len(rows) == 2 and all(r[1] == 1 for r in rows)  # the same list on every rank
    data = json.loads(json.dumps(checkpoint_data({"t": 2.0}, broken, _fluid())))
    fresh = tiny_solid(MPI.COMM_SELF)  # another partition: keys are global vertex ids
    scalars, fluid = read_checkpoint(data, fresh)
    assert scalars == {"t": 2.0} and fluid == _fluid()
    crack = crack_facets(fresh)
    assert fresh.state[crack].tolist() == [1, 1]
    assert int(np.sum(fresh.state != 0)) == 2
    assert interface_rows(fresh) == rows
    assert not fresh.released.any()


def test_debris_faces_stay_released_through_a_checkpoint():
    broken = tiny_solid()
    break_crack(broken)
    broken.release_facets(crack_facets(broken))
    data = json.loads(json.dumps(checkpoint_data({"t": 2.0}, broken, _fluid())))
    assert all(row[4] is True for row in data["interfaces"])
    fresh = tiny_solid(MPI.COMM_SELF)
    read_checkpoint(data, fresh)
    assert fresh.released[crack_facets(fresh)].tolist() == [True, True]
    assert int(np.count_nonzero(fresh.released)) == 2
    # a checkpoint from before the release flag (four items per row) reads as not released
    data["interfaces"] = [row[:4] for row in data["interfaces"]]
    older = tiny_solid(MPI.COMM_SELF)
    read_checkpoint(data, older)
    assert int(np.sum(older.state != 0)) == 2 and not older.released.any()


def test_the_pressure_a_facet_closed_at_goes_through_a_checkpoint():
    broken = tiny_solid()
    break_crack(broken)

    # a pressure made of the facet's global vertex ids: the same facet, the same value
    def made_up(solid, facets):
        ids = np.sort(solid.vertex_ids[facets], axis=1)
        return 61e6 + 1e3 * ids @ (10.0 ** np.arange(ids.shape[1]))

    crack = crack_facets(broken)
    broken.states.shut_at[crack] = made_up(broken, crack)
    data = json.loads(json.dumps(checkpoint_data({"t": 2.0}, broken, _fluid())))
    assert all(row[5] > 61e6 for row in data["interfaces"]) and len(data["interfaces"]) == 2
    fresh = tiny_solid(MPI.COMM_SELF)
    read_checkpoint(data, fresh)
    crack = crack_facets(fresh)
    assert np.array_equal(fresh.states.shut_at[crack], made_up(fresh, crack))
    assert int(np.count_nonzero(np.isfinite(fresh.states.shut_at))) == 2
    # a checkpoint from before the shut pressure (five items per row) reads as never closed
    data["interfaces"] = [row[:5] for row in data["interfaces"]]
    older = tiny_solid(MPI.COMM_SELF)
    read_checkpoint(data, older)
    assert int(np.sum(older.state != 0)) == 2 and np.isnan(older.states.shut_at).all()


def test_the_reduced_band_round_trips_through_a_fresh_solid():
    broken = tiny_solid(mode="reduced")
    break_crack(broken)  # frees the crack and two vertex rings around it
    rows = band_rows(broken)
    assert len(rows) == broken.band.count() > 2
    data = json.loads(json.dumps(checkpoint_data({"t": 2.0}, broken, _fluid())))
    fresh = tiny_solid(MPI.COMM_SELF, mode="reduced")
    assert fresh.band.count() == 0
    read_checkpoint(data, fresh)
    assert band_rows(fresh) == rows
    older = {k: v for k, v in data.items() if k != "band"}  # a checkpoint of before
    read_checkpoint(older, tiny_solid(MPI.COMM_SELF, mode="reduced"))
