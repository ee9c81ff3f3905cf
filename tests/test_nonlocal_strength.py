"""The stress filtered over a material length (``rock.strength_length``)."""

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.analytic import filtered_wall_breakdown
from hfcdem.config.materials import ElasticMaterial
from hfcdem.config.scene import load_scene
from hfcdem.config.tables import SceneError
from hfcdem.solid.nonlocal_strength import StressFilter
from hfcdem.workflows.run import run_scene

BOREHOLE = "meshes/scenes/borehole_plate.toml"
MATERIAL = ElasticMaterial(20e9, 0.25)
LAM2MU = MATERIAL.lame_lambda + 2.0 * MATERIAL.shear_modulus


def _interior(mesh):
    """Interior facets owned or ghosted here, and a cell beside each."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    imap = mesh.topology.index_map(tdim - 1)
    facets = np.array(
        [f for f in range(imap.size_local + imap.num_ghosts) if len(f2c.links(f)) == 2],
        dtype=np.int32,
    )
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
    mids = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, facets)
    return facets, cells, mids


def _filtered(nx, length, field, comm=MPI.COMM_WORLD):
    """Filter the stress of the DG1 displacement ``field`` on a 1 x 0.2 strip."""
    mesh = dolfinx.mesh.create_rectangle(
        comm, [[0.0, 0.0], [1.0, 0.2]], [nx, max(2, nx // 5)],
        ghost_mode=dolfinx.mesh.GhostMode.shared_facet,
    )  # fmt: skip
    u = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("DG", 1, (2,))))
    u.interpolate(field)
    facets, cells, mids = _interior(mesh)
    filt = StressFilter(u, MATERIAL, facets, cells, length)
    out = filt.midpoint_stress()
    filt.destroy()
    return out, mids


def _boundary_layer(x, length, slope):
    """Solve s - l^2 s'' = slope x on [0, 1], s' = 0 at both ends (closed form)."""
    e = np.exp(1.0 / length)
    # s = slope x + C1 exp(x / l) + C2 exp(-x / l); s'(0) = s'(1) = 0
    m = np.array([[1.0, -1.0], [e, -1.0 / e]]) / length
    c1, c2 = np.linalg.solve(m, [-slope, -slope])
    return slope * x + c1 * np.exp(x / length) + c2 * np.exp(-x / length)


@pytest.mark.parametrize("comm", [MPI.COMM_WORLD, MPI.COMM_SELF], ids=["world", "self"])
def test_a_uniform_stress_passes_the_filter_unchanged(comm):
    strain = np.array([[2e-4, 5e-5], [5e-5, -1e-4]])
    out, _ = _filtered(8, 0.05, lambda x: strain @ x[:2], comm)
    mu, lam = MATERIAL.shear_modulus, MATERIAL.lame_lambda
    sigma = lam * np.trace(strain) * np.eye(2) + 2 * mu * strain
    worst = comm.allreduce(float(np.abs(out - sigma).max(initial=0.0)), op=MPI.MAX)
    assert worst < 1e-9 * np.abs(sigma).max()


def test_a_linear_stress_filters_to_the_closed_form_boundary_layers():
    """u_x = c x^2 / 2: sigma_xx = (lam + 2 mu) c x; the filter adds boundary layers.

    Measured (largest error at the facet midpoints over the largest stress,
    l = 0.1): 20 / 40 / 80 cells along the strip give 3.49e-3 / 1.14e-3 /
    3.49e-4, orders 1.61 and 1.71, on 1 and 2 ranks alike.
    """
    c, length = 1e-3, 0.1
    errors = []
    for nx in (20, 40, 80):
        out, mids = _filtered(nx, length, lambda x: np.vstack((0.5 * c * x[0] ** 2, 0 * x[0])))
        exact = _boundary_layer(mids[:, 0], length, LAM2MU * c)
        local = float(np.abs(out[:, 0, 0] - exact).max(initial=0.0))
        errors.append(MPI.COMM_WORLD.allreduce(local, op=MPI.MAX) / (LAM2MU * c))
    order = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 4e-4 and np.all(order > 1.5), (errors, order)


def test_the_borehole_wall_breaks_where_the_filtered_kirsch_stress_reaches_t0(shared_tmp_path):
    """Seed 001's dry borehole (a = 30 mm, T0 5 MPa) with strength over l = 6 mm.

    Closed form (filtered Kirsch, :func:`filtered_wall_breakdown`): 33.30 MPa,
    against Hubbert-Willis' 21 MPa at a point.  The first break at a/5 and a/10:
    35.68 and 34.17 MPa (+7.2 %, +2.6 %); at a/20 33.75 (+1.4 %).  At a point
    the same meshes give 14.42 / 16.08 / 18.08 MPa (-31 / -23 / -14 %).
    """
    reference = filtered_wall_breakdown(0.03, 20e6, 12e6, 5e6, 6e-3)
    errors = []
    for size in ("6 mm", "3 mm"):
        sets = {"rock.strength_length": "6 mm", "geometry.mesh.size": size}
        scene = load_scene(BOREHOLE, overrides=sets)
        summary = run_scene(scene, shared_tmp_path / f"filtered_{size[0]}")
        assert summary["initial_failures"] == 0 and summary["shear_failures"] == 0
        errors.append(summary["first_crack_pressure_MPa"] * 1e6 / reference - 1.0)
    assert 0.0 < errors[1] < 0.03 and errors[1] < errors[0] < 0.08, errors


def test_a_bad_strength_length_names_the_field():
    assert load_scene(BOREHOLE).physics.interfaces.strength_length == 0.0  # off by default
    for bad in ("-1 mm", "20 m"):
        with pytest.raises(SceneError, match=r"rock\.strength_length.*0 \(a point\) to 10 m"):
            load_scene(BOREHOLE, overrides={"rock.strength_length": bad})
    with pytest.raises(SceneError, match=r"rock\.strength_length"):
        load_scene(BOREHOLE, overrides={"rock.strength_length": "3 MPa"})
    with pytest.raises(ValueError, match="length must be positive"):
        StressFilter(None, MATERIAL, np.zeros(0, np.int32), np.zeros(0, np.int32), 0.0)


def test_the_reduced_solid_reads_the_filtered_stress_too(shared_tmp_path):
    """Springs only in a band (``solver.solid = "reduced"``): the band grows by the filtered check.

    Measured at a/5, l = 6 mm: first break 36.22 MPa reduced, 35.68 full (+1.5 %).
    """
    first = {}
    for solid in ("full", "reduced"):
        sets = {"rock.strength_length": "6 mm", "solver.solid": solid}
        summary = run_scene(load_scene(BOREHOLE, "coarse", overrides=sets), shared_tmp_path / solid)
        first[solid] = summary["first_crack_pressure_MPa"]
    assert first["reduced"] == pytest.approx(first["full"], rel=0.02)
