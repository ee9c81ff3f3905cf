"""The group mass balance against hand-computed cases on a two-facet network (NumPy only)."""

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.config.materials import Fluid
from hfcdem.flow.balance import (
    APERTURE_FLOOR,
    ROUNDOFF,
    GroupBalance,
    VoidVolumes,
    gravity_drive,
    relative_permeability,
)
from hfcdem.flow.network import CAVITY, build_network

KW = 2e9


def _line():
    # facet 0 on [0, 1] touches the cavity at vertex 0; facet 1 on [1, 2] follows it
    keys = np.array([[0, 1], [1, 2]])
    coords = np.array([[[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [2, 0, 0]]], dtype=float)
    net, _ = build_network(MPI.COMM_SELF, keys, np.ones(2), coords, np.array([0]))
    return net


def _balance(group, v0=(1e-4, 2e-4), rate=True, fluid=None, h=None, lag=False):
    net = _line()
    fluid = fluid or Fluid(viscosity=1e-3, bulk_modulus=KW)
    m = 1 + max(int(max(group)), 0)
    h = np.zeros((2, m)) if h is None else np.asarray(h)
    volumes = VoidVolumes(np.array(v0), h, 1e-3, np.zeros(m))
    drive = gravity_drive(net, fluid, np.zeros(3))
    return GroupBalance(net, fluid, volumes, np.array(group), drive, 1e-3, rate, lag=lag)


def _trans(balance, vf):
    aperture = vf / balance.net.area + APERTURE_FLOOR  # no residual aperture
    return balance.net.transmissibility(aperture, balance.fluid.conductivity)


def test_relative_permeability():
    s = np.array([-1.0, 0.0, 0.5, 1.0, 2.0])
    assert relative_permeability(s).tolist() == [0.0, 0.0, 0.5, 1.0, 1.0]


def test_void_volumes_are_linear_in_the_pressures():
    vol = VoidVolumes(np.array([1.0, 2.0]), np.array([[1.0, 0.0], [0.0, 2.0]]), 3.0, np.ones(2))
    vf, vc = vol.at(np.array([2.0, 3.0]))
    assert vf.tolist() == [3.0, 8.0] and vc == 8.0
    batch, cav = vol.at(np.array([[2.0, 0.0], [3.0, 1.0]]))  # two columns
    assert batch.tolist() == [[3.0, 1.0], [8.0, 4.0]] and cav.tolist() == [8.0, 4.0]
    # uniform pressure holding 10: (10 - 1 - 3) / (1 + 2) with facet 0 and the cavity
    assert vol.filling_pressure(np.array([True, False]), 10.0) == pytest.approx(2.0)
    rigid = VoidVolumes(np.ones(2), np.zeros((2, 2)), 3.0, np.zeros(2))
    assert rigid.filling_pressure(np.array([True, True]), 10.0) is None


def test_the_network_pairs():
    net = _line()
    fa, fb, inner = net.pair_facets
    assert net.size == 2 and int(np.sum(net.pair_b == CAVITY)) == 1
    assert fa[~inner].tolist() == [0]  # facet 0 meets the cavity
    assert sorted([int(fa[inner][0]), int(fb[inner][0])]) == [0, 1]


def test_fluxes_follow_the_pressure_difference_and_relative_permeability():
    bal = _balance([1, -1])  # facet 0 wet (group 1), facet 1 dry
    p = np.array([2e6, 1.5e6])
    vf, _ = bal.volumes.at(p)
    content = np.array([0.0, 0.5e-4])  # facet 1 a quarter full
    flux, sat = bal.fluxes(p, vf, content)
    assert sat.tolist() == [1.0, 0.25]
    fa, fb, inner = bal.net.pair_facets
    pf = np.array([1.5e6, 0.0])  # facet pressures (dry: 0)
    trans = _trans(bal, vf)
    pb = np.where(inner, pf[fb], 2e6)  # the cavity end at the cavity pressure
    s_b = np.where(inner, sat[fb], 1.0)
    expect = trans * relative_permeability(0.5 * (sat[fa] + s_b)) * (pf[fa] - pb)
    np.testing.assert_allclose(flux, expect, rtol=1e-14)
    # kr of the half-full mean saturation 0.625 on the inner pair, 1 at the cavity
    kr = relative_permeability(np.array([0.625]))[0]
    assert flux[inner][0] == pytest.approx(trans[inner][0] * kr * 1.5e6, rel=1e-14)


def test_residual_sums_to_the_global_mass_balance():
    bal = _balance([1, 2])  # both facets wet: fluxes between groups cancel
    p = np.array([2e6, 1.8e6, 1.2e6])
    content = np.array([1.1e-4, 2.3e-4])
    leak = np.array([1e-7, 2e-7])
    source, dt = 5e-6, 0.5
    r = bal.residual(p, dt, source, leak, content, 1.0e-3)
    vf, vc = bal.volumes.at(p)
    stored = vf * (1 + p[1:] / KW)
    expect = stored.sum() + vc * (1 + p[0] / KW) - content.sum() - 1.0e-3 + leak.sum() - source
    assert r.sum() == pytest.approx(expect, rel=1e-9)
    # group 2 (facet 1) by hand: its storage, minus content, plus outflow, plus leak
    flux, _ = bal.fluxes(p, vf, content)
    fa, fb, inner = bal.net.pair_facets
    out_of_1 = np.sum(flux[inner & (fa == 1)]) - np.sum(flux[inner & (fb == 1)])
    assert r[2] == pytest.approx(stored[1] - content[1] + dt * out_of_1 + leak[1], rel=1e-12)
    assert bal.size == 3


def test_a_pressure_schedule_fixes_the_cavity_pressure():
    bal = _balance([1, 2], rate=False)
    p = np.array([2e6, 1e6, 1e6])
    r = bal.residual(p, 1.0, 3e6, np.zeros(2), np.zeros(2), 0.0)
    scale = 1e-3 / KW  # cavity storage over Kw (the wall compliance hc is zero here)
    assert r[0] == pytest.approx((2e6 - 3e6) * scale, rel=1e-12)


def test_advance_keeps_exact_books():
    bal = _balance([1, 2])
    p = np.array([2e6, 1.8e6, 1.2e6])
    content, cavity = np.array([1.1e-4, 2.3e-4]), 1.0e-3
    leak = np.array([1e-7, 2e-7])
    after = bal.advance(p, 0.5, 5e-6, leak, content, cavity)
    before = content.sum() + cavity
    held = after.content.sum() + after.cavity_content
    assert held == pytest.approx(before + 5e-6 - leak.sum(), rel=1e-13)
    assert after.injected == 5e-6
    assert after.pressure.tolist() == [1.8e6, 1.2e6]
    r = bal.residual(p, 0.5, 5e-6, leak, content, cavity, control=False)
    assert after.mismatch == pytest.approx(np.sum(np.abs(r)), rel=1e-12)


def test_a_dry_facet_gains_what_flows_in_and_fills():
    bal = _balance([1, -1], v0=(1e-4, 1e-8))
    p = np.array([2e6, 2e6])
    vf, _ = bal.volumes.at(p)
    content = np.array([1e-4, 0.0])
    dt = 10.0
    gain = bal.dry_gain(p, vf, content, dt)
    flux, _ = bal.fluxes(p, vf, content)
    _, _, inner = bal.net.pair_facets
    assert gain[1] == pytest.approx(dt * flux[inner][0], rel=1e-14)
    assert gain.sum() == pytest.approx(-dt * flux[~inner].sum(), rel=1e-12)  # from the cavity
    # an empty dry facet has zero saturation: kr(0.5) = 0.5 at the pair
    drained, full = bal.wet_changes(p, dt, content, np.array([True, True]))
    assert not drained.any()
    assert full.tolist() == [False, bool(gain[1] >= vf[1])]
    sucked = bal.wet_changes(np.array([2e6, -1e5]), dt, content, np.array([True, True]))[0]
    assert sucked.tolist() == [True, False]
    held = bal.wet_changes(np.array([2e6, -1e5]), dt, content, np.array([False, True]))[0]
    assert not held.any()  # filled during this step: suction allowed until it ends


def test_a_lagging_group_holds_its_fluid_at_zero_pressure():
    """Water carries no tension: less fluid than void is a part-full group at p = 0."""
    kw = 10e6
    fluid = Fluid(viscosity=1e-3, bulk_modulus=kw)
    h = [[1e-11], [0.0]]  # facet 0 opens 1e-11 m^3/Pa under its group's pressure
    lag = _balance([0, -1], v0=(1e-4, 1e-8), fluid=fluid, h=h, lag=True)
    held = 0.5 * (1e-4 + 1e-3)  # half of what the cavity and facet 0 hold at zero pressure

    def r(q):
        return lag.residual(np.array([q]), 1.0, 0.0, np.zeros(2), np.array([0.0, 0.0]), held)

    q = kw * (held / (1e-4 + 1e-3) - 1.0)  # V (1 + q / Kw) = held with V at zero load
    assert q == pytest.approx(-0.5 * kw)
    assert abs(r(q)[0]) < 1e-18
    assert lag.load(np.array([q, 2e6])).tolist() == [0.0, 2e6]
    # the faces see no pressure: the void is the zero-load void, whatever q
    _, sat = lag.fluxes(np.array([q]), lag.volumes.at(lag.load(np.array([q])))[0], np.zeros(2))
    assert sat[0] == pytest.approx(0.5)
    # the residual is monotone through q = 0 (one root), unlike V(q) (1 + q / Kw) with suction
    qs = np.linspace(-0.9 * kw, 0.5 * kw, 57)
    assert np.all(np.diff([r(x)[0] for x in qs]) > 0.0)
    suction = _balance([0, -1], v0=(1e-4, 1e-8), fluid=fluid, h=h)  # lag off: the zero-lag rung
    assert suction.load(np.array([q])).tolist() == [q]
    with_suction = suction.residual(
        np.array([q]), 1.0, 0.0, np.zeros(2), np.array([0.0, 0.0]), held
    )
    assert with_suction[0] != pytest.approx(r(q)[0])  # the faces pulled in by the suction


def test_tolerance_scales_with_the_fluid_held():
    bal = _balance([1, 2])
    tol = bal.tolerance(np.array([1e-4, 2e-4]), 1e-3, 5e-6, 1e-8)
    assert tol == pytest.approx(1e-8 * (1e-3 + 3e-4 + 5e-6), rel=1e-14)


def test_tolerance_has_the_round_off_floor_of_the_voids():
    """Voids far above the fluid held: the residual cannot resolve 1e-10 of the fluid."""
    bal = _balance([1, 2], v0=(50.0, -49.0))  # a detached block: one face open, one overlapping
    content = np.array([1e-9, 1e-9])
    p = np.zeros(3)
    plain = bal.tolerance(content, 1e-9, 0.0, 1e-10)
    assert plain == pytest.approx(1e-10 * 3e-9)
    floored = bal.tolerance(content, 1e-9, 0.0, 1e-10, p)
    assert floored == pytest.approx(ROUNDOFF * (50.0 + 49.0 + 1e-3), rel=1e-12)
    # the floor is the size of the round-off of the residual's sum, not above it by decades
    r = bal.residual(p, 1.0, 0.0, np.zeros(2), content, 1e-9)
    assert floored < 1e-11 and abs(r.sum()) > 1.0


def test_gravity_drives_along_the_pairs():
    net = _line()
    fluid = Fluid(gravity=(-10.0, 0.0))
    drive = gravity_drive(net, fluid, np.array([-1.0, 0.0, 0.0]))
    fa, fb, inner = net.pair_facets
    xb = np.where(inner, net.centroid[fb, 0], -1.0)
    np.testing.assert_allclose(drive, 1000.0 * (xb - net.centroid[fa, 0]) * -10.0)


def test_one_group_per_facet_is_required():
    with pytest.raises(ValueError, match="group"):
        _balance([1])
