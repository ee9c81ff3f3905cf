"""The CDEM solid against closed-form solutions (CI-sized meshes).

Finer-mesh figures come from benchmarks/cdem_verification.py.
"""

import math

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem import analytic
from hfcdem.config.materials import ElasticMaterial, InSituStress, InterfaceModel
from hfcdem.config.parts import Crack, MeshSizing, Plate, Wellbore
from hfcdem.config.plates import BoreholeSquare, CrackPlate
from hfcdem.io.sampling import evaluate_at_points, interpolate_expression
from hfcdem.mesh.build import mesh_geometry
from hfcdem.mesh.penny import PennyBlock, create_penny_block
from hfcdem.solid.cdem import CascadeStopped, CDEMSolid, Loads
from hfcdem.solid.interfaces import FacetState
from hfcdem.solvers import SimulationStopped

MPa = 1e6
E, NU, P, A = 210e9, 0.25, 22e6, 0.1  # Table 1 of the perforation paper
STEEL = ElasticMaterial(E, NU)
NO_ZONE = None


def crack_plate(half_width, size, size_far, comm=MPI.COMM_WORLD, half=True, grading=0.25):
    """The Sneddon plate: a crack of half-length A in a square of ``half_width``."""
    sizing = MeshSizing(size, size_far, grading=grading, size_integration="exact")
    plate = Plate(2 * half_width, 2 * half_width)
    geom = CrackPlate(plate, Crack(2 * A), sizing, symmetry=("x",) if half else ())
    return mesh_geometry(geom, comm)


def no_zone(x):
    return np.zeros(x.shape[1], dtype=bool)


def crack_opening(solid, x, axis=1):
    """Opening across the crack plane y = 0 (2D) or z = 0 (3D) at points x."""
    x = np.atleast_2d(x)
    up, down = x.copy(), x.copy()
    up[:, axis] = 1e-10
    down[:, axis] = -1e-10
    return evaluate_at_points(solid.u, up)[:, axis] - evaluate_at_points(solid.u, down)[:, axis]


def sneddon_solid(size, comm=MPI.COMM_WORLD, zone=no_zone, alpha=100.0, sigma0=0.0, pressure=P):
    tmesh = crack_plate(50 * A, size, 10 * A, comm)
    solid = CDEMSolid(
        tmesh,
        STEEL,
        InSituStress(sigma0, sigma0),
        InterfaceModel(alpha=alpha),
        zone=zone,
        degree=2,
        rollers={"symmetry_x": 0},
        fixed=tmesh.facet_groups("outer"),
    )
    solid.solve(Loads(crack_pressure=pressure))
    return solid


def test_sneddon_centre_opening_within_3_percent_and_converging():
    errors = []
    for size in (A / 10, A / 20, A / 40):
        solid = sneddon_solid(size)
        w0 = crack_opening(solid, [[1e-9, 0.0]])[0]
        errors.append(abs(w0 / analytic.sneddon_opening(0.0, A, P, E, NU) - 1))
    assert errors[0] <= 0.03
    assert errors[2] < errors[1] < errors[0], errors


def test_sneddon_profile_at_ten_points():
    solid = sneddon_solid(A / 20)
    x = np.linspace(0.0, 0.9 * A, 10)
    w = crack_opening(solid, np.column_stack([x, np.zeros_like(x)]))
    ref = analytic.sneddon_opening(x, A, P, E, NU)
    assert np.all(np.abs(w / ref - 1) < 0.03), w / ref - 1


def test_griffith_opening_scales_with_net_pressure():
    # background stress normal to the crack (compression positive) subtracts from p
    sigma0 = 5 * MPa
    loaded = crack_opening(sneddon_solid(A / 20, sigma0=sigma0), [[1e-9, 0.0]])[0]
    net = crack_opening(sneddon_solid(A / 20, pressure=P - sigma0), [[1e-9, 0.0]])[0]
    assert loaded == pytest.approx(net, rel=1e-8)
    ref = analytic.sneddon_opening(0.0, A, P - sigma0, E, NU)
    assert loaded == pytest.approx(ref, rel=0.03)


def test_springs_in_the_zone_converge_to_the_glued_solution_with_alpha():
    box = lambda x: (np.abs(x[0]) < 3 * A) & (np.abs(x[1]) < 2 * A)  # noqa: E731
    glued = crack_opening(sneddon_solid(A / 10), [[1e-9, 0.0]])[0]
    diffs = [
        abs(crack_opening(sneddon_solid(A / 10, zone=box, alpha=al), [[1e-9, 0.0]])[0] / glued - 1)
        for al in (10.0, 100.0, 1000.0)
    ]
    assert diffs[2] < diffs[1] < diffs[0]
    assert diffs[2] < 0.01


def test_penny_crack_centre_opening_within_5_percent():
    a = A
    tmesh = create_penny_block(PennyBlock(a, 10 * a, a / 4, 2.5 * a))
    solid = CDEMSolid(
        tmesh,
        STEEL,
        InSituStress(0, 0),
        InterfaceModel(),
        zone=no_zone,
        degree=2,
        rollers={"symmetry_x": 0, "symmetry_y": 1},
        fixed=tmesh.facet_groups("outer"),
    )
    solid.solve(Loads(crack_pressure=P))
    w0 = crack_opening(solid, [[1e-9, 1e-9, 0.0]], axis=2)[0]
    assert w0 == pytest.approx(analytic.penny_opening(0.0, a, P, E, NU), rel=0.05)


ROCK = ElasticMaterial(21.5e9, 0.25)
RADIUS = 0.035


def borehole_solid(
    sh_ratio, comm=MPI.COMM_WORLD, size=RADIUS / 10, model=None, quarter=False, walls=None
):
    sizing = MeshSizing(
        size, 8 * RADIUS, grading=0.25, wall_rings=4, circle_elements=6, size_integration="exact"
    )
    plate = Plate(80 * RADIUS, 80 * RADIUS)
    geom = BoreholeSquare(
        plate, Wellbore(2 * RADIUS, "z"), sizing, symmetry=("x", "y") if quarter else ()
    )
    tmesh = mesh_geometry(geom, comm)
    sh = 10 * MPa
    model = model or InterfaceModel(
        alpha=100, tensile_strength=3 * MPa, cohesion=17 * MPa, friction_angle=40
    )
    kwargs = (
        {"rollers": {"symmetry_x": 0, "symmetry_y": 1}}
        if quarter
        else {"fixed": tmesh.facet_groups("outer")}
    )
    return CDEMSolid(
        tmesh,
        ROCK,
        InSituStress(sh_ratio * sh, sh),
        model,
        zone=lambda x: np.hypot(x[0], x[1]) < 4 * RADIUS,
        degree=2,
        walls=walls,
        **kwargs,
    )


def ramp_wellbore(solid, max_pressure=200 * MPa):
    return solid.ramp(
        Loads(cavity={"wellbore_wall": 0.0}),
        Loads(cavity={"wellbore_wall": 1.0}, in_situ_factor=0.0),
        max_pressure,
    )


def wall_hoop_stress(solid):
    """Hoop stress (compression positive) at the wall on the x and y axes."""
    sigma = interpolate_expression(solid.total_stress(), solid.mesh, ("DG", 1, (2, 2)))
    theta = np.array([0.0, np.pi / 2])
    r = RADIUS * (1 + 1e-9)
    s = evaluate_at_points(sigma, r * np.column_stack([np.cos(theta) + 1e-6, np.sin(theta) + 1e-6]))
    s = s.reshape(-1, 2, 2)
    return theta, -np.array([s[0, 1, 1], s[1, 0, 0]])


def test_kirsch_hoop_stress_with_springs_in_the_zone():
    solid = borehole_solid(1.5, quarter=True)
    pw = 5 * MPa
    solid.solve(Loads(cavity={"wellbore_wall": pw}))
    theta, hoop = wall_hoop_stress(solid)
    ref = analytic.kirsch_wall_hoop_stress(theta, 15 * MPa, 10 * MPa, pw)
    assert np.all(np.abs(hoop - ref) <= 0.05 * np.abs(ref).max()), (hoop / MPa, ref / MPa)


def test_a_drilled_wall_keeps_the_kirsch_stress_of_its_pressure_under_the_in_situ_load():
    # drilled at pw and cased: the in-situ load alone gives the hole's Kirsch state,
    # exactly the drilled state the casing holds (nothing broke)
    pw = 5 * MPa
    solid = borehole_solid(1.5, quarter=True, walls={"wellbore_wall": pw})
    solid.solve(Loads())
    theta, hoop = wall_hoop_stress(solid)
    ref = analytic.kirsch_wall_hoop_stress(theta, 15 * MPa, 10 * MPa, pw)
    assert np.all(np.abs(hoop - ref) <= 0.05 * np.abs(ref).max()), (hoop / MPa, ref / MPa)
    drilled = solid.forms.wall_reference.x.array
    gap = MPI.COMM_WORLD.allreduce(np.abs(solid.u.x.array - drilled).max(initial=0.0), op=MPI.MAX)
    scale = MPI.COMM_WORLD.allreduce(np.abs(drilled).max(initial=0.0), op=MPI.MAX)
    assert scale > 0.0 and gap <= 1e-9 * scale
    # a unit load carries nothing of the drilled wall
    solid.solve(Loads(), unit=Loads(in_situ_factor=0.0))
    assert MPI.COMM_WORLD.allreduce(np.abs(solid.u_unit.x.array).max(initial=0.0), op=MPI.MAX) == 0


def test_a_drilled_wall_is_held_by_its_casing_against_later_loads():
    # fluid inside the zone's joints pushes the wall into the hole: the cased wall moves
    # a few hundredths of what the same wall moves at a fixed pressure (measured: 5.9 % on
    # the x axis, 2.9 % on the y axis)
    def wall_motion(walls, cavity):
        solid = borehole_solid(1.5, quarter=True, walls=walls)
        solid.solve(Loads(cavity=cavity))
        before = solid.u.x.array.copy()
        joints = np.full(solid.num_facets, 20 * MPa)
        solid.solve(Loads(cavity=cavity, joint_pressure=joints))
        x = RADIUS * (1 + 1e-9) * np.array([[1.0, 1e-6], [1e-6, 1.0]])
        solid.u.x.array[:] -= before
        moved = evaluate_at_points(solid.u, x)
        return np.abs(np.array([moved[0, 0], moved[1, 1]]))

    cased = wall_motion({"wellbore_wall": 5 * MPa}, {})
    free = wall_motion(None, {"wellbore_wall": 5 * MPa})
    assert np.all(free > 0.0)
    assert np.all(cased < 0.08 * free), (cased, free)


def test_a_wall_that_is_not_a_facet_group_or_has_no_finite_pressure_is_named():
    with pytest.raises(ValueError, match="'casing_wall' is not a facet group"):
        borehole_solid(1.5, quarter=True, walls={"casing_wall": 5 * MPa})
    with pytest.raises(ValueError, match="wall pressure on 'wellbore_wall' must be finite"):
        borehole_solid(1.5, quarter=True, walls={"wellbore_wall": math.inf})


@pytest.mark.parametrize("ratio", [1.0, 1.3, 1.7])
def test_hubbert_willis_breakdown(ratio):
    solid = borehole_solid(ratio)
    pb = ramp_wellbore(solid)
    ref = analytic.hubbert_willis_breakdown(ratio * 10 * MPa, 10 * MPa, 3 * MPa)
    assert pb == pytest.approx(ref, rel=0.10)
    first = solid.events[0]
    assert np.all(first.modes == FacetState.TENSILE)
    if ratio > 1.0:
        # the first crack opens against Sh: it lies along SH (the x axis)
        angle = np.degrees(np.arctan2(np.abs(first.midpoints[:, 1]), np.abs(first.midpoints[:, 0])))
        assert np.all(angle < 5.0), angle


def test_breakdown_pressure_and_broken_set_are_rank_independent():
    world = borehole_solid(1.3)
    alone = borehole_solid(1.3, comm=MPI.COMM_SELF)
    assert ramp_wellbore(world) == pytest.approx(ramp_wellbore(alone), rel=1e-9)
    mids_world = world.midpoints[world.owned & (world.state != FacetState.INTACT)]
    gathered = np.concatenate(MPI.COMM_WORLD.allgather(mids_world))
    mids_alone = alone.midpoints[alone.state != FacetState.INTACT]
    key = lambda m: sorted(map(tuple, np.round(m, 9)))  # noqa: E731
    assert key(gathered) == key(mids_alone)
    assert world.broken_counts() == alone.broken_counts()


def test_intact_block_under_in_situ_stress_stays_intact_and_still():
    solid = borehole_solid(1.5)
    solid.equilibrate(Loads(cavity={}))  # no excavation load: wall traction left as in situ
    umax = solid.comm.allreduce(np.abs(solid.u.x.array).max(initial=0.0), op=MPI.MAX)
    assert umax == 0.0
    assert solid.fracture_degree() == 0.0


@pytest.mark.parametrize("alpha", [1e6])
def test_very_stiff_springs_solve_without_nan(alpha):
    solid = borehole_solid(1.5, model=InterfaceModel(alpha=alpha, tensile_strength=3 * MPa))
    solid.solve(Loads(cavity={"wellbore_wall": 10 * MPa}))
    assert np.all(np.isfinite(solid.u.x.array))
    pb = ramp_wellbore(solid)
    assert pb == pytest.approx(analytic.hubbert_willis_breakdown(15e6, 10e6, 3e6), rel=0.10)


@pytest.mark.parametrize(
    ("t0", "c0"), [(1.0, 17 * MPa), (3 * MPa, 1.0), (0.0, 0.0)], ids=["T0->0", "c0->0", "both 0"]
)
def test_vanishing_strengths_solve_or_diagnose_without_nan(t0, c0):
    weak = InterfaceModel(tensile_strength=t0, cohesion=c0, friction_angle=40.0, break_rule="all")
    solid = borehole_solid(1.5, model=weak, size=RADIUS / 5)
    try:
        # 16 MPa exceeds 3 Sh - SH = 15 MPa: the wall is in tension
        solid.equilibrate(Loads(cavity={"wellbore_wall": 16 * MPa}), max_iterations=30)
    except CascadeStopped as stop:
        assert "did not settle in 30 iterations" in str(stop)
        assert (stop.iterations, stop.load_factor, stop.first_break) == (30, 0.0, None)
        assert stop.broken > 0
    counts = solid.broken_counts()
    assert counts["tensile"] + counts["shear"] > 0
    assert np.all(np.isfinite(solid.u.x.array))
    assert 0.0 < solid.fracture_degree() <= 1.0


def test_extreme_stress_ratio_is_solved_or_diagnosed():
    # 100:1 in-situ ratio: the wall is in tension before any pressure
    model = InterfaceModel(tensile_strength=3 * MPa, cohesion=17 * MPa, break_rule="all")
    solid = borehole_solid(100.0, model=model, size=RADIUS / 5)
    try:
        solid.equilibrate(Loads(cavity={"wellbore_wall": 0.0}), max_iterations=50)
    except CascadeStopped as stop:
        assert "did not settle" in str(stop) and stop.iterations == 50
    else:
        assert solid.fracture_degree() > 0.0
    assert np.all(np.isfinite(solid.u.x.array))


def _global_facets(solid, events):
    return solid.comm.allreduce(sum(len(ev.facets) for ev in events), op=MPI.SUM)


def test_a_cascade_that_does_not_settle_stops_the_ramp_and_keeps_its_breaks():
    # one re-solve per load level: the first break leaves the states unsettled
    solid = borehole_solid(1.3, size=RADIUS / 5)
    with pytest.raises(CascadeStopped) as caught:
        solid.ramp(
            Loads(cavity={"wellbore_wall": 0.0}),
            Loads(cavity={"wellbore_wall": 1.0}, in_situ_factor=0.0),
            200 * MPa,
            stop_after_first=False,
            max_iterations=1,
        )
    stop = caught.value
    assert isinstance(stop, SimulationStopped) and isinstance(stop, RuntimeError)
    assert stop.iterations == 1 and stop.broken >= 1
    # the breakdown is the first break: the same as that of a ramp given room to settle
    settled = ramp_wellbore(borehole_solid(1.3, size=RADIUS / 5))
    assert stop.first_break == pytest.approx(settled, rel=1e-9)
    assert stop.first_break <= stop.load_factor <= 200 * MPa
    assert f"{stop.load_factor:.6g}" in str(stop) and f"{stop.broken} facets" in str(stop)
    # the breaks so far are kept: the events hold every broken facet, the last at the stop
    assert solid.events[0].load_factor == pytest.approx(stop.first_break, rel=1e-8)
    assert solid.events[-1].load_factor == stop.load_factor
    counts = solid.broken_counts()
    assert _global_facets(solid, solid.events) == counts["tensile"] + counts["shear"]
    at_stop = [ev for ev in solid.events if ev.load_factor == stop.load_factor]
    assert _global_facets(solid, at_stop) == stop.broken
    assert np.all(np.isfinite(solid.u.x.array))


def test_weibull_strengths_are_reproducible_and_rank_independent():
    model = InterfaceModel(
        tensile_strength=3 * MPa, cohesion=17 * MPa, weibull_modulus=3.0, seed=11
    )
    world = borehole_solid(1.3, model=model)
    alone = borehole_solid(1.3, comm=MPI.COMM_SELF, model=model)
    pick = lambda s: dict(zip(map(tuple, np.round(s.midpoints, 9)), s.t0, strict=True))  # noqa: E731
    mine = pick(world)
    ref = pick(alone)
    assert all(math.isclose(v, ref[k]) for k, v in mine.items())
    other = borehole_solid(
        1.3,
        comm=MPI.COMM_SELF,
        model=InterfaceModel(
            tensile_strength=3 * MPa, cohesion=17 * MPa, weibull_modulus=3.0, seed=12
        ),
    )
    assert not np.allclose(other.t0, alone.t0)


def test_bad_solver_settings_are_named():
    tmesh = crack_plate(5 * A, A / 4, A)
    with pytest.raises(ValueError, match="degree"):
        CDEMSolid(tmesh, STEEL, InSituStress(0, 0), InterfaceModel(), degree=3)
    with pytest.raises(ValueError, match="solver"):
        CDEMSolid(tmesh, STEEL, InSituStress(0, 0), InterfaceModel(), solver="magic")
    with pytest.raises(KeyError, match="not a cell or facet group"):
        CDEMSolid(tmesh, STEEL, InSituStress(0, 0), InterfaceModel(), zone="nowhere")


def test_iterative_solver_matches_direct():
    tmesh = crack_plate(50 * A, A / 10, 10 * A)
    results = []
    for kind in ("direct", "iterative"):
        solid = CDEMSolid(
            tmesh,
            STEEL,
            InSituStress(0, 0),
            InterfaceModel(),
            zone=lambda x: np.abs(x[1]) < A,
            degree=2,
            rollers={"symmetry_x": 0},
            fixed=tmesh.facet_groups("outer"),
            solver=kind,
        )
        solid.solve(Loads(crack_pressure=P))
        results.append(crack_opening(solid, [[1e-9, 0.0]])[0])
    assert results[1] == pytest.approx(results[0], rel=1e-6)


def test_sliver_elements_solve_finite_or_stop_clearly():
    import dolfinx
    from tiny_solid import tag_sides

    comm = MPI.COMM_WORLD
    mesh = dolfinx.mesh.create_unit_square(
        comm, 6, 6, ghost_mode=dolfinx.mesh.GhostMode.shared_facet
    )
    # squash a column of vertices almost onto its neighbours: aspect ratios ~1e5
    x = mesh.geometry.x
    x[np.isclose(x[:, 0], 0.5), 0] = 1.0 / 3.0 + 1e-6
    tmesh = tag_sides(mesh, 1.0)
    solid = CDEMSolid(
        tmesh,
        ROCK,
        InSituStress(0, 0),
        InterfaceModel(tensile_strength=1 * MPa),
        degree=1,
        fixed=["right"],
    )
    try:
        solid.equilibrate(Loads(cavity={"left": 5 * MPa}), max_iterations=20)
    except (RuntimeError, FloatingPointError) as err:
        assert "did not" in str(err) or "non-finite" in str(err)
    assert np.all(np.isfinite(solid.u.x.array))


def test_per_facet_crack_pressure_matches_uniform_pressure():
    uniform = sneddon_solid(A / 10)
    w_uniform = crack_opening(uniform, [[1e-9, 0.0]])[0]
    per_facet = CDEMSolid(
        uniform.tmesh,
        STEEL,
        InSituStress(0, 0),
        InterfaceModel(),
        zone=no_zone,
        degree=2,
        rollers={"symmetry_x": 0},
        fixed=uniform.tmesh.facet_groups("outer"),
    )
    per_facet.solve(Loads(crack_pressure=np.full(per_facet.num_facets, P)))
    # midpoint quadrature of a per-facet value: same load, so the same opening to O(h^2)
    assert crack_opening(per_facet, [[1e-9, 0.0]])[0] == pytest.approx(w_uniform, rel=2e-2)
    # and it is linear in the pressure
    per_facet.solve(Loads(crack_pressure=np.full(per_facet.num_facets, 2 * P)))
    assert crack_opening(per_facet, [[1e-9, 0.0]])[0] == pytest.approx(2 * w_uniform, rel=2e-2)


@pytest.mark.parametrize("friction_angle", [20.0, 40.0])
def test_coulomb_friction_on_a_closed_crack_matches_mode_ii_slip(friction_angle):
    # A closed, broken interface on y = 0 under in-situ shear tau0 = 10 MPa and
    # normal stress 20 MPa (SH 30, Sh 10 MPa at 45 deg).  Where tau0 > mu sigma_n it
    # slips, and the slip is that of a mode-II crack under the stress drop
    # tau0 - mu sigma_n: 4 (tau0 - mu sigma_n) a / E'.  Otherwise it sticks.
    from hfcdem.solid.cdem import SLIP, STICK

    a, e, nu = A, 21.5e9, 0.25
    tmesh = crack_plate(30 * a, a / 20, 6 * a, half=False)
    solid = CDEMSolid(
        tmesh,
        ElasticMaterial(e, nu),
        InSituStress(30 * MPa, 10 * MPa, azimuth_sh=45.0),
        InterfaceModel(alpha=1e3, friction_angle=friction_angle),
        zone=no_zone,
        degree=2,
        fixed=tmesh.facet_groups("outer"),
    )
    solid.is_crack[:] = False  # a broken interface governed by contact, not an open crack
    solid.state[:] = FacetState.SHEAR
    solid.contact[:] = STICK
    solid.equilibrate(Loads(), max_iterations=50)
    top = evaluate_at_points(solid.u, [[1e-9, 1e-10]])[0]
    bottom = evaluate_at_points(solid.u, [[1e-9, -1e-10]])[0]
    slip, opening = abs(top[0] - bottom[0]), top[1] - bottom[1]
    drop = 10 * MPa - math.tan(math.radians(friction_angle)) * 20 * MPa
    owned = solid.owned
    sliding = solid.comm.allreduce(int(np.count_nonzero(solid.contact[owned] == SLIP)), op=MPI.SUM)
    total = solid.comm.allreduce(int(owned.sum()), op=MPI.SUM)
    assert abs(opening) < 1e-3 * 4 * 10 * MPa * a / e  # stays closed
    if drop > 0:
        assert sliding == total
        assert slip == pytest.approx(4 * drop * a * (1 - nu**2) / e, rel=0.03)
    else:
        assert sliding == 0
        assert slip < 0.01 * 4 * 10 * MPa * a * (1 - nu**2) / e  # spring compliance only


def test_stiffness_is_symmetric_so_cholesky_applies():
    # the direct solver factorises K as LDL^T: springs in every state, the Nitsche glue
    # and the Dirichlet rows must keep it symmetric
    tmesh = crack_plate(5 * A, A / 5, A)
    solid = CDEMSolid(
        tmesh,
        STEEL,
        InSituStress(10 * MPa, 5 * MPa),
        InterfaceModel(),
        zone=lambda x: np.abs(x[1]) < A,
        rollers={"symmetry_x": 0},
        fixed=tmesh.facet_groups("outer"),
    )
    # one facet of each broken state next to the intact springs and the glue
    some = np.flatnonzero(~solid.is_crack)[:3]
    solid.state[some] = FacetState.TENSILE
    solid.contact[some] = [0, 1, 2]  # open, stick, slip
    _, ksp = solid.factorize()
    A_ = ksp.getOperators()[0]
    assert A_.isSymmetric(1e-10 * A_.norm())
    assert ksp.getPC().getType() == "cholesky"
    # and it solves as before
    solid.solve(Loads(crack_pressure=P))
    assert np.all(np.isfinite(solid.u.x.array))


def test_a_load_form_is_compiled_once_per_interface_states_and_gives_a_fresh_forms_vector():
    """The load form of some terms is reused, its values set per call.

    The vector of the reused form equals that of a form built from scratch for
    the same loads, whatever the loads before; a break (new interface states)
    or new terms (a per-facet joint pressure) give another form.
    """
    import dolfinx.fem.petsc
    import ufl
    from petsc4py import PETSc
    from tiny_solid import crack_facets, tiny_solid

    solid = tiny_solid()
    n = solid.num_facets
    x = solid.midpoints[:, 0]

    def vector(form):
        b = dolfinx.fem.petsc.assemble_vector(form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        out = b.array.copy()
        b.destroy()
        return out

    def fresh(loads):
        dS = ufl.Measure("dS", domain=solid.mesh, subdomain_data=solid.interface_tags())
        return vector(dolfinx.fem.form(solid.forms.load(loads, solid.states, dS)))

    def same(a, b):  # on every rank
        local = bool(np.allclose(a, b, rtol=1e-14, atol=0.0))
        return MPI.COMM_WORLD.allreduce(local, op=MPI.LAND)

    first = Loads(cavity={"left": 3e6}, crack_pressure=np.full(n, 1e6))
    second = Loads(cavity={"left": 5e6}, crack_pressure=1e5 * (1.0 + x), in_situ_factor=0.3)
    form = solid.load_form(first)
    assert solid.load_form(second) is form
    assert same(vector(form), fresh(second))
    assert not same(vector(solid.load_form(first)), fresh(second))
    joints = Loads(cavity={"left": 5e6}, crack_pressure=np.zeros(n), joint_pressure=2e6 + x)
    assert solid.load_form(joints) is not form
    assert same(vector(solid.load_form(joints)), fresh(joints))
    crack = crack_facets(solid)
    solid.break_facets(crack, np.full(len(crack), FacetState.TENSILE), 0.0)
    broken = solid.load_form(second)
    assert broken is not form
    assert same(vector(broken), fresh(second))


@pytest.mark.parametrize("mode", ["full", "reduced"])
def test_a_load_and_its_unit_solved_together_are_those_solved_one_by_one(mode):
    """``solve(loads, unit)`` hands MUMPS both right-hand sides at once: the same answer."""
    from borehole import WALL, borehole_plate, borehole_solid

    solid = borehole_solid(borehole_plate(), mode)
    solid.free_interfaces(np.ones(solid.num_facets, dtype=bool))  # springs, not glue
    loads = Loads(cavity={WALL[0]: 10 * MPa})
    unit = Loads(cavity={WALL[0]: 1.0}, in_situ_factor=0.0)
    solid.solve(loads, unit)
    together = solid.u.x.array.copy(), solid.u_unit.x.array.copy()
    for item, expected in zip((loads, unit), together, strict=True):
        solid.solve(item)
        scale = MPI.COMM_WORLD.allreduce(float(np.abs(expected).max()), op=MPI.MAX)
        gap = MPI.COMM_WORLD.allreduce(float(np.abs(solid.u.x.array - expected).max()), op=MPI.MAX)
        assert 0.0 < scale and gap <= 1e-12 * scale


def test_a_load_under_zero_displacement_conditions_is_the_lifted_one():
    """Zero Dirichlet values lift nothing: the load skips the lifting and is the same vector."""
    import dolfinx.fem.petsc
    from petsc4py import PETSc

    from hfcdem.solid.cdem import _homogeneous

    solid = sneddon_solid(A / 5)
    a_form, _ = solid.factorize()
    form = solid.load_form(Loads(crack_pressure=P))
    b = solid.assemble_load(a_form, form)
    lifted = dolfinx.fem.petsc.assemble_vector(form)
    dolfinx.fem.petsc.apply_lifting(lifted, [a_form], bcs=[solid.bcs])
    lifted.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(lifted, solid.bcs)
    assert np.array_equal(b.array, lifted.array)
    assert _homogeneous(solid.bcs)
    dofs = np.zeros(0, dtype=np.int32)
    assert not _homogeneous([dolfinx.fem.dirichletbc(1.0, dofs, solid.V.sub(0))])
