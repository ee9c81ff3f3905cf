"""The solid's forms: energies of hand-built displacements, loads, tags, rigid-body modes.

A unit square cut at y = 0.5 (the ``crack`` group, N facets), every interior
facet an interface.  The displacement fields are built cell by cell, so their
jumps are known exactly and each energy has a closed form.
"""

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import pytest
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from hfcdem.config.materials import ElasticMaterial, InterfaceModel
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.facets import FacetFunctions, InterfaceFacets
from hfcdem.solid.forms import (
    GLUE,
    OPEN_FACETS,
    SLIP_FACETS,
    SPRING,
    Loads,
    SolidForms,
    combine,
    interface_tags,
    rigid_body_modes,
)
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import SLIP, InterfaceStates

N = 4
ROCK = ElasticMaterial(10e9, 0.25)
ALPHA = 50.0
RESIDUAL = 1e-3


def build(zone=None, crack_state=FacetState.INTACT, comm=MPI.COMM_WORLD, sigma0=None):
    mesh = dolfinx.mesh.create_unit_square(
        comm, N, N, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    mesh.topology.create_entities(1)
    line = dolfinx.mesh.locate_entities(mesh, 1, lambda x: np.isclose(x[1], 0.5))
    ftags = dolfinx.mesh.meshtags(mesh, 1, line, np.full(len(line), 7, dtype=np.int32))
    empty = np.zeros(0, dtype=np.int32)
    tmesh = TaggedMesh(mesh, dolfinx.mesh.meshtags(mesh, 2, empty, empty), ftags, {}, {"crack": 7})
    facets = InterfaceFacets.build(tmesh, zone, ("crack",))
    states = InterfaceStates.initial(np.zeros(facets.num_facets, dtype=bool), 2)
    if crack_state != FacetState.INTACT:
        on_line = np.flatnonzero(np.isclose(facets.midpoints[:, 1], 0.5))
        states.break_facets(on_line, np.full(len(on_line), crack_state))
    V = dolfinx.fem.functionspace(mesh, ("DG", 1, (2,)))
    model = InterfaceModel(alpha=ALPHA, residual_stiffness=RESIDUAL)
    sigma0 = np.zeros((2, 2)) if sigma0 is None else sigma0
    forms = SolidForms(tmesh, V, ROCK, model, sigma0, 40.0, FacetFunctions(mesh, facets))
    dS = ufl.Measure("dS", domain=mesh, subdomain_data=interface_tags(mesh, facets, states))
    return tmesh, V, facets, states, forms, dS


def energy(form, u):
    """u^T K u, assembled without boundary conditions."""
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(form))
    A.assemble()
    y = A.createVecLeft()
    A.mult(u.x.petsc_vec, y)
    value = y.dot(u.x.petsc_vec)
    A.destroy()
    y.destroy()
    return value


def step_field(V, jump):
    """Zero below y = 0.5, the constant ``jump`` above it."""
    u = dolfinx.fem.Function(V)
    mesh = V.mesh
    cmap = mesh.topology.index_map(2)
    cells = np.arange(cmap.size_local + cmap.num_ghosts, dtype=np.int32)
    upper = cells[dolfinx.mesh.compute_midpoints(mesh, 2, cells)[:, 1] > 0.5]
    u.interpolate(lambda x: np.tile(np.asarray(jump)[:, None], (1, x.shape[1])), cells0=upper)
    u.x.scatter_forward()
    return u


def test_a_linear_field_stores_only_its_strain_energy():
    # no jumps: springs and glue carry nothing, the energy is |Omega| eps:C:eps
    _, V, _, _, forms, dS = build()
    u = dolfinx.fem.Function(V)
    exx, eyy, exy = 1e-4, -2e-4, 0.5e-4
    u.interpolate(lambda x: np.vstack([exx * x[0] + exy * x[1], exy * x[0] + eyy * x[1]]))
    lam, mu = ROCK.lame_lambda, ROCK.shear_modulus
    exact = lam * (exx + eyy) ** 2 + 2 * mu * (exx**2 + eyy**2 + 2 * exy**2)
    assert energy(forms.stiffness(dS), u) == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize(
    ("state", "factor"),
    [(FacetState.INTACT, 1.0), (FacetState.TENSILE, RESIDUAL)],
    ids=["intact springs", "open: residual stiffness"],
)
def test_a_normal_jump_stores_kn_d2_along_the_cut(state, factor):
    # kn = alpha E / h, h = sqrt(2)/N on this mesh; the cut has length 1
    _, V, _, _, forms, dS = build(crack_state=state)
    d = 1e-6
    kn = ALPHA * ROCK.youngs_modulus / (np.sqrt(2.0) / N)
    got = energy(forms.stiffness(dS), step_field(V, [0.0, d]))
    assert got == pytest.approx(factor * kn * d**2, rel=1e-12)


def test_a_tangential_jump_uses_the_shear_ratio_and_sliding_faces_keep_only_kn():
    _, V, _, states, forms, dS = build()
    d = 1e-6
    kn = ALPHA * ROCK.youngs_modulus / (np.sqrt(2.0) / N)
    ks = kn / (2.0 * (1.0 + ROCK.poisson_ratio))
    assert energy(forms.stiffness(dS), step_field(V, [d, 0.0])) == pytest.approx(
        ks * d**2, rel=1e-12
    )
    tmesh, V, facets, states, forms, _ = build(crack_state=FacetState.SHEAR)
    states.contact[np.isclose(facets.midpoints[:, 1], 0.5)] = SLIP
    dS = ufl.Measure(
        "dS", domain=tmesh.mesh, subdomain_data=interface_tags(tmesh.mesh, facets, states)
    )
    tangential = energy(forms.stiffness(dS), step_field(V, [d, 0.0]))
    normal = energy(forms.stiffness(dS), step_field(V, [0.0, d]))
    assert tangential == pytest.approx(RESIDUAL * ks * d**2, rel=1e-12)
    assert normal == pytest.approx(kn * d**2, rel=1e-12)


def test_pressure_on_an_open_cut_does_the_work_p_times_the_opening():
    _, V, _, states, forms, dS = build(crack_state=FacetState.TENSILE)
    p, d = 7e6, 2e-6
    u = step_field(V, [0.3e-6, d])  # the tangential part does no work
    b = dolfinx.fem.petsc.assemble_vector(
        dolfinx.fem.form(forms.load(Loads(crack_pressure=p), states, dS))
    )
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    work = b.dot(u.x.petsc_vec)
    assert work == pytest.approx(p * d, rel=1e-12)


def test_glue_and_tags_follow_the_zone_and_the_states():
    tmesh, _, facets, states, _, _ = build(zone=lambda x: x[1] < 0.5)
    on_line = np.isclose(facets.midpoints[:, 1], 0.5)
    states.break_facets(np.flatnonzero(on_line), np.full(on_line.sum(), FacetState.TENSILE))
    states.contact[np.flatnonzero(on_line)[:1]] = SLIP
    tags = interface_tags(tmesh.mesh, facets, states)
    got = dict(zip(tags.indices, tags.values, strict=True))
    assert all(got[f] == GLUE for f in facets.glue_facets)
    expected = np.where(on_line, OPEN_FACETS, SPRING)
    expected[np.flatnonzero(on_line)[:1]] = SLIP_FACETS
    assert [got[f] for f in facets.facets] == list(expected)


def test_combine_is_linear_in_every_part():
    base = Loads(cavity={"wall": 1e6}, crack_pressure=2e6, in_situ_factor=1.0)
    unit = Loads(cavity={"wall": 1.0, "tip": 2.0}, crack_pressure=1.0, in_situ_factor=0.0)
    got = combine(base, unit, 3e6)
    assert got.cavity == {"wall": 4e6, "tip": 6e6}
    assert got.crack_pressure == 5e6 and got.in_situ_factor == 1.0
    per_facet = combine(base, Loads(crack_pressure=np.array([1.0, 2.0])), 1e6)
    assert np.allclose(per_facet.crack_pressure, [3e6, 4e6])
    assert got.joint_pressure is None
    joints = combine(base, Loads(joint_pressure=np.array([1.0, 0.0])), 2e6)
    assert np.array_equal(joints.joint_pressure, [2e6, 0.0])
    both = combine(joints, Loads(joint_pressure=np.array([0.5, 1.0])), 2.0)
    assert np.array_equal(both.joint_pressure, [2e6 + 1.0, 2.0])


def test_rigid_body_modes_are_orthonormal_and_cost_no_energy():
    _, V, _, _, forms, dS = build()
    _space, modes = rigid_body_modes(V)
    assert len(modes) == 3
    gram = np.array([[a.petsc_vec.dot(b.petsc_vec) for b in modes] for a in modes])
    assert np.allclose(gram, np.eye(3), atol=1e-12)
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(forms.stiffness(dS)))
    A.assemble()
    # K m = 0 for every mode, to round-off relative to the size of K
    y = A.createVecLeft()
    scale = A.norm(PETSc.NormType.FROBENIUS)
    for m in modes:
        A.mult(m.petsc_vec, y)
        assert y.norm() < 1e-15 * scale  # measured 1e-17
    y.destroy()
    A.destroy()
