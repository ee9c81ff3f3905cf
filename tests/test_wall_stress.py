"""The closed-form check of cavity walls under the in-situ stress alone."""

import math
from pathlib import Path

import pytest

from hfcdem.config.scene import load_scene
from hfcdem.workflows.wall_stress import in_situ_wall_tension, wall_tension_warning

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"


@pytest.mark.serial
@pytest.mark.parametrize(("azimuth", "tunnel"), [(30, 10.29), (45, 8.33), (60, 6.02)])
def test_the_lab_specimen_walls_crack_under_the_in_situ_stress(azimuth, tunnel):
    # Sv 15, SH 6, Sh 1 MPa: the tunnels' walls in tension (Sv across them), more
    # so nearer SH; T0 = 2.59 MPa.  The cased wellbore (a tube cast in before loading)
    # keeps its in-situ traction: no hole to check; drilled unloaded, its wall would
    # carry 3 Sh - SH = -3 MPa
    path = SCENES / f"lab_specimen_{azimuth}deg.toml"
    walls = in_situ_wall_tension(load_scene(path))
    assert [w.hole for w in walls] == ["perforation 1", "perforation 2"]
    drilled = load_scene(path, overrides={"injection.wellbore": "drilled"})
    wellbore = in_situ_wall_tension(drilled)[0]
    assert wellbore.hole == "wellbore" and wellbore.exceeds
    assert wellbore.tension == pytest.approx(3.0e6, rel=1e-6)
    for w in walls:
        assert w.tension / 1e6 == pytest.approx(tunnel, abs=0.01) and w.exceeds
        assert abs(w.where[2]) > 0.99  # at the roof and floor: Sv pulls them apart
    text = wall_tension_warning(walls)
    assert "tensile strength 2.59 MPa" in text and f"perforation 1 {tunnel:.2f} MPa" in text
    assert 1.1 < walls[0].shear_ratio < 1.2  # and beyond Mohr-Coulomb where compressed


@pytest.mark.serial
def test_deep_scenes_have_no_wall_in_tension_and_an_unloaded_wellbore_would_break_out():
    # No. 2: the wellbore runs along Sh (y), so Sv 76 and SH 73 MPa act across it; cased,
    # it keeps its in-situ traction and only the tunnel is checked
    no2 = in_situ_wall_tension(load_scene(SCENES / "perforation_no2.toml"))
    assert [w.hole for w in no2] == ["perforation 1"]
    assert not no2[0].exceeds and not no2[0].tension and not no2[0].shears  # at 30 MPa
    assert wall_tension_warning(no2) is None
    # open and unloaded (no initial pressure), its wall carries up to 3 Sv - SH = 155 MPa
    # of hoop stress, beyond Mohr-Coulomb (c0 17 MPa, phi 40 deg): a breakout
    unloaded = load_scene(
        SCENES / "perforation_no2.toml",
        overrides={"injection.wellbore": "open", "injection.initial_pressure": "0 MPa"},
    )
    wellbore = in_situ_wall_tension(unloaded)[0]
    phi = math.radians(40.0)
    breakout = 77.5 / (17.0 * math.cos(phi) + 77.5 * math.sin(phi))
    assert wellbore.shear_ratio == pytest.approx(breakout, rel=1e-3) and wellbore.shears
    text = wall_tension_warning(in_situ_wall_tension(unloaded))
    assert "in shear beyond Mohr-Coulomb (demand over capacity): wellbore 1.23x" in text
    assert "tension" not in text
    field = in_situ_wall_tension(load_scene(SCENES / "field_cluster.toml"))
    assert len(field) == 6 and not any(w.exceeds or w.shears for w in field)
    assert in_situ_wall_tension(load_scene(SCENES / "sneddon_plate.toml")) == []


@pytest.mark.serial
def test_a_drilled_wellbore_is_checked_at_the_pressure_it_was_drilled_at():
    # drilled at 30 MPa, No. 2's wall carries 3 Sv - SH - 30 = 125 MPa of hoop stress
    # against 30 MPa radial: within Mohr-Coulomb, no breakout before injection
    scene = load_scene(SCENES / "perforation_no2.toml", overrides={"injection.wellbore": "drilled"})
    wellbore = in_situ_wall_tension(scene)[0]
    phi = math.radians(40.0)
    ratio = 47.5 / (17.0 * math.cos(phi) + 77.5 * math.sin(phi))
    assert wellbore.shear_ratio == pytest.approx(ratio, rel=1e-3) and not wellbore.shears
    assert wall_tension_warning(in_situ_wall_tension(scene)) is None


def test_the_check_is_in_the_public_api():
    import hfcdem

    assert hfcdem.in_situ_wall_tension is in_situ_wall_tension
    assert "in_situ_wall_tension" in hfcdem.__all__
