"""Quantities with explicit units: parsing to SI and errors that name the field."""

import math

import pytest

from hfcdem.config.units import (
    FieldError,
    UnitError,
    format_quantity,
    join_path,
    parse_quantity,
    show_stress,
)


@pytest.mark.parametrize(
    ("text", "dimension", "si"),
    [
        ("33.44 mm", "length", 0.03344),
        ("2 m", "length", 2.0),
        ("7 cm", "length", 0.07),
        ("50 nm", "length", 5e-8),
        ("5 µm", "length", 5e-6),
        ("-150 mm", "length", -0.15),
        ("1.5e-3 m", "length", 1.5e-3),
        ("60 deg", "angle", math.pi / 3),
        ("0.5 rad", "angle", 0.5),
        ("38 MPa", "stress", 38e6),
        ("8.402 GPa", "stress", 8.402e9),
        ("250 kPa", "stress", 2.5e5),
        ("60 s", "time", 60.0),
        ("2 min", "time", 120.0),
        ("1 h", "time", 3600.0),
        ("1e-7 m3/s", "flow_rate", 1e-7),
        ("6 L/min", "flow_rate", 1e-4),
        ("2 m^3/s", "flow_rate", 2.0),
        ("1 mPa.s", "viscosity", 1e-3),
        ("1000 kg/m3", "density", 1000.0),
        ("  12mm ", "length", 0.012),
    ],
)
def test_quantities_convert_to_si(text, dimension, si):
    assert parse_quantity(text, dimension, "x") == pytest.approx(si, rel=1e-12)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("70", "geometry.wellbore.diameter: expected a length such as '70 mm', got '70'"),
        (70, "geometry.wellbore.diameter: expected a length such as '70 mm', got 70"),
        (0.07, "got 0.07"),
        ("70 furlongs", "unknown unit 'furlongs' (use one of m, cm, mm"),
        ("60 deg", "got '60 deg' (an angle)"),
        ("38 MPa", "got '38 MPa' (a stress)"),
        ("seventy mm", "expected a length such as '70 mm', got 'seventy mm'"),
        ("1e999 m", "(not finite)"),
        ("", "expected a length"),
    ],
)
def test_bad_quantities_name_the_field(value, message):
    with pytest.raises(UnitError) as err:
        parse_quantity(value, "length", "geometry.wellbore.diameter")
    assert message in str(err.value)
    assert err.value.path == "geometry.wellbore.diameter"


def test_unit_errors_are_value_errors_with_a_path():
    with pytest.raises(ValueError, match="unknown dimension"):
        parse_quantity("1 m", "charm")
    err = FieldError("diameters[2]", "must be positive")
    moved = err.within("geometry.perforations[0]")
    assert str(moved) == "geometry.perforations[0].diameters[2]: must be positive"
    assert join_path("geometry.perforations", "[1]") == "geometry.perforations[1]"
    assert join_path("", "name") == "name"


def test_format_quantity_round_trips():
    assert format_quantity(0.034859, "mm") == "34.86 mm"
    assert parse_quantity(format_quantity(73e6, "MPa"), "stress") == pytest.approx(73e6)
    with pytest.raises(ValueError, match="unknown unit"):
        format_quantity(1.0, "parsec")


def test_stresses_are_echoed_as_a_scene_writes_them():
    assert show_stress(-5e6) == "-5 MPa"
    assert show_stress(8.402e9) == "8.402 GPa"
    assert show_stress(2500.0) == "2.5 kPa"
    assert show_stress(12.0) == "12 Pa" and show_stress(0.0) == "0 Pa"
    assert show_stress(float("nan")) == "nan Pa"


def test_a_scene_s_bad_stress_is_echoed_in_a_readable_unit():
    from hfcdem.config.scene import load_scene
    from hfcdem.config.tables import SceneError

    scene = "meshes/scenes/borehole_seepage.toml"
    negative = r"rock\.tensile_strength: must not be negative, got -5 MPa"
    with pytest.raises(SceneError, match=negative):
        load_scene(scene, "coarse", overrides={"rock.tensile_strength": "-5 MPa"})
    with pytest.raises(SceneError, match=r"injection\.pressure_step: .* got -100 kPa"):
        load_scene(scene, "coarse", overrides={"injection.pressure_step": "-100 kPa"})
