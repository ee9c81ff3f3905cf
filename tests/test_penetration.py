"""Breakdown of a borehole under a pressure ramp with seepage into the joints.

Seed 001's borehole (a = 30 mm, SH 20 MPa, Sh 12 MPa, T0 5 MPa) at a coarse wall
size a/5.  The two limits are checked against the same solid ramped without
seepage (the linear ramp of :mod:`hfcdem.solid.equilibrium`): fast, the joints
are still dry when the wall breaks (the dry first break, Hubbert-Willis on this
mesh); slow, every joint stands at the cavity pressure.  In between the
breakdown pressure falls as the rate falls.  A viscous fluid (1 Pa s) puts the
transition at MPa/s rates.
"""

import itertools
import math

import numpy as np
import pytest
from borehole import WALL, A, borehole_plate, borehole_solid
from mpi4py import MPI

from hfcdem.config.materials import Fluid
from hfcdem.coupling import events
from hfcdem.coupling.events import check_small_displacement, switch_contacts
from hfcdem.coupling.penetration import (
    CavityPumping,
    PressureRamp,
    excavation_loads,
    ramp_breakdown,
    settle_excavation,
)
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.forms import Loads
from hfcdem.solid.fragments import Fragments
from hfcdem.solid.interfaces import FacetState
from hfcdem.solid.states import CascadeStopped
from hfcdem.solvers import ValidityLimit

FLUID = Fluid(viscosity=1.0)
APERTURE = 5e-6


@pytest.fixture(scope="module")
def plate():
    return borehole_plate()


def _solid(tmesh) -> CDEMSolid:
    return borehole_solid(tmesh)


def _weak_solid(tmesh) -> CDEMSolid:
    """The borehole with Weibull m = 3 strengths (seed 0, the same mean): some weak facets.

    At the wall, where the hoop stress reaches 48 MPa, weak ones fail on excavation
    and cut a wedge loose: a breakout.
    """
    return borehole_solid(tmesh, weibull_modulus=3.0)


def _global(solid: CDEMSolid, mask: np.ndarray) -> int:
    return int(solid.comm.allreduce(int(np.count_nonzero(mask & solid.owned)), op=MPI.SUM))


def _static_first_break(tmesh, joints_wet: bool) -> float:
    """First break of the linear ramp: the cavity (and, wet, every joint) at the load factor."""
    solid = _solid(tmesh)
    joint = ((solid.state == FacetState.INTACT) & ~solid.is_crack).astype(float)
    unit = Loads(
        cavity={WALL[0]: 1.0}, joint_pressure=joint if joints_wet else None, in_situ_factor=0.0
    )
    try:
        first = solid.ramp(Loads(cavity={WALL[0]: 0.0}), unit, 40e6)
    except CascadeStopped as stop:  # wet joints: the first break runs through the zone
        first = stop.first_break
    assert first is not None
    return float(first)


def _ramp(tmesh, rate: float, steps: int = 150, filling: str = "saturation"):
    return ramp_breakdown(
        _solid(tmesh),
        WALL,
        FLUID,
        APERTURE,
        PressureRamp(rate, 25e6, steps=steps, filling=filling),
    )


def test_fast_ramp_breaks_dry(plate):
    dry = _static_first_break(plate, joints_wet=False)
    # Hubbert-Willis 3 Sh - SH + T0 = 21 MPa; a/5 is 31 % low (benchmarks/README.md)
    assert dry == pytest.approx(14.435e6, rel=1e-4)
    fast = _ramp(plate, 1e12)
    assert fast.wet_fraction == 0.0
    assert fast.pressure == pytest.approx(dry, rel=1e-9)
    assert fast.mode == FacetState.TENSILE
    # on the SH axis, at the wall
    assert abs(fast.location[1]) < 1e-9 and abs(abs(fast.location[0]) - A) < A / 5


def test_slow_ramp_breaks_with_joints_at_cavity_pressure(plate):
    wet = _static_first_break(plate, joints_wet=True)
    slow = _ramp(plate, 10.0)  # Pa/s: the joints lag the cavity by ~2e-7 of its pressure
    assert slow.wet_fraction == 1.0
    assert slow.wall_joint_pressure == pytest.approx(1.0, abs=1e-6)
    assert slow.pressure == pytest.approx(wet, rel=1e-6)
    # compressible joints, already full at the start: the same limit
    full = _ramp(plate, 10.0, filling="compressible")
    assert full.pressure == pytest.approx(wet, rel=1e-6)


def test_breakdown_falls_with_rate(plate):
    dry = _static_first_break(plate, joints_wet=False)
    wet = _static_first_break(plate, joints_wet=True)
    # away from the jump (0.15-0.5 of A t_h / P_dry: 4e6-1.5e7 Pa/s here), where one wall joint
    # filling a step earlier or later (time step, ranks) decides
    pb = [_ramp(plate, rate).pressure for rate in (1e9, 1e6, 1e5, 1e4)]
    assert all(b is not None for b in pb)
    assert all(wet * (1 - 1e-6) <= b <= dry * (1 + 1e-9) for b in pb)
    assert all(a > b for a, b in itertools.pairwise(pb))
    assert pb[0] - pb[-1] > 0.5 * (dry - wet)  # the sweep spans most of the transition


def test_pumping_into_a_sealed_cavity_raises_its_pressure_linearly(plate):
    # joints of 1 nm take nothing: the cavity's storage alone, then the dry first break
    dry = _static_first_break(plate, joints_wet=False)
    q = 2e-6  # m^2/s per metre of borehole (seed 001)
    sealed = ramp_breakdown(_solid(plate), WALL, FLUID, 1e-9, CavityPumping(q, 40.0, steps=100))
    # V / Kw + 2 pi a^2 (1 + nu) / E (plane strain, infinite plate): -0.8 % (the polygon
    # of the wall and the fixed plate edge at 1 m)
    closed = math.pi * A**2 / FLUID.bulk_modulus + 2 * math.pi * A**2 * 1.25 / 20e9
    assert sealed.cavity_storage == pytest.approx(closed, rel=1e-2)
    t, p = np.array([(h[0], h[1]) for h in sealed.history]).T
    assert np.allclose(p, q * t / sealed.cavity_storage, rtol=1e-9)
    assert sealed.pressure == pytest.approx(dry, rel=1e-9)
    assert sealed.max_mass_error < 1e-12


def test_pumping_faster_breaks_higher_and_keeps_the_mass(plate):
    runs = [
        ramp_breakdown(_solid(plate), WALL, FLUID, APERTURE, CavityPumping(q, 40.0 * 2e-6 / q))
        for q in (2e-6, 2e-5)
    ]
    slow, fast = runs
    assert slow.pressure < fast.pressure
    assert slow.wet_fraction > 0.05 and fast.wet_fraction < slow.wet_fraction
    # pumped = stored in the cavity + in the joints, every step, to the balance tolerance
    assert max(slow.max_mass_error, fast.max_mass_error) < 1e-9


@pytest.mark.mpi
def test_ranks_agree(plate):
    world = _ramp(plate, 1e6, steps=60)
    one = _ramp(borehole_plate(MPI.COMM_SELF), 1e6, steps=60)
    assert world.pressure == pytest.approx(one.pressure, rel=1e-10)
    assert world.wet_fraction == one.wet_fraction


def test_a_reduced_solid_ramps_with_its_whole_zone_free(plate):
    """A reduced solid frees every interface of its zone: the joints' pressure loads them all.

    The rock outside the zone stays continuous; the first break is the full
    solid's to the difference of the two discretisations there.
    """
    solid = borehole_solid(plate, "reduced")
    reduced = ramp_breakdown(solid, WALL, FLUID, APERTURE, PressureRamp(1e6, 25e6, steps=80))
    assert solid.comm.allreduce(bool(np.all(solid.band.free)), op=MPI.LAND)
    full = _ramp(plate, 1e6, steps=80)
    assert reduced.pressure == pytest.approx(full.pressure, rel=2e-4)  # measured 9.8e-5


def test_a_wedge_the_excavation_cuts_loose_is_debris_and_the_ramp_runs(plate):
    """Weak facets break on excavation: a breakout at the wall, then the ramp's first break.

    Settled as a pumped step settles (contacts switched before the strength is
    checked, the wedge cut loose from the wall released as debris), 25 facets
    break, all in the first ring of cells, and 24 faces round the debris take
    the cavity's pressure.  Before (2026-12), the settle checked the strength
    while new tensile breaks were still open, and kept breaking while the
    loose wedge flew 5.7 km on its residual springs: 951 of the zone's 952
    interfaces broke at 0 MPa and no joint was left for the ramp ("no joint
    broke up to 25 MPa").
    """
    solid = _weak_solid(plate)
    run = ramp_breakdown(solid, WALL, FLUID, APERTURE, PressureRamp(1e6, 25e6, steps=100))
    assert run.stopped is None and run.initial_failures == 25  # measured
    broken = (solid.state != FacetState.INTACT) & solid.owned
    assert np.all(np.hypot(solid.midpoints[broken, 0], solid.midpoints[broken, 1]) < 1.2 * A)
    assert _global(solid, solid.released) == 24
    # the ramp breaks the rock beside the breakout, far below the intact wall's 14.4 MPa
    assert run.pressure == pytest.approx(3.4655e6, rel=1e-4)  # measured 3.46554 MPa
    assert 0.0 < run.wet_fraction < 0.05


def test_the_settled_excavation_is_the_state_a_step_starts_from(plate):
    """Nothing left to switch or break, no block past the small-displacement limit.

    A pumped step starts with a free round of contact switches: were the
    settle's closing-only rounds to hold faces shut or stuck that the free round
    lets slip, the first step would go on breaking the excavation at the first
    pressure step (Weibull m = 2 on the scene's plate: 62 interfaces, not a first
    break at 0.21 MPa).  A wedge cut loose that is not released as debris
    stops the settle at the validity limit instead of breaking everything.
    """
    solid = _weak_solid(plate)
    loads = excavation_loads(solid, WALL, 0.0, None)
    assert settle_excavation(solid, loads, fragments=Fragments(solid, WALL)) == 25
    settled = loads()
    solid.solve(settled)
    check_small_displacement(solid, 0.0)
    assert switch_contacts(solid, settled, only_closing=False) == 0
    ratio, _ = solid.overstress(settled)
    assert solid.comm.allreduce(float(ratio.max(initial=0.0)), op=MPI.MAX) < 1.0
    bare = _weak_solid(plate)
    with pytest.raises(ValidityLimit, match="block cut out by broken faces"):
        settle_excavation(bare, excavation_loads(bare, WALL, 0.0, None))
    assert 0 < sum(bare.broken_counts().values()) < 30  # where it stopped


def test_an_excavation_past_the_validity_limit_stops_the_ramp_with_a_message(plate, monkeypatch):
    monkeypatch.setattr(events, "LOOSE_JUMP", 0.0)  # any broken face parting is too far
    run = ramp_breakdown(
        _weak_solid(plate), WALL, FLUID, APERTURE, PressureRamp(1e6, 25e6, steps=10)
    )
    assert run.stopped.startswith("the excavated rock fails before the ramp: at t = 0 s")
    assert run.initial_failures == 1 and run.pressure is None and run.history == []


def test_bad_input(plate):
    with pytest.raises(ValueError, match="rate"):
        PressureRamp(-1.0, 1e6)
    with pytest.raises(ValueError, match="max_pressure"):
        PressureRamp(1.0, 1e6, initial_pressure=2e6)
    with pytest.raises(ValueError, match="steps"):
        PressureRamp(1.0, 1e6, steps=0)
    with pytest.raises(ValueError, match="filling"):
        PressureRamp(1.0, 1e6, filling="instant")
    with pytest.raises(ValueError, match="rate"):
        CavityPumping(0.0, 1.0)
    with pytest.raises(ValueError, match="duration"):
        CavityPumping(1e-6, -1.0)
    for tolerance in (-0.01, 1.5, math.nan):
        with pytest.raises(ValueError, match="landing_tolerance"):
            CavityPumping(1e-6, 1.0, landing_tolerance=tolerance)
    with pytest.raises(KeyError, match="no_such_group"):
        ramp_breakdown(_solid(plate), ("no_such_group",), FLUID, APERTURE, PressureRamp(1.0, 1e6))
