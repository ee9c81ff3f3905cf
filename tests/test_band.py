"""The band of free interfaces of the reduced solid: recovered tractions, rings, the reference."""

import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import unit_block

from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.solid.band import InterfaceBand
from hfcdem.solid.cdem import CDEMSolid, Loads

MPa = 1e6
comm = MPI.COMM_WORLD


def allsum(value):
    return comm.allreduce(int(value), op=MPI.SUM)


def block_solid(dim=2, band=(0.3, 2), tmesh=None):
    """A reduced solid with springs on every facet; rollers on the left (x) and bottom (y)."""
    return CDEMSolid(
        unit_block(dim) if tmesh is None else tmesh,
        ElasticMaterial(30e9, 0.25),
        InSituStress(8 * MPa, 5 * MPa, 6 * MPa),
        InterfaceModel(alpha=100, tensile_strength=1e3 * MPa, cohesion=1e3 * MPa),
        rollers={"left": 0, "bottom": 1},
        mode="reduced",
        band=band,
    )


@pytest.mark.parametrize("dim", [2, 3])
def test_recovered_traction_is_exact_in_a_uniform_stress(dim):
    # pressure p on the right of a block on rollers: sigma = diag(-p, S0yy, ...) everywhere
    solid = block_solid(dim)
    p = 12 * MPa
    loads = Loads(cavity={"right": p})
    solid.solve(loads)
    assert solid.band.count() == 0  # every interface glued: continuous P1 elasticity
    total = solid.sigma0.copy()
    total[0, 0] = -p
    n = solid.normals
    t = n @ total.T
    tn = np.einsum("fi,fi->f", t, n)
    tau = np.linalg.norm(t - tn[:, None] * n, axis=1)
    snap = solid.snapshot(loads)
    assert np.allclose(snap.normal_traction, tn, rtol=0, atol=1e-8 * p)
    assert np.allclose(snap.shear_traction, tau, rtol=0, atol=1e-8 * p)
    scale = comm.allreduce(float(np.abs(solid.u.x.array).max(initial=0.0)), op=MPI.MAX)
    assert np.all(np.abs(snap.opening) < 1e-12 * scale)  # no jump across glued facets


def _vertex_ids_of(solid, flags):
    """Global input ids of the vertices of the owned ``flags`` facets, on every rank."""
    return np.unique(np.concatenate(comm.allgather(solid.vertex_ids[flags & solid.owned].ravel())))


def _touching(solid, ids):
    return np.isin(solid.vertex_ids, ids).any(axis=1)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_freed_facet_brings_its_vertex_rings_on_any_number_of_ranks(dim):
    # one mesh for every solid below: a new mesh may be partitioned differently
    tmesh = unit_block(dim)
    solid = block_solid(dim, tmesh=tmesh)
    # the interface nearest a point inside the block, found on whichever rank owns it
    d = np.linalg.norm(solid.midpoints - [0.52, 0.47, 0.41 if dim == 3 else 0.0], axis=1)
    d = np.where(solid.owned, d, np.inf)
    nearest = comm.allreduce(float(d.min(initial=np.inf)), op=MPI.MIN)
    seed = solid.owned & (d == nearest)
    assert allsum(np.count_nonzero(seed)) == 1
    ring1 = _touching(solid, _vertex_ids_of(solid, seed))
    ring2 = _touching(solid, _vertex_ids_of(solid, ring1))
    assert allsum(np.count_nonzero(ring1 & solid.owned)) < allsum(
        np.count_nonzero(ring2 & solid.owned)
    )
    # the seed facet on every rank that holds it (its owner and its ghosts)
    where = np.concatenate(comm.allgather(solid.midpoints[seed]))
    ring0 = np.isclose(solid.midpoints, where[0], rtol=0, atol=1e-12).all(axis=1)
    for rings, expected in ((0, ring0), (1, ring1), (2, ring2)):
        fresh = block_solid(dim, tmesh=tmesh)
        freed = fresh.free_interfaces(seed, rings=rings)
        assert freed == allsum(np.count_nonzero(expected & solid.owned))
        assert fresh.band.count() == freed
        assert np.array_equal(fresh.band.free, expected)  # owners and ghosts agree
    # freeing again frees nothing, and the band never shrinks
    assert fresh.free_interfaces(seed, rings=2) == 0


def test_the_band_only_grows_and_counts_its_versions():
    solid = block_solid(2)
    band = solid.band
    assert isinstance(band, InterfaceBand) and band.version == 0
    everything = np.ones(solid.num_facets, dtype=bool)
    solid.free_interfaces(everything)
    assert band.version == 1 and band.count() == allsum(np.count_nonzero(solid.owned))
    solid.free_interfaces(everything)
    assert band.version == 1


def test_a_glued_facet_is_freed_before_it_can_break():
    # a uniform tension near the strength: the recovered traction frees every facet past
    # the threshold; none breaks while glued
    solid = CDEMSolid(
        unit_block(2),
        ElasticMaterial(30e9, 0.25),
        InSituStress(0.0, 0.0),
        InterfaceModel(alpha=100, tensile_strength=10 * MPa, cohesion=100 * MPa),
        rollers={"left": 0, "bottom": 1},
        mode="reduced",
        band=(0.5, 0),
    )
    loads = Loads(cavity={"right": -6 * MPa})  # sigma_xx = 6 MPa: 0.6 of the strength
    solid.solve(loads)
    ratio, _ = solid.overstress(loads)
    assert comm.allreduce(float(ratio.max(initial=0.0)), op=MPI.MAX) == 0.0  # all glued
    freed = solid.grow_band(loads)
    # the facets whose normal has n_x^2 >= 0.5 / 0.6 carry the tension past the threshold
    nx2 = solid.normals[:, 0] ** 2
    assert freed == allsum(np.count_nonzero(solid.owned & (nx2 >= 0.5 / 0.6 - 1e-12)))
    assert solid.grow_band(loads) == 0  # settled at this load
    solid.solve(loads)
    ratio, _ = solid.overstress(loads)
    worst = comm.allreduce(float(ratio.max(initial=0.0)), op=MPI.MAX)
    assert worst == pytest.approx(0.6, rel=1e-8)  # the free springs carry the stress exactly


def test_full_mode_keeps_every_interface_free_and_reduced_needs_dg1():
    solid = CDEMSolid(
        unit_block(2),
        ElasticMaterial(30e9, 0.25),
        InSituStress(0.0, 0.0),
        InterfaceModel(),
        rollers={"left": 0, "bottom": 1},
    )
    assert solid.mode == "full" and solid.band.free.all()
    assert solid.grow_band(Loads()) == 0
    assert solid.free_interfaces(np.ones(solid.num_facets, dtype=bool)) == 0
    with pytest.raises(ValueError, match="reduced mode needs DG1"):
        CDEMSolid(
            unit_block(2),
            ElasticMaterial(30e9, 0.25),
            InSituStress(0, 0),
            InterfaceModel(),
            degree=2,
            mode="reduced",
        )
    with pytest.raises(ValueError, match="mode must be one of"):
        CDEMSolid(
            unit_block(2),
            ElasticMaterial(30e9, 0.25),
            InSituStress(0, 0),
            InterfaceModel(),
            mode="partial",
        )
    with pytest.raises(ValueError, match="band threshold"):
        block_solid(2, band=(0.0, 1))
    with pytest.raises(ValueError, match="ramp\\(\\) needs mode='full'"):
        block_solid(2).ramp(Loads(), Loads(cavity={"right": 1.0}, in_situ_factor=0.0), 1e6)
