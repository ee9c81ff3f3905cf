"""Seepage through intact joints: mass balance, an equivalent porous medium, ranks.

A plate [0, 1] x [0, 0.25] meshed with crossed diagonals (a lattice with no
x-y coupling, so its steady profile is exactly linear) has every interior facet
as a joint of the perforation paper's aperture.  Its equivalent conductivity
and storage make the joint network a 1D diffusion with ``D = k_eq / s_eq``,
checked against ``p0 erfc(x / 2 sqrt(D t))`` before the front reaches x = 1.
An annulus meshed by Gmsh (unstructured) checks steady radial flow against the
log profile; a box of tetrahedra checks 3D mass balance, decay and ranks.
An outer boundary held at a pressure is part of the cavity set, with its own
per-connection value.
"""

import math

import dolfinx
import gmsh
import numpy as np
import pytest
from mpi4py import MPI
from tiny_solid import tag_sides

from hfcdem.config.materials import ElasticMaterial, Fluid, InSituStress, InterfaceModel
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.seepage import INITIAL_JOINT_APERTURE, JointSeepage, joint_network
from hfcdem.mesh.tagged import TaggedMesh, mesh_from_gmsh
from hfcdem.solid.cdem import CDEMSolid

L, H, P0 = 1.0, 0.25, 1e6
FLUID = Fluid()  # water: 1 mPa s, Kw = 2.2 GPa
TAUS = (0.015, 0.03)  # D t / L^2 at which the front is compared: erfc(L / 2 sqrt(D t)) < 5e-5


def _plate(nx: int, comm: MPI.Comm = MPI.COMM_WORLD) -> CDEMSolid:
    mesh = dolfinx.mesh.create_rectangle(
        comm,
        [[0.0, 0.0], [L, H]],
        [nx, max(nx // 4, 1)],
        diagonal=dolfinx.mesh.DiagonalType.crossed,
        ghost_mode=dolfinx.mesh.GhostMode.shared_facet,
    )
    return CDEMSolid(
        tag_sides(mesh, L),
        ElasticMaterial(10e9, 0.25),
        InSituStress(1e6, 0.5e6),
        InterfaceModel(alpha=100, tensile_strength=1e6),
    )


def _seepage(solid: CDEMSolid, sides: list[str], aperture=INITIAL_JOINT_APERTURE) -> JointSeepage:
    net = joint_network(solid, cavity_vertices(solid, sides, None))
    return JointSeepage(net, aperture, FLUID)


def _equivalent(solid: CDEMSolid) -> tuple[float, float, float, float]:
    """k_eq, s_eq per unit plate area, steady error against the linear profile, flux mismatch."""
    sp = _seepage(solid, ["left", "right"])
    left = sp.net.centroid[sp.cavity_facets, 0] < 0.5 * L
    pc = np.where(left, P0, 0.0)
    p = sp.steady(pc)
    q = sp.inflow(pc, p)
    q_in, q_out = float(q[left].sum()), float(q[~left].sum())
    linear = P0 * (1.0 - sp.net.centroid[:, 0] / L)
    k_eq = q_in / (H * P0 / L)
    s_eq = float(sp.storage.sum()) / (L * H)
    return k_eq, s_eq, float(np.abs(p - linear).max() / P0), abs(q_in + q_out) / q_in


def _front(solid: CDEMSolid, steps: int) -> tuple[list[float], np.ndarray]:
    """Max error / p0 against erfc at each of TAUS, and the final pressures."""
    k_eq, s_eq, _, _ = _equivalent(solid)
    diff = k_eq / s_eq
    sp = _seepage(solid, ["left"])
    x = sp.net.centroid[:, 0]
    dt = TAUS[-1] * L * L / diff / steps
    errors = []
    for k in range(1, steps + 1):
        p = sp.step(dt, P0)
        if any(k == round(tau / TAUS[-1] * steps) for tau in TAUS):
            scale = 2.0 * math.sqrt(diff * k * dt)
            exact = P0 * np.array([math.erfc(xi / scale) for xi in x])
            errors.append(float(np.abs(p - exact).max() / P0))
    return errors, p


def test_steady_plate_is_linear_and_conserves():
    nx, ny = 16, 4
    k_eq, s_eq, linear_error, mismatch = _equivalent(_plate(nx))
    assert linear_error < 2e-14  # measured 5.1e-15: every facet on the linear profile
    assert mismatch < 1e-13  # inflow = outflow, measured 3.4e-14
    # storage: aperture x joint length / Kw; the joints are the interior facets
    # (4 half-diagonals per cell and the interior grid lines)
    h = L / nx
    length = nx * ny * 2.0 * math.sqrt(2.0) * h + (nx - 1) * H + (ny - 1) * L
    assert s_eq == pytest.approx(INITIAL_JOINT_APERTURE * length / FLUID.bulk_modulus / (L * H))
    assert k_eq == pytest.approx(3.607023e-13, rel=1e-6)  # regression: 1D flux / gradient


def test_mass_balance_every_step():
    solid = _plate(16)
    net = joint_network(solid, cavity_vertices(solid, ["left"], None))
    rng = np.random.default_rng(14)
    aperture = INITIAL_JOINT_APERTURE * rng.lognormal(0.0, 0.5, net.size)
    sp = JointSeepage(net, aperture, FLUID)
    stored, worst, total = sp.stored(), 0.0, 0.0
    for k in range(60):
        dt = 1e-4 if k < 30 else 3e-4  # a change of dt refactorises
        sp.step(dt, P0 * min(1.0, (k + 1) / 20))
        gained = sp.stored() - stored
        stored += gained
        injected = sp.flux_into_network()
        total += injected
        assert injected > 0.0
        worst = max(worst, abs(injected - gained) / abs(gained))
    assert worst < 1e-13  # measured 4.3e-14
    assert abs(total - sp.stored()) / sp.stored() < 1e-14  # measured 1e-15


def test_front_converges_with_mesh():
    errors = {nx: _front(_plate(nx), 400)[0] for nx in (8, 16, 32)}
    for e, expected in zip(errors[32], (5.865e-3, 3.718e-3), strict=True):
        assert e == pytest.approx(expected, rel=0.01)
    for tau in range(len(TAUS)):
        e8, e16, e32 = (errors[nx][tau] for nx in (8, 16, 32))
        assert e8 / e16 > 2.6 and e16 / e32 > 2.25  # measured 2.68-3.05, 2.29-2.37


def test_front_converges_with_time_step():
    solid = _plate(32)
    runs = {steps: _front(solid, steps) for steps in (50, 100, 200, 1600)}
    errors = [runs[s][0][-1] for s in (50, 100, 200)]
    assert errors[0] > errors[1] > errors[2]
    assert errors == pytest.approx([6.054e-3, 4.711e-3, 4.049e-3], rel=0.01)
    # implicit Euler: the distance to the converged-in-time solution halves with dt
    fine = runs[1600][1]
    gaps = [float(np.abs(runs[s][1] - fine).max()) / P0 for s in (50, 100, 200)]
    # first order against a reference at dt / 32, dt / 16: (32 - 1) / (16 - 1), (16 - 1) / (8 - 1)
    assert gaps[0] / gaps[1] == pytest.approx(31 / 15, rel=0.01)  # measured 2.066
    assert gaps[1] / gaps[2] == pytest.approx(15 / 7, rel=0.01)  # measured 2.143


def test_same_pressures_on_any_number_of_ranks():
    comm = MPI.COMM_WORLD
    pressures = []
    for c in (comm, MPI.COMM_SELF):
        sp = _seepage(_plate(16, c), ["left"])
        for _ in range(20):
            p = sp.step(2e-4, P0)
        pressures.append(p)
    difference = float(np.abs(pressures[0] - pressures[1]).max())
    assert comm.allreduce(difference, op=MPI.MAX) == 0.0
    gathered = comm.allgather(pressures[0])
    assert all(np.array_equal(g, gathered[0]) for g in gathered)


def test_bad_input_is_refused():
    solid = _plate(8)
    net = joint_network(solid, cavity_vertices(solid, ["left"], None))
    with pytest.raises(ValueError, match=r"aperture .* > 0 m"):
        JointSeepage(net, -5e-6, FLUID)
    with pytest.raises(ValueError, match=r"aperture must be one value or"):
        JointSeepage(net, np.full(net.size + 1, INITIAL_JOINT_APERTURE), FLUID)
    sp = JointSeepage(net, INITIAL_JOINT_APERTURE, FLUID)
    for dt in (0.0, -1.0):
        with pytest.raises(ValueError, match=r"dt must be > 0 s"):
            sp.step(dt, P0)
    with pytest.raises(ValueError, match=r"dt must be finite \(s\)"):
        sp.step(math.nan, P0)
    with pytest.raises(ValueError, match=r"cavity_pressure must be finite \(Pa\)"):
        sp.step(1e-4, math.inf)
    with pytest.raises(ValueError, match=r"cavity_pressure must be one value or"):
        sp.step(1e-4, np.zeros(len(sp.cavity_facets) + 1))
    with pytest.raises(ValueError, match=r"pressure must be finite \(Pa\)"):
        JointSeepage(net, INITIAL_JOINT_APERTURE, FLUID, pressure=math.nan)
    with pytest.raises(ValueError, match=r"facets must be local interface indices"):
        joint_network(solid, np.zeros(0, np.int64), [solid.num_facets])


R0, R = 0.2, 1.0  # annulus: the hole wall (cavity at P0) and the outer circle (held at 0)


def _solid(tmesh: TaggedMesh) -> CDEMSolid:
    stress = InSituStress(1e6, 0.5e6, 1e6)
    model = InterfaceModel(alpha=100, tensile_strength=1e6)
    return CDEMSolid(tmesh, ElasticMaterial(10e9, 0.25), stress, model)


def _annulus(h: float, comm: MPI.Comm = MPI.COMM_WORLD) -> CDEMSolid:
    """Gmsh annulus R0 < r < R, uniform size ``h`` (``wall`` and ``outer`` tagged)."""

    def build(model) -> None:
        outer = model.occ.addDisk(0.0, 0.0, 0.0, R, R)
        hole = model.occ.addDisk(0.0, 0.0, 0.0, R0, R0)
        model.occ.cut([(2, outer)], [(2, hole)])
        model.occ.synchronize()
        surfaces = [tag for _, tag in model.getEntities(2)]
        curves = [tag for _, tag in model.getBoundary([(2, s) for s in surfaces], oriented=False)]
        inner = [c for c in curves if model.getBoundingBox(1, abs(c))[3] < 0.5 * (R0 + R)]
        model.addPhysicalGroup(2, surfaces, 1, name="rock")
        model.addPhysicalGroup(1, [abs(c) for c in inner], 2, name="wall")
        model.addPhysicalGroup(1, [abs(c) for c in curves if c not in inner], 3, name="outer")
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        model.mesh.generate(2)

    return _solid(mesh_from_gmsh(build, comm, gdim=2, name="annulus"))


def _radial(
    solid: CDEMSolid, aperture: float = INITIAL_JOINT_APERTURE
) -> tuple[dict[str, float], np.ndarray]:
    """Steady errors / p0 against ``p0 ln(R/r) / ln(R/r0)`` at the facet centroids, pressures."""
    sp = _seepage(solid, ["wall", "outer"], aperture)
    r = np.linalg.norm(sp.net.centroid[:, :2], axis=1)
    hole = np.linalg.norm(sp.net.centroid[sp.cavity_facets, :2], axis=1) < 0.5 * (R0 + R)
    pc = np.where(hole, P0, 0.0)
    p = sp.steady(pc)
    q = sp.inflow(pc, p)
    error = (p - P0 * np.log(R / r) / np.log(R / R0)) / P0
    ring = np.digitize(r, np.linspace(R0, R, 9))  # 8 rings: the mean error is the bias
    stats = {
        "max": float(np.abs(error).max()),
        "rms": float(np.sqrt(np.mean(error**2))),
        "bias": max(abs(float(error[ring == k].mean())) for k in np.unique(ring)),
        "balance": abs(float(q[hole].sum() + q[~hole].sum())) / float(q[hole].sum()),
    }
    return stats, p


def test_radial_flow_from_a_hole_on_an_unstructured_mesh():
    """Steady flow from the hole (p0) to the outer circle (0) against the log profile.

    Measured on Gmsh meshes of uniform size h (max / rms over all facets, bias the
    largest mean error of 8 rings): h = 0.1: 4.65e-2 / 9.03e-3 / 1.08e-2;
    0.05: 1.89e-2 / 3.58e-3 / 4.89e-3; 0.025: 1.08e-2 / 1.67e-3 / 2.60e-3 (and
    h = 0.0125, too slow for the suite: 7.95e-3 / 6.37e-4 / 1.15e-3).  rms and
    bias fall as O(h); the maximum, always at a facet near the wall, falls more
    slowly (2.46, 1.75 per halving), attributed to the lattice's local anisotropy:
    0.12-0.20 h |grad p| at the wall.  The mesh must be uniform: the
    equivalent conductivity of a joint lattice goes as 1 / h.
    """
    runs = {h: _radial(_annulus(h)) for h in (0.1, 0.05, 0.025)}
    coarse = runs[0.1][1]
    measured = {
        0.1: (4.652e-2, 9.027e-3, 1.078e-2),
        0.05: (1.890e-2, 3.578e-3, 4.893e-3),
        0.025: (1.078e-2, 1.673e-3, 2.603e-3),
    }
    for h, (run, _) in runs.items():
        got = (run["max"], run["rms"], run["bias"])
        assert got == pytest.approx(measured[h], rel=0.01)
        assert run["balance"] < 2e-14  # hole inflow = outer outflow, measured 3e-15
    rms = [runs[h][0]["rms"] for h in (0.1, 0.05, 0.025)]
    assert rms[0] / rms[1] > 2.4 and rms[1] / rms[2] > 2.1  # measured 2.52, 2.14
    # the equivalent medium is homogeneous: the profile does not depend on the aperture
    thrice = _radial(_annulus(0.1), 3.0 * INITIAL_JOINT_APERTURE)[1]
    assert np.abs(thrice - coarse).max() < 1e-14 * P0  # measured 1.3e-15 p0
    assert np.array_equal(_radial(_annulus(0.1, MPI.COMM_SELF))[1], coarse)


def _box(n: int, comm: MPI.Comm = MPI.COMM_WORLD) -> CDEMSolid:
    """Tetrahedra in [0, 1] x [0, 0.5]^2 (n x n/2 x n/2 cubes), x = 0 'left', x = 1 'right'."""
    mesh = dolfinx.mesh.create_box(
        comm,
        [[0.0, 0.0, 0.0], [L, 0.5, 0.5]],
        [n, n // 2, n // 2],
        cell_type=dolfinx.mesh.CellType.tetrahedron,
        ghost_mode=dolfinx.mesh.GhostMode.shared_facet,
    )
    mesh.topology.create_connectivity(2, 3)
    faces = [
        dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda p, x=x: np.isclose(p[0], x))
        for x in (0.0, L)
    ]
    facets = np.concatenate(faces).astype(np.int32)
    values = np.repeat(np.arange(1, 3, dtype=np.int32), [len(f) for f in faces])
    order = np.argsort(facets)
    ftags = dolfinx.mesh.meshtags(mesh, 2, facets[order], values[order])
    cells = np.arange(mesh.topology.index_map(3).size_local, dtype=np.int32)
    ctags = dolfinx.mesh.meshtags(mesh, 3, cells, np.ones_like(cells))
    return _solid(TaggedMesh(mesh, ctags, ftags, {"rock": 1}, {"left": 1, "right": 2}))


def test_box_3d_conserves_decays_and_is_rank_independent():
    """A 3D box of tetrahedra: x = 0 at p0, x = 1 held at 0, the sides sealed.

    create_box splits every cube into six tetrahedra about one diagonal: the
    lattice is anisotropic, so the steady profile is *not* linear.  Measured
    (n = 4, 8, 12 cubes along x): the deviation from ``p0 (1 - x)`` tilts across
    the block by 0.186, 0.198, 0.199 p0 per metre in y and z (it does not vanish
    with refinement); max deviation 8.6e-2, 1.07e-1, 1.14e-1 p0; the mean over
    slices of x still approaches the line (3.2e-2, 2.1e-2, 1.6e-2).  Asserted:
    mass balance, the maximum principle, monotone decay in x, ranks.
    """
    solid = _box(8)
    sp = _seepage(solid, ["left", "right"])
    x, y = sp.net.centroid[:, 0], sp.net.centroid[:, 1]
    left = sp.net.centroid[sp.cavity_facets, 0] < 0.5 * L
    pc = np.where(left, P0, 0.0)
    p = sp.steady(pc)
    q = sp.inflow(pc, p)
    assert abs(q[left].sum() + q[~left].sum()) / q[left].sum() < 1e-13  # measured 1.9e-14
    assert 0.0 < p.min() and p.max() < P0
    slices = np.clip(np.digitize(x, np.linspace(0.0, L, 9)), 1, 8)
    means = np.array([p[slices == k].mean() for k in range(1, 9)])
    assert np.all(np.diff(means) < -0.1 * P0)  # decays from the cavity: 0.111-0.130 p0 a slice
    deviation = (p - P0 * (1.0 - x / L)) / P0
    assert np.abs(deviation).max() == pytest.approx(0.1069, rel=0.01)  # not linear: measured
    assert np.polyfit(y, deviation, 1)[0] == pytest.approx(0.1982, rel=0.01)  # the tilt

    rng = np.random.default_rng(3)
    aperture = INITIAL_JOINT_APERTURE * rng.lognormal(0.0, 0.5, sp.net.size)
    pressures = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        box = solid if comm is MPI.COMM_WORLD else _box(8, comm)
        tr = _seepage(box, ["left", "right"], aperture)
        worst = 0.0
        for k in range(20):
            before = tr.stored()
            tr.step(2e-4 if k < 10 else 5e-4, pc)
            gained = tr.stored() - before
            worst = max(worst, abs(tr.flux_into_network() - gained) / abs(gained))
        assert worst < 5e-14  # injected = stored gain every step, measured 8.6e-15
        pressures.append(tr.pressure)
    assert np.array_equal(pressures[0], pressures[1])
