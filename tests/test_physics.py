"""The physics sections of scene files: units, defaults and errors that name the key."""

import inspect
import math

import pytest

from hfcdem.config.scene import parse_scene
from hfcdem.config.tables import SceneError

GEOMETRY = {"catalogue": "borehole_plate"}
PHYSICS = {
    "rock": {
        "youngs_modulus": "21.5 GPa",
        "poisson_ratio": 0.25,
        "tensile_strength": "3 MPa",
        "cohesion": "17 MPa",
    },
    "stress": {"sh_max": "73 MPa", "sh_min": "60 MPa", "sv": "76 MPa"},
    "injection": {"rate": "1e-7 m3/s", "duration": "60 s"},
}


def scene(**changes):
    doc = {"geometry": dict(GEOMETRY), **{k: dict(v) for k, v in PHYSICS.items()}}
    for dotted, value in changes.items():
        section, key = dotted.split("__")
        doc.setdefault(section, {})
        if value is None:
            doc[section].pop(key, None)
        else:
            doc[section][key] = value
    return parse_scene(doc)


def test_a_minimal_physics_scene_is_complete_with_defaults():
    phys = scene().physics
    assert phys.rock.youngs_modulus == pytest.approx(21.5e9)
    assert phys.interfaces.tensile_strength == pytest.approx(3e6)
    assert phys.stress.sh_min == pytest.approx(60e6)
    assert phys.injection.value_at(10.0) == pytest.approx(1e-7)
    assert phys.duration == pytest.approx(60.0)
    assert phys.fluid.viscosity == pytest.approx(1e-3)
    assert phys.solver.fidelity == "viscous"
    assert phys.interfaces.break_rule == "most_overstressed"
    # what was assumed is listed, so a run can print it
    assert "fluid.viscosity" in phys.defaulted
    assert "rock.friction_angle" in phys.defaulted
    assert "rock.youngs_modulus" not in phys.defaulted


def test_units_convert():
    phys = scene(
        fluid__viscosity="100 cP", rock__friction_angle="35 deg", solver__time_step="500 ms"
    ).physics
    assert phys.fluid.viscosity == pytest.approx(0.1)
    assert phys.interfaces.friction_angle == pytest.approx(35.0)
    assert phys.solver.time_step == pytest.approx(0.5)
    assert math.isfinite(phys.interfaces.friction)


def test_schedules():
    phys = scene(
        injection__rate=None,
        injection__pressure_schedule=[["0 s", "0 MPa"], ["10 s", "40 MPa"]],
    ).physics
    assert not phys.injection.rate_controlled
    assert phys.injection.value_at(5.0) == pytest.approx(20e6)


def test_cavity_options():
    phys = scene().physics
    assert (phys.wellbore, phys.wall_film, phys.wall_joints) == ("cased", None, "dry")
    assert "injection.wellbore" in phys.defaulted
    phys = scene(
        injection__wellbore="open", injection__wall_film="5 um", injection__wall_joints="wet"
    ).physics
    assert (phys.wellbore, phys.wall_joints) == ("open", "wet")
    assert phys.wall_film == pytest.approx(5e-6)
    assert scene(injection__wellbore="drilled").physics.wellbore == "drilled"
    # where a run ends is a run-control choice, not an assumption to list
    assert phys.until == "end" and "injection.until" not in phys.defaulted
    assert scene(injection__until="first crack").physics.until == "first crack"


@pytest.mark.parametrize(
    "changes, key",
    [
        ({"rock__poisson_ratio": 0.5}, "rock.poisson_ratio"),
        ({"rock__tensile_strength": "-1 MPa"}, "rock.tensile_strength"),
        ({"rock__youngs_modulus": 21.5e9}, "rock.youngs_modulus"),  # a number without unit
        ({"rock__colour": "grey"}, "rock.colour"),
        ({"stress__sh_min": "60 Pa"}, "stress.sh_min"),  # MPa typed as Pa
        ({"stress__sh_min": None}, "stress.sh_min"),
        ({"injection__rate": "1e-7 m3"}, "injection.rate"),
        ({"injection__pressure_schedule": [["0 s", "1 MPa"]]}, "injection"),
        ({"solver__fidelity": "exact"}, "solver.fidelity"),
        ({"fluid__viscosity": "-1 mPa.s"}, "viscosity"),
        ({"injection__wellbore": "steel"}, "injection.wellbore"),
        ({"injection__wall_film": "5 m"}, "injection.wall_film"),
        ({"injection__wall_film": "0 um"}, "injection.wall_film"),
        ({"injection__wall_film": 5e-6}, "injection.wall_film"),  # a number without unit
        ({"injection__wall_joints": "damp"}, "injection.wall_joints"),
        ({"injection__until": "breakdown"}, "injection.until"),
        ({"injection__until": True}, "injection.until"),
        ({"solver__linear_solver": "lu"}, "solver.linear_solver"),
        ({"solver__solid": "partial"}, "solver.solid"),
        ({"solver__solid": "reduced", "solver__degree": 2}, "solver.solid"),
        ({"solver__band_threshold": 0.0}, "solver.band_threshold"),
        ({"solver__band_threshold": 1.5}, "solver.band_threshold"),
        ({"solver__band_rings": -1}, "solver.band_rings"),
        ({"solver__band_rings": 1.5}, "solver.band_rings"),
        ({"solver__contact_hysteresis": "yes"}, "solver.contact_hysteresis"),
        ({"solver__contact_hysteresis": 1}, "solver.contact_hysteresis"),
        ({"solver__max_pressure_change": 0.0}, "solver.max_pressure_change"),
        ({"solver__max_pressure_change": 1e-6}, "solver.max_pressure_change"),
        ({"solver__max_pressure_change": 2.0}, "solver.max_pressure_change"),
        ({"solver__max_pressure_change": "2 %"}, "solver.max_pressure_change"),
        ({"solver__max_pressure_change": float("nan")}, "solver.max_pressure_change"),
        (
            {"solver__max_pressure_change": 0.02, "injection__wall_joints": "seepage"},
            "solver.max_pressure_change",
        ),
        ({"solver__break_landing": "late"}, "solver.break_landing"),
        ({"solver__break_landing": "step"}, "solver.break_landing"),  # not a seepage run
        ({"solver__break_landing": "tolerance"}, "solver.break_landing"),
        ({"solver__max_breaks_per_iteration": 0}, "solver.max_breaks_per_iteration"),
        ({"solver__max_breaks_per_iteration": -1}, "solver.max_breaks_per_iteration"),
        ({"solver__max_breaks_per_iteration": 1.5}, "solver.max_breaks_per_iteration"),
        ({"injection__extra_volume": "1 MPa"}, "injection.extra_volume"),
        ({"injection__extra_volume": "-1 L"}, "injection.extra_volume"),
        # ranges the dataclasses check name the scene key, not the field
        ({"rock__spring_factor": 0}, "rock.spring_factor"),
        ({"rock__weibull_modulus": 0.01}, "rock.weibull_modulus"),
        ({"fluid__viscosity": "1e9 Pa.s"}, "fluid.viscosity"),
        ({"stress__sh_max": "5 MPa"}, "stress.sh_max"),
    ],
)
def test_bad_input_names_the_key(changes, key):
    with pytest.raises(SceneError) as err:
        scene(**changes)
    assert key in str(err.value)


def test_errors_in_several_sections_are_said_at_once():
    # before, only the first section's came, and the next run found the next one
    with pytest.raises(SceneError) as err:
        scene(rock__poisson_ratio=0.6, fluid__viscosity="1e9 Pa.s", solver__band_rings=-1)
    said = str(err.value)
    assert said.startswith("3 sections have an error:")
    lines = said.splitlines()[1:]
    assert [line.split(":")[0].strip() for line in lines] == [
        "rock.poisson_ratio", "fluid.viscosity", "solver.band_rings"
    ]  # fmt: skip
    # one error keeps its one-line form: the key first
    with pytest.raises(SceneError, match=r"^solver\.band_rings: "):
        scene(solver__band_rings=-1)
    # a geometry error comes with the physics' ones
    with pytest.raises(SceneError) as err:
        scene(geometry__catalogue="no_such_scene", fluid__viscosity="1e9 Pa.s")
    lines = str(err.value).splitlines()
    assert lines[0] == "2 sections have an error:"
    assert lines[1].startswith("  geometry.catalogue: ") and lines[2].startswith("  fluid.")
    # a unit error keeps its key as the error's path
    with pytest.raises(SceneError) as err:
        scene(rock__youngs_modulus="21.5 m", fluid__viscosity="1e9 Pa.s")
    assert "  rock.youngs_modulus: " in str(err.value)
    with pytest.raises(SceneError) as err:
        scene(rock__youngs_modulus="21.5 m")
    assert err.value.path == "rock.youngs_modulus"


def test_extra_volume_takes_a_unit_or_a_number_in_m3():
    assert scene().physics.extra_volume == 0.0
    assert scene(injection__extra_volume="0.5 L").physics.extra_volume == pytest.approx(5e-4)
    assert scene(injection__extra_volume="2 bbl").physics.extra_volume == pytest.approx(0.31797459)
    assert scene(injection__extra_volume=0.001).physics.extra_volume == 0.001
    assert scene(solver__max_breaks_per_iteration=3).physics.solver.max_breaks_per_iteration == 3


def test_output_section():
    phys = scene(output__interval="5 s", output__pictures=False).physics
    assert phys.output_interval == pytest.approx(5.0)
    assert phys.pictures is False
    with pytest.raises(SceneError, match=r"output\.interval"):
        scene(output__interval="-5 s")
    with pytest.raises(SceneError, match=r"output\.pictures"):
        scene(output__pictures="yes")
    with pytest.raises(SceneError, match=r"output\.colour"):
        scene(output__colour="red")


def test_max_pressure_change_is_a_fraction_or_none():
    assert scene().physics.solver.max_pressure_change == math.inf
    assert scene(solver__max_pressure_change=0.02).physics.solver.max_pressure_change == 0.02
    unbounded = scene(solver__max_pressure_change=math.inf).physics.solver
    assert unbounded.max_pressure_change == math.inf


def test_contact_hysteresis_is_read_as_a_flag():
    assert scene(solver__contact_hysteresis=False).physics.solver.contact_hysteresis is False
    assert scene().physics.solver.contact_hysteresis is True
    seepage = scene(injection__wall_joints="seepage").physics
    assert seepage.solver.contact_hysteresis is True
    assert "solver.contact_hysteresis" in seepage.defaulted


def test_break_landing_is_exact_unless_a_seepage_run_says_otherwise():
    assert scene().physics.solver.break_landing == "exact"
    for landing in ("step", "tolerance"):
        seepage = scene(injection__wall_joints="seepage", solver__break_landing=landing).physics
        assert seepage.solver.break_landing == landing


def test_every_default_has_one_home():
    # a scene that says nothing gets what the library classes say, field by field
    from hfcdem.config.materials import Fluid, InterfaceModel
    from hfcdem.config.physics import SolverSettings
    from hfcdem.coupling.hydrofrac import FlowSettings
    from hfcdem.solid.cdem import CDEMSolid

    solver, flow, model = SolverSettings(), FlowSettings(cavity=("wall",)), InterfaceModel()
    assert solver.fidelity == flow.fidelity
    assert solver.filling == flow.filling
    assert solver.time_step == flow.dt_initial
    assert solver.max_time_step == flow.dt_max
    assert solver.break_tolerance == flow.break_tolerance
    assert solver.max_pressure_change == flow.max_pressure_change
    assert solver.max_breaks_per_iteration == flow.max_breaks_per_iteration
    assert solver.break_rule == model.break_rule
    assert solver.debris == flow.debris
    assert solver.contact_hysteresis == flow.contact_hysteresis
    solid = inspect.signature(CDEMSolid).parameters
    assert solver.solid == solid["mode"].default
    assert (solver.band_threshold, solver.band_rings) == solid["band"].default
    phys = scene().physics
    assert phys.solver == solver
    assert phys.fluid == Fluid()
    assert phys.interfaces.alpha == model.alpha
    assert phys.interfaces.friction_angle == pytest.approx(model.friction_angle)


def test_an_unknown_key_lists_the_optional_keys_of_its_table_too():
    with pytest.raises(SceneError) as err:
        scene(rock__tensile_strenght="3 MPa")
    listed = str(err.value).split("this table takes: ")[1]
    for key in ("tensile_strength", "weibull_modulus", "strength_length", "joint_aperture"):
        assert key in listed
    with pytest.raises(SceneError) as err:
        scene(output__intervl="1 s")
    assert "interval" in str(err.value).split("this table takes: ")[1]
