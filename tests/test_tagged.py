"""Gmsh on rank 0, distribution with shared-facet ghosting, named tags."""

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from hfcdem.mesh.tagged import MeshingError, mesh_from_gmsh
from hfcdem.mesh.verification import BoreholePlate, create_borehole_plate


def _measure(tmesh, name=None):
    one = dolfinx.fem.Constant(tmesh.mesh, 1.0)
    form = one * (ufl.dx if name is None else tmesh.ds(name))
    return tmesh.comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(form)), op=MPI.SUM)


@pytest.fixture(scope="module")
def quarter():
    return create_borehole_plate(BoreholePlate(0.035, 0.7, 0.005, 0.2), MPI.COMM_WORLD)


def test_quarter_plate_area_and_wall_length(quarter):
    a, w = 0.035, 0.7
    assert _measure(quarter) == pytest.approx(w * w - np.pi * a * a / 4, rel=1e-4)
    # polygonal wall: length error is O(h^2 / a^2)
    assert _measure(quarter, "wellbore_wall") == pytest.approx(np.pi * a / 2, rel=5e-3)
    assert _measure(quarter, "symmetry_x") == pytest.approx(w - a, rel=1e-9)
    assert _measure(quarter, "outer") == pytest.approx(2 * w, rel=1e-9)


def test_tag_names_are_the_api(quarter):
    assert set(quarter.facet_names) == {"wellbore_wall", "symmetry_x", "symmetry_y", "outer"}
    assert set(quarter.cell_names) == {"rock"}
    with pytest.raises(KeyError, match="wellbore_wall"):
        quarter.facet_tag("perforation_wall")


def test_symmetry_facets_lie_on_their_planes(quarter):
    mesh = quarter.mesh
    for name, axis in (("symmetry_x", 0), ("symmetry_y", 1)):
        facets = quarter.facets(name)
        if len(facets) == 0:  # DOLFINx divides by the count; this rank holds none
            continue
        verts = dolfinx.mesh.entities_to_geometry(mesh, 1, facets, False)
        assert np.allclose(mesh.geometry.x[verts][..., axis], 0.0)


def test_interior_facet_integral_assembles_in_parallel(quarter):
    # needs shared-facet ghosting; the total over interior facets is rank independent
    one = dolfinx.fem.Constant(quarter.mesh, 1.0)
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * ufl.dS))
    total = quarter.comm.allreduce(local, op=MPI.SUM)
    serial = create_borehole_plate(BoreholePlate(0.035, 0.7, 0.005, 0.2), MPI.COMM_SELF)
    ref = dolfinx.fem.assemble_scalar(
        dolfinx.fem.form(dolfinx.fem.Constant(serial.mesh, 1.0) * ufl.dS)
    )
    assert total == pytest.approx(ref, rel=1e-12)


def test_full_plate_has_no_symmetry_tags():
    full = create_borehole_plate(BoreholePlate(0.035, 0.35, 0.007, 0.1, quarter=False))
    assert "symmetry_x" not in full.facet_names
    assert _measure(full, "wellbore_wall") == pytest.approx(2 * np.pi * 0.035, rel=1e-2)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"radius": -0.1}, "radius must be a positive length"),
        ({"half_width": 0.05}, "half_width"),
        ({"size_at_wall": 0.0}, "size_at_wall must be a positive"),
        ({"size_at_wall": 0.05}, "must not exceed the radius"),
        ({"size_far": float("nan")}, "size_far"),
    ],
)
def test_bad_plate_input_is_named(kwargs, message):
    base = {"radius": 0.035, "half_width": 0.7, "size_at_wall": 0.005, "size_far": 0.2}
    with pytest.raises(ValueError, match=message):
        BoreholePlate(**{**base, **kwargs})


def test_gmsh_failure_is_reported_on_every_rank_with_the_scene_name():
    def broken(model):
        model.occ.addBox(0, 0, 0, 1, 1, 1)
        model.occ.synchronize()
        raise RuntimeError("no groups defined")

    with pytest.raises(MeshingError, match=r"'broken-scene'.*no groups defined"):
        mesh_from_gmsh(broken, MPI.COMM_WORLD, gdim=3, name="broken-scene")
