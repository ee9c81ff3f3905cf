"""The physics sections of a scene file: rock, stress, fluid, injection or load, solver.

Every dimensional value carries its unit (``"21.5 GPa"``, ``"1e-7 m3/s"``);
fields left out take the defaults below, and :attr:`Physics.defaulted` lists
them so a run's record can print what was assumed.  Any invalid field raises
:class:`~hfcdem.config.tables.SceneError` naming it, before anything is meshed.

.. code-block:: toml

    [rock]                      # ElasticMaterial + InterfaceModel
    youngs_modulus = "21.5 GPa"
    poisson_ratio = 0.25
    tensile_strength = "3 MPa"
    cohesion = "17 MPa"
    friction_angle = "30 deg"
    weibull_modulus = 5         # optional scatter of the strengths
    spring_factor = 100         # alpha in kn = alpha E / h

    [stress]                    # compression positive
    sh_max = "73 MPa"
    sh_min = "60 MPa"
    sv = "76 MPa"
    azimuth = "0 deg"           # of SH from the x axis

    [fluid]
    viscosity = "1 mPa.s"
    bulk_modulus = "2.2 GPa"
    density = "1000 kg/m3"
    residual_aperture = "1 um"

    [injection]                 # exactly one of rate, rate_schedule, pressure_schedule
    rate = "1e-7 m3/s"
    duration = "60 s"
    initial_pressure = "0 MPa"
    extra_volume = "0 m3"       # storage outside the model (not yet a unit: m3 as a number)
    wellbore = "cased"          # or "open": does the pressure load the wellbore wall too?
    wall_film = "5 um"          # fluid storage = film thickness x pressurised wall area
    wall_joints = "wet"         # "dry", "wet" (the wall's) or "permeated" (open cracks' too)
    rigid_cavity = false        # true: the stored volume ignores the wall motion

    [load]                      # instead of [injection]: one static solve
    crack_pressure = "22 MPa"   # on the faces of the pre-existing crack (tag 'crack');
                                # the springs stay elastic (hfcdem.workflows.static)

    [output]
    interval = "5 s"            # fields over time (default: 20 frames per run)
    pictures = true             # PNG pictures of the fracture pattern (PyVista)

    [solver]
    fidelity = "uniform"        # or "viscous"
    filling = "saturation"      # or "no_lag"
    degree = 1                  # DG1 or DG2 blocks
    time_step = "0.5 s"
    max_time_step = "5 s"
    break_rule = "all"
    max_breaks_per_iteration = 1
    strength_points = "vertices" # or "midpoint": where a spring's strength is checked
    break_tolerance = 0.01      # a step may overshoot the next break by this fraction
    linear_solver = "auto"      # "direct" (MUMPS LDL^T), "iterative" (CG + GAMG) or "auto":
                                # direct up to 300k unknowns
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from hfcdem.config.tables import SceneError, TomlTable
from hfcdem.config.units import parse_quantity
from hfcdem.flow.fluid import Fluid, Injection
from hfcdem.solid.elastic import ElasticMaterial, InSituStress
from hfcdem.solid.interfaces import InterfaceModel

PHYSICS_SECTIONS = ("rock", "stress", "fluid", "injection", "load", "solver", "output")

# in-situ stresses below this are almost surely MPa values typed with "Pa"
_SMALLEST_STRESS = 1e3  # Pa
_LARGEST_STRESS = 1e9  # Pa


@dataclass(frozen=True)
class SolverSettings:
    """Numerical choices of a run (SI units)."""

    fidelity: str = "uniform"
    filling: str = "saturation"
    degree: int = 1
    time_step: float = 0.5
    max_time_step: float = 5.0
    break_rule: str = "all"
    max_breaks_per_iteration: int | None = None
    strength_points: str = "vertices"
    break_tolerance: float = 0.01
    linear_solver: str = "auto"


@dataclass(frozen=True)
class StaticLoad:
    """A pressure held on the pre-existing crack faces, solved once, elastic (no flow)."""

    crack_pressure: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.crack_pressure) and abs(self.crack_pressure) <= 1e9):
            raise ValueError(
                f"load.crack_pressure: expected -1 GPa to 1 GPa, got {self.crack_pressure!r} Pa"
            )


@dataclass(frozen=True)
class Physics:
    """Everything a run needs besides the mesh, complete when constructed.

    A coupled run has ``injection`` (and ``load`` None); a static run has
    ``load`` (and ``injection`` None, ``duration`` 0).
    """

    rock: ElasticMaterial
    interfaces: InterfaceModel
    stress: InSituStress
    fluid: Fluid
    injection: Injection | None
    duration: float
    initial_pressure: float
    extra_volume: float
    solver: SolverSettings
    wellbore: str = "cased"
    wall_film: float | None = None
    wall_joints: str = "dry"
    rigid_cavity: bool = False
    output_interval: float | None = None  # None: duration / 20
    pictures: bool = True
    load: StaticLoad | None = None
    defaulted: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if (self.injection is None) == (self.load is None):
            raise ValueError("a scene has exactly one of [injection] and [load]")


def parse_physics(data: Mapping[str, Any]) -> Physics:
    """Read the physics sections of a parsed scene document (see the module docstring)."""
    defaulted: list[str] = []

    def section(name: str) -> Any:
        return TomlTable(data.get(name, {}), name)

    def get(table: Any, key: str, kind: str, default: Any, **kw: Any) -> Any:
        if not table.has(key):
            defaulted.append(table.sub(key))
        if kind == "number":
            return table.number(key, default, **kw)
        if kind == "string":
            return table.string(key, default, **kw)
        return table.quantity(key, kind, default)

    def check(ok: bool, path: str, reason: str) -> None:
        if not ok:
            raise SceneError(path, reason)

    rock = section("rock")
    e = rock.quantity("youngs_modulus", "stress")
    nu = rock.number("poisson_ratio")
    check(1e6 <= e <= 1e13, "rock.youngs_modulus", f"expected 1 MPa to 10 TPa, got {e:g} Pa")
    check(-1.0 < nu < 0.5, "rock.poisson_ratio", f"expected a value in (-1, 0.5), got {nu!r}")
    t0 = rock.quantity("tensile_strength", "stress")
    c0 = rock.quantity("cohesion", "stress")
    for key, value in (("tensile_strength", t0), ("cohesion", c0)):
        check(value >= 0.0, f"rock.{key}", f"a strength must not be negative, got {value:g} Pa")
    phi = math.degrees(get(rock, "friction_angle", "angle", math.radians(30.0)))
    check(0.0 <= phi < 90.0, "rock.friction_angle", f"expected 0 to 90 deg, got {phi:g} deg")
    weibull = rock.number("weibull_modulus", None) if rock.has("weibull_modulus") else None
    alpha = get(rock, "spring_factor", "number", 100.0)
    rock.finish()

    st = section("stress")
    stresses = {}
    for key in ("sh_max", "sh_min", "sv"):
        value = st.quantity(key, "stress")
        check(
            value == 0.0 or _SMALLEST_STRESS <= abs(value) <= _LARGEST_STRESS,
            f"stress.{key}",
            f"{value:g} Pa is not a plausible in-situ stress (1 kPa to 1 GPa); did you mean MPa?",
        )
        stresses[key] = value
    azimuth = math.degrees(get(st, "azimuth", "angle", 0.0))
    st.finish()

    fl = section("fluid")
    fluid_kw = {
        "viscosity": get(fl, "viscosity", "viscosity", 1e-3),
        "bulk_modulus": get(fl, "bulk_modulus", "stress", 2.2e9),
        "density": get(fl, "density", "density", 1000.0),
        "residual_aperture": get(fl, "residual_aperture", "length", 0.0),
    }
    fl.finish()

    static = "load" in data
    if static and "injection" in data:
        raise SceneError(
            "load", "give [injection] (a coupled run) or [load] (one static solve), not both"
        )
    if static:
        ld = section("load")
        pressure = ld.quantity("crack_pressure", "stress")
        check(
            abs(pressure) <= _LARGEST_STRESS,
            "load.crack_pressure",
            f"expected -1 GPa to 1 GPa, got {pressure:g} Pa",
        )
        ld.finish()
        load: StaticLoad | None = StaticLoad(pressure)
        injection, duration, p0, extra, wellbore = None, 0.0, 0.0, 0.0, "cased"
        film, joints, rigid = None, "dry", False
    else:
        load = None
        inj = section("injection")
        given = [k for k in ("rate", "rate_schedule", "pressure_schedule") if inj.has(k)]
        check(
            len(given) == 1,
            "injection",
            "give exactly one of rate, rate_schedule, pressure_schedule"
            + (f" (got {', '.join(given)})" if given else ""),
        )
        if given[0] == "rate":
            injection = Injection.constant_rate(inj.quantity("rate", "flow_rate"))
        else:
            points = inj.raw(given[0])
            dim = "flow_rate" if given[0] == "rate_schedule" else "stress"
            check(
                isinstance(points, list) and len(points) > 0, inj.sub(given[0]), "expected a list"
            )
            pairs = []
            for i, pt in enumerate(points):
                path = f"{inj.sub(given[0])}[{i}]"
                check(isinstance(pt, list) and len(pt) == 2, path, "expected [time, value]")
                pairs.append(
                    (parse_quantity(pt[0], "time", path), parse_quantity(pt[1], dim, path))
                )
            try:
                injection = (
                    Injection.rate_schedule(pairs)
                    if given[0] == "rate_schedule"
                    else Injection.pressure_schedule(pairs)
                )
            except ValueError as exc:
                raise SceneError(inj.sub(given[0]), str(exc)) from None
        duration = inj.quantity("duration", "time")
        check(duration > 0.0, "injection.duration", f"must be positive, got {duration:g} s")
        p0 = get(inj, "initial_pressure", "stress", 0.0)
        extra = get(inj, "extra_volume", "number", 0.0)
        check(extra >= 0.0, "injection.extra_volume", f"must be >= 0 m3, got {extra!r}")
        # perforated wells are cased: only the tunnels are open hole
        wellbore = get(inj, "wellbore", "string", "cased", choices=("cased", "open"))
        film = inj.quantity("wall_film", "length") if inj.has("wall_film") else None
        joints = get(inj, "wall_joints", "string", "dry", choices=("dry", "wet", "permeated"))
        rigid = inj.raw("rigid_cavity") if inj.has("rigid_cavity") else False
        check(
            isinstance(rigid, bool), "injection.rigid_cavity", f"expected true or false: {rigid!r}"
        )
        check(
            film is None or 0.0 < film <= 1e-2,
            "injection.wall_film",
            f"expected a thickness in (0, 10 mm], got {film!r} m",
        )
        inj.finish()

    out = section("output")
    interval = out.quantity("interval", "time") if out.has("interval") else None
    check(
        interval is None or interval > 0.0,
        "output.interval",
        f"must be a positive time, got {interval!r} s",
    )
    pictures = out.raw("pictures", True, "true or false") if out.has("pictures") else True
    check(isinstance(pictures, bool), "output.pictures", f"expected true or false: {pictures!r}")
    out.finish()

    so = section("solver")
    solver = SolverSettings(
        fidelity=get(so, "fidelity", "string", "uniform", choices=("uniform", "viscous")),
        filling=get(so, "filling", "string", "saturation", choices=("saturation", "no_lag")),
        degree=get(so, "degree", "number", 1, integer=True),
        time_step=get(so, "time_step", "time", 0.5),
        max_time_step=get(so, "max_time_step", "time", 5.0),
        break_rule=get(
            so, "break_rule", "string", "all", choices=("all", "most_overstressed", "cap")
        ),
        max_breaks_per_iteration=(
            so.number("max_breaks_per_iteration", integer=True)
            if so.has("max_breaks_per_iteration")
            else None
        ),
        strength_points=get(
            so, "strength_points", "string", "vertices", choices=("vertices", "midpoint")
        ),
        break_tolerance=get(so, "break_tolerance", "number", 0.01),
        linear_solver=get(
            so, "linear_solver", "string", "auto", choices=("auto", "direct", "iterative")
        ),
    )
    check(
        0.0 < solver.break_tolerance <= 1.0,
        "solver.break_tolerance",
        f"expected a fraction in (0, 1], got {solver.break_tolerance!r}",
    )
    check(solver.degree in (1, 2), "solver.degree", f"expected 1 or 2, got {solver.degree!r}")
    for key in ("time_step", "max_time_step"):
        value = getattr(solver, key)
        check(value > 0.0, f"solver.{key}", f"must be a positive time, got {value:g} s")
    so.finish()

    try:
        return Physics(
            rock=ElasticMaterial(e, nu),
            interfaces=InterfaceModel(
                alpha=alpha,
                tensile_strength=t0,
                cohesion=c0,
                friction_angle=phi,
                weibull_modulus=weibull,
                break_rule=solver.break_rule,
            ),
            stress=InSituStress(
                sh_max=stresses["sh_max"],
                sh_min=stresses["sh_min"],
                sv=stresses["sv"],
                azimuth_sh=azimuth,
            ),
            fluid=Fluid(**fluid_kw),
            injection=injection,
            duration=duration,
            initial_pressure=p0,
            extra_volume=float(extra),
            solver=solver,
            wellbore=wellbore,
            wall_film=film,
            wall_joints=joints,
            rigid_cavity=rigid,
            output_interval=interval,
            pictures=pictures,
            load=load,
            defaulted=tuple(defaulted),
        )
    except ValueError as exc:  # a range the dataclasses check themselves
        raise SceneError("", str(exc)) from None


__all__ = [
    "PHYSICS_SECTIONS",
    "Physics",
    "SolverSettings",
    "StaticLoad",
    "parse_physics",
]
