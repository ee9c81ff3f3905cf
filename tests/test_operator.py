"""The kept stiffness: updated where interfaces changed, it equals the one assembled afresh."""

import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import unit_block

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.solid.cdem import CDEMSolid, Loads
from hfcdem.solid.states import OPEN, SLIP, STICK

MPa = 1e6
comm = MPI.COMM_WORLD


def block(mode, tmesh=None, low_rank_columns=0):
    """A small solid; by default every event refactorises (no low-rank correction)."""
    return CDEMSolid(
        unit_block(2) if tmesh is None else tmesh,
        ElasticMaterial(30e9, 0.25),
        InSituStress(8 * MPa, 5 * MPa),
        InterfaceModel(alpha=100, residual_stiffness=1e-3),
        rollers={"left": 0, "bottom": 1},
        mode=mode,
        petsc_options={"low_rank_columns": low_rank_columns},
    )


def fresh_matrix(solid):
    """The solved matrix assembled from nothing for the current states."""
    _, A = solid.assemble_stiffness()
    if solid.mode == "reduced":
        A_dg, A = A, solid.reduced_system().reduce(A, 1.0)
        A_dg.destroy()
    return A


def difference(solid):
    _, ksp = solid.factorize()
    kept = ksp.getOperators()[0]
    ref = fresh_matrix(solid)
    scale = ref.norm()
    ref.axpy(-1.0, kept)
    diff = ref.norm() / scale
    ref.destroy()
    return diff


def some_interfaces(solid, count, seed):
    """``count`` owned interfaces picked by position, the same on any number of ranks."""
    key = np.round(solid.midpoints @ np.array([1.0, 0.37, 0.11]), 9)
    chosen = np.zeros(solid.num_facets, dtype=bool)
    order = np.unique(np.concatenate(comm.allgather(key[solid.owned])))
    picks = np.random.default_rng(seed).choice(order, count, replace=False)
    chosen[np.isin(key, picks) & solid.owned] = True
    return np.flatnonzero(chosen)


@pytest.mark.parametrize("mode", ["full", "reduced"])
def test_updates_equal_a_fresh_assembly_through_breaks_and_contact_switches(mode):
    solid = block(mode)
    everything = np.ones(solid.num_facets, dtype=bool)
    solid.free_interfaces(everything)  # reduced: one structure for the whole test
    assert difference(solid) == 0.0  # assembled afresh
    counts = {"assembled": 1, "updated": 0, "unchanged": 0, "low_rank": 0, "columns": 0}
    assert solid.operator.counts == counts
    for step, contact in enumerate((OPEN, STICK, SLIP, OPEN)):
        chosen = some_interfaces(solid, 6, step)
        solid.break_facets(chosen, np.ones(len(chosen), dtype=np.int8), 0.0)
        solid.states.contact[chosen] = contact
        solid.sync_ghost_states()
        assert difference(solid) < 1e-14
    assert solid.operator.counts["updated"] == 4
    assert solid.operator.counts["assembled"] == 1
    # nothing changed: the same factorisation
    solid.factorize()
    assert solid.operator.counts["unchanged"] >= 1


def test_a_new_band_or_the_refresh_count_assembles_afresh():
    solid = block("reduced")
    solid.factorize()
    solid.free_interfaces(np.ones(solid.num_facets, dtype=bool))
    solid.factorize()
    assert solid.operator.counts["assembled"] == 2
    solid.operator.refresh_every = 1
    for step in range(2):
        chosen = some_interfaces(solid, 2, 10 + step)
        solid.break_facets(chosen, np.ones(len(chosen), dtype=np.int8), 0.0)
        solid.factorize()
    assert solid.operator.counts["updated"] == 1  # then the refresh
    assert solid.operator.counts["assembled"] == 3


@pytest.mark.parametrize("mode", ["full", "reduced"])
def test_a_solve_after_updates_equals_a_fresh_solid(mode):
    loads = Loads(cavity={"right": 3 * MPa}, crack_pressure=12 * MPa)
    tmesh = unit_block(2)  # one mesh: a new one may be partitioned differently
    kept, fresh = block(mode, tmesh), block(mode, tmesh)
    kept.solve(loads)  # assembled with every interface intact
    for solid in (kept, fresh):
        chosen = some_interfaces(solid, 8, 3)
        solid.break_facets(chosen, np.ones(len(chosen), dtype=np.int8), 0.0)
    kept.solve(loads)  # updated: the broken facets open under the crack pressure
    fresh.solve(loads)
    assert kept.operator.counts["updated"] == (1 if mode == "full" else 0)
    scale = comm.allreduce(float(np.abs(fresh.u.x.array).max()), op=MPI.MAX)
    diff = comm.allreduce(float(np.abs(kept.u.x.array - fresh.u.x.array).max()), op=MPI.MAX)
    assert diff < 1e-12 * scale
    opened = kept.snapshot(loads).opening[kept.states.state > 0]
    assert comm.allreduce(int(np.count_nonzero(opened > 0)), op=MPI.SUM) > 0
