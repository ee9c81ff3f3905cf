"""Material and loading data: validation names the field, derived values are right."""

import numpy as np
import pytest

from hfcdem.config.materials import ElasticMaterial, Fluid, Injection, InSituStress, InterfaceModel


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"youngs_modulus": -1.0}, "youngs_modulus"),
        ({"youngs_modulus": 21.5e15}, "youngs_modulus must be in"),
        ({"poisson_ratio": 0.5}, "poisson_ratio must be in"),
        ({"poisson_ratio": float("nan")}, "poisson_ratio"),
    ],
)
def test_material_validation_names_the_field(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ElasticMaterial(**{"youngs_modulus": 21.5e9, "poisson_ratio": 0.25, **kwargs})


def test_in_situ_validation_and_rotation():
    with pytest.raises(ValueError, match=r"sh_max \(1 MPa\) must be >= sh_min \(2 MPa\)"):
        InSituStress(1e6, 2e6)
    with pytest.raises(ValueError, match=r"sv must be a stress below 10 GPa, got 4\.3e\+04 GPa"):
        InSituStress(38e6, 34e6, sv=43e12)
    rotated = InSituStress(6e6, 1e6, azimuth_sh=90.0).tensor(2)
    assert np.allclose(rotated, -np.diag([1e6, 6e6]))
    assert InSituStress(6e6, 1e6, sv=9e6).tensor(3)[2, 2] == -9e6


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"alpha": 0.0}, "alpha"),
        ({"tensile_strength": -1.0}, "tensile_strength"),
        ({"cohesion": float("nan")}, "cohesion"),
        ({"friction_angle": 90.0}, "friction_angle"),
        ({"weibull_modulus": 0.0}, "weibull_modulus"),
        ({"break_rule": "some"}, "break_rule"),
        ({"max_breaks": 0}, "max_breaks"),
        ({"residual_stiffness": 1.0}, "residual_stiffness"),
    ],
)
def test_interface_model_validation_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        InterfaceModel(**kwargs)


def test_cubic_law():
    fluid = Fluid(viscosity=1e-3)
    assert fluid.conductivity(np.array([1e-3]))[0] == pytest.approx(1e-9 / 12e-3)


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"viscosity": -1.0}, "viscosity"),
        ({"bulk_modulus": 0.0}, "bulk_modulus"),
        ({"residual_aperture": -1e-6}, "residual_aperture"),
        ({"gravity": (0.0, "x")}, "could not convert|gravity"),
    ],
)
def test_bad_fluid_names_the_field(kwargs, key):
    with pytest.raises(ValueError, match=key):
        Fluid(**kwargs)


def test_rate_schedule_volume_is_exact_for_linear_pieces():
    inj = Injection.rate_schedule([(0.0, 0.0), (10.0, 1e-3), (20.0, 1e-3)])
    assert inj.value_at(5.0) == pytest.approx(5e-4)
    assert inj.volume_between(0.0, 20.0) == pytest.approx(0.5 * 10 * 1e-3 + 10 * 1e-3)
    assert inj.volume_between(4.0, 12.0) == pytest.approx(0.5 * (4e-4 + 1e-3) * 6.0 + 2.0 * 1e-3)
    assert Injection.constant_rate(2e-6).volume_between(1.0, 3.0) == pytest.approx(4e-6)


def test_bad_schedules_are_named():
    with pytest.raises(ValueError, match="increasing"):
        Injection.rate_schedule([(1.0, 1e-6), (0.5, 1e-6)])
    with pytest.raises(ValueError, match="injection rate"):
        Injection.constant_rate(-1e-6)
    with pytest.raises(ValueError, match="no prescribed volume"):
        Injection.pressure_schedule([(0.0, 1e6)]).volume_between(0.0, 1.0)
