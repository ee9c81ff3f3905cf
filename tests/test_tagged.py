"""Gmsh on rank 0, distribution with shared-facet ghosting, named tags."""

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from hfcdem.config.parts import MeshSizing, Plate, Wellbore
from hfcdem.config.plates import BoreholeSquare
from hfcdem.mesh.build import mesh_geometry
from hfcdem.mesh.tagged import MeshingError, mesh_from_gmsh


def borehole_plate(radius, half_width, size, size_far, quarter=True, comm=MPI.COMM_WORLD):
    """A plate around a borehole meshed as the verified set-ups are (grading 0.25)."""
    sizing = MeshSizing(size, size_far, grading=0.25, circle_elements=6, size_integration="exact")
    plate = Plate(2 * half_width, 2 * half_width)
    axes = ("x", "y") if quarter else ()
    return mesh_geometry(
        BoreholeSquare(plate, Wellbore(2 * radius, "z"), sizing, symmetry=axes), comm
    )


def _measure(tmesh, name=None):
    one = dolfinx.fem.Constant(tmesh.mesh, 1.0)
    form = one * (ufl.dx if name is None else tmesh.ds(name))
    return tmesh.comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(form)), op=MPI.SUM)


@pytest.fixture(scope="module")
def quarter():
    return borehole_plate(0.035, 0.7, 0.005, 0.2)


def test_quarter_plate_area_and_wall_length(quarter):
    a, w = 0.035, 0.7
    assert _measure(quarter) == pytest.approx(w * w - np.pi * a * a / 4, rel=1e-4)
    # polygonal wall: length error is O(h^2 / a^2)
    assert _measure(quarter, "wellbore_wall") == pytest.approx(np.pi * a / 2, rel=5e-3)
    assert _measure(quarter, "symmetry_x") == pytest.approx(w - a, rel=1e-9)
    for name in ("outer_xmax", "outer_ymax"):
        assert _measure(quarter, name) == pytest.approx(w, rel=1e-9)
    assert quarter.facet_groups("outer") == ("outer_xmax", "outer_ymax")


def test_tag_names_are_the_api(quarter):
    assert set(quarter.facet_names) == {
        "wellbore_wall",
        "symmetry_x",
        "symmetry_y",
        "outer_xmax",
        "outer_ymax",
    }
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
    serial = borehole_plate(0.035, 0.7, 0.005, 0.2, comm=MPI.COMM_SELF)
    ref = dolfinx.fem.assemble_scalar(
        dolfinx.fem.form(dolfinx.fem.Constant(serial.mesh, 1.0) * ufl.dS)
    )
    assert total == pytest.approx(ref, rel=1e-12)


def test_full_plate_has_no_symmetry_tags():
    full = borehole_plate(0.035, 0.35, 0.007, 0.1, quarter=False)
    assert "symmetry_x" not in full.facet_names
    assert _measure(full, "wellbore_wall") == pytest.approx(2 * np.pi * 0.035, rel=1e-2)


def test_wall_rings_put_radial_facets_on_the_axes():
    # four structured rings of the wall size: facets along SH (y = 0) and Sh (x = 0)
    a, h = 0.035, 0.0035
    sizing = MeshSizing(
        h, 0.28, grading=0.25, wall_rings=4, circle_elements=6, size_integration="exact"
    )
    geom = BoreholeSquare(Plate(2.8, 2.8), Wellbore(2 * a, "z"), sizing)
    tmesh = mesh_geometry(geom)
    mesh = tmesh.mesh
    mesh.topology.create_entities(1)
    n = mesh.topology.index_map(1).size_local
    verts = dolfinx.mesh.entities_to_geometry(mesh, 1, np.arange(n, dtype=np.int32), False)
    ends = mesh.geometry.x[verts]
    mid = ends.mean(axis=1)
    r = np.hypot(mid[:, 0], mid[:, 1])
    inside = r < a + 4 * h
    on_axis = inside & (np.abs(mid[:, 1]) < 1e-12) & (mid[:, 0] > 0.0)
    local = int(on_axis.sum())
    # every layer has one radial facet of the wall size on the +x axis
    assert tmesh.comm.allreduce(local, op=MPI.SUM) == 4
    lengths = np.linalg.norm(ends[on_axis, 1] - ends[on_axis, 0], axis=1)
    assert np.allclose(lengths, h, rtol=1e-9)


def test_the_full_plate_names_its_four_edges():
    full = borehole_plate(0.035, 0.35, 0.007, 0.1, quarter=False)
    edges = ("outer_xmax", "outer_xmin", "outer_ymax", "outer_ymin")
    assert full.facet_groups("outer") == edges
    for name in edges:
        assert _measure(full, name) == pytest.approx(0.7, rel=1e-9)


def test_gmsh_failure_is_reported_on_every_rank_with_the_scene_name():
    def broken(model):
        model.occ.addBox(0, 0, 0, 1, 1, 1)
        model.occ.synchronize()
        raise RuntimeError("no groups defined")

    with pytest.raises(MeshingError, match=r"'broken-scene'.*no groups defined"):
        mesh_from_gmsh(broken, MPI.COMM_WORLD, gdim=3, name="broken-scene")
