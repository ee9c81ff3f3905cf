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
    # so nearer SH; the wellbore's 3 Sh - SH = -3 MPa; T0 = 2.59 MPa
    walls = in_situ_wall_tension(load_scene(SCENES / f"lab_specimen_{azimuth}deg.toml"))
    assert [w.hole for w in walls] == ["wellbore", "perforation 1", "perforation 2"]
    assert walls[0].tension == pytest.approx(3.0e6, rel=1e-6) and walls[0].exceeds
    for w in walls[1:]:
        assert w.tension / 1e6 == pytest.approx(tunnel, abs=0.01) and w.exceeds
        assert abs(w.where[2]) > 0.99  # at the roof and floor: Sv pulls them apart
    text = wall_tension_warning(walls)
    assert "tensile strength 2.59 MPa" in text and f"perforation 1 {tunnel:.2f} MPa" in text
    assert 1.1 < walls[1].shear_ratio < 1.2  # and beyond Mohr-Coulomb where compressed


@pytest.mark.serial
def test_deep_scenes_have_no_wall_in_tension_but_a_wellbore_breakout():
    # No. 2: the wellbore runs along Sh (y), so Sv 76 and SH 73 MPa act across it and
    # its cased (unloaded) wall carries up to 3 Sv - SH = 155 MPa of hoop stress, beyond
    # Mohr-Coulomb (c0 17 MPa, phi 40 deg): a breakout
    no2 = in_situ_wall_tension(load_scene(SCENES / "perforation_no2.toml"))
    assert len(no2) == 2 and not any(w.exceeds or w.tension for w in no2)
    phi = math.radians(40.0)
    breakout = 77.5 / (17.0 * math.cos(phi) + 77.5 * math.sin(phi))
    assert no2[0].shear_ratio == pytest.approx(breakout, rel=1e-3) and no2[0].shears
    assert not no2[1].shears  # the tunnel, at its 30 MPa start
    text = wall_tension_warning(no2)
    assert "in shear beyond Mohr-Coulomb (demand over capacity): wellbore 1.23x" in text
    assert "tension" not in text
    field = in_situ_wall_tension(load_scene(SCENES / "field_cluster.toml"))
    assert len(field) == 7 and not any(w.exceeds for w in field)
    assert [w.hole for w in field if w.shears] == ["wellbore"]
    assert in_situ_wall_tension(load_scene(SCENES / "sneddon_plate.toml")) == []


def test_the_check_is_in_the_public_api():
    import hfcdem

    assert hfcdem.in_situ_wall_tension is in_situ_wall_tension
    assert "in_situ_wall_tension" in hfcdem.__all__
