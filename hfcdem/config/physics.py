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
    joint_aperture = "1 um"     # hydraulic aperture of the intact joints (wall_joints = "seepage")
    joint_reference_size = "5 mm"  # optional: cell size at which joint_aperture holds
                                # (apertures then follow the mesh size: hfcdem.flow.apertures)
    weibull_modulus = 5         # optional scatter of the strengths
    strength_length = "0 mm"    # the length the rock resists over (0: strength at a point;
                                # > 0: the check reads the stress filtered over it)
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

    [injection]                 # exactly one of rate, rate_schedule, pressure_schedule,
                                # pressure_rate ("1 MPa/s": a ramp from initial_pressure
                                # to max_pressure, or over duration; pressure_step sets
                                # the steps of a seepage ramp)
    rate = "1e-7 m3/s"
    duration = "60 s"
    initial_pressure = "0 MPa"
    extra_volume = "0 m3"       # storage outside the model (a bare number is m3)
    wellbore = "cased"          # "cased" (wall at its in-situ traction), "drilled" (drilled at
                                # initial_pressure, then held by its casing) or "open" (pumped)
    wall_film = "5 um"          # fluid storage = film thickness x pressurised wall area
    wall_joints = "wet"         # "dry", "wet" (the wall's), "permeated" (open cracks' too) or
                                # "seepage" (joints fill in time; a pressure_schedule ramp)
    joint_pressure = "30 MPa"   # seepage, pumped: the zone's joints start full at this pore
                                # pressure (left out: they start dry)
    rigid_cavity = false        # true: the stored volume ignores the wall motion
    until = "end"               # or "first crack": end the run on the step that breaks the
                                # first interface (where and at what pressure the rock
                                # starts to crack, without the cascade after it)

    [load]                      # instead of [injection]: one static solve
    crack_pressure = "22 MPa"   # on the faces of the pre-existing crack (tag 'crack');
                                # the springs stay elastic (hfcdem.workflows.static)

    [output]
    interval = "5 s"            # fields over time (default: 20 frames per run)
    pictures = true             # PNG pictures of the fracture pattern (PyVista)

    [solver]
    fidelity = "viscous"        # or "uniform"
    filling = "saturation"      # or "no_lag"
    degree = 1                  # DG1 or DG2 blocks
    time_step = "10 ms"         # the first step
    max_time_step = "inf s"     # no cap unless given
    break_rule = "most_overstressed"  # or "all", "cap"
    max_breaks_per_iteration = 1
    strength_points = "vertices" # or "midpoint": where a spring's strength is checked
    break_tolerance = 0.01      # a step may overshoot the next break by this fraction
                                # (break_landing = "tolerance": the share of the cavity
                                # pressure a pumped step may move without landing)
    break_landing = "exact"     # pumped seepage: "exact" shortens a step onto its first break;
                                # "step" breaks what is overstressed at the step's end (at
                                # most a step late, far fewer steps); "tolerance" lands
                                # only a step that moved the cavity pressure by more than
                                # break_tolerance of it
    max_pressure_change = inf   # a step may move the cavity pressure by at most this
                                # fraction of it (at least of 1 MPa), else it is halved;
                                # 0.001 to 1
    linear_solver = "auto"      # "direct" (MUMPS LDL^T), "iterative" (CG + GAMG) or "auto":
                                # direct up to 600k unknowns
    solid = "full"              # "full": DG springs on every interface of the zone (the
                                # reference); "reduced": springs only in a band that grows,
                                # continuous blocks elsewhere (DG1, direct; hfcdem.solid.band)
    debris = "stay"             # or "released": blocks cut loose at the cavity walls join the
                                # cavity's fluid (their faces at its pressure; a cased wall
                                # holds those against it); "stay": held by contact alone
    band_threshold = 0.3        # reduced: a glued interface joins the band when its traction
                                # (from the cells' stress) reaches this share of its strength
    band_rings = 2              # reduced: vertex rings of neighbours freed with each facet
    contact_hysteresis = true   # a broken interface that closed opens again only once the
                                # fluid pressure on it passes the one it closed at, or a facet
                                # of its cells breaks (no contact chatter at fine meshes)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from hfcdem.config.fingerprint import fingerprinted
from hfcdem.config.materials import (
    JOINT_HYDRAULIC_APERTURE,
    ElasticMaterial,
    Fluid,
    Injection,
    InSituStress,
    InterfaceModel,
    JointAperture,
)
from hfcdem.config.tables import SceneError, SceneErrors, TomlTable
from hfcdem.config.units import FieldError, parse_quantity, show_stress


def field_default(cls: type, name: str) -> Any:
    """Return the default of dataclass field ``name`` of ``cls``: the one home of a default."""
    return cls.__dataclass_fields__[name].default  # type: ignore[attr-defined]


WALL_JOINTS = ("dry", "wet", "permeated", "seepage")
# how the wellbore wall is loaded where the scene has tunnels: "cased", a tube set before
# the rock was stressed (the wall keeps its in-situ traction, a lab specimen's cast tube);
# "drilled", drilled in the stressed rock with fluid at the initial pressure and cased
# after (the wall keeps that pressure and the stress around the hole it made; the casing
# carries the pumping); "open", the wall takes the pumped pressure
WELLBORES = ("cased", "drilled", "open")
# where an injection run ends: at its duration, or on the step of its first crack
UNTIL = ("end", "first crack")
PHYSICS_SECTIONS = ("rock", "stress", "fluid", "injection", "load", "solver", "output")

# in-situ stresses below this are almost surely MPa values typed with "Pa"
_SMALLEST_STRESS = 1e3  # Pa
_LARGEST_STRESS = 1e9  # Pa


@fingerprinted
@dataclass(frozen=True)
class SolverSettings:
    """Numerical choices of a run (SI units).

    The defaults are the library's: those of :class:`FlowSettings`
    (``fidelity``, ``filling``, ``dt_initial``, ``dt_max``, ``break_tolerance``,
    ``max_pressure_change``),
    :class:`InterfaceModel` (``break_rule``) and :class:`CDEMSolid`; a test holds
    them equal.  The scene reader takes its defaults from these fields.
    """

    fidelity: str = "viscous"
    filling: str = "saturation"
    degree: int = 1
    time_step: float = 0.01
    max_time_step: float = math.inf
    break_rule: str = "most_overstressed"
    max_breaks_per_iteration: int | None = None
    strength_points: str = "vertices"
    break_tolerance: float = 0.01
    break_landing: str = "exact"
    max_pressure_change: float = math.inf
    linear_solver: str = "auto"
    solid: str = "full"
    band_threshold: float = 0.3
    band_rings: int = 2
    debris: str = "stay"
    contact_hysteresis: bool = True


@fingerprinted
@dataclass(frozen=True)
class StaticLoad:
    """A pressure held on the pre-existing crack faces, solved once, elastic (no flow)."""

    crack_pressure: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.crack_pressure) and abs(self.crack_pressure) <= 1e9):
            raise ValueError(
                "load.crack_pressure: expected -1 GPa to 1 GPa, "
                f"got {show_stress(self.crack_pressure)}"
            )


@fingerprinted
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
    solver: SolverSettings
    initial_pressure: float = 0.0
    extra_volume: float = 0.0
    wellbore: str = "cased"
    wall_film: float | None = None
    wall_joints: str = "dry"
    joint_pressure: float | None = None  # Pa, the joints' at t = 0 (seepage); None: dry
    joint_aperture: float = JOINT_HYDRAULIC_APERTURE  # m, the intact joints' (seepage)
    joint_reference_size: float | None = None  # m, cell size at which joint_aperture holds
    pressure_step: float | None = None  # Pa per step of a seepage ramp (None: time_step)
    rigid_cavity: bool = False
    until: str = "end"  # or "first crack" (UNTIL)
    output_interval: float | None = None  # None: duration / 20
    pictures: bool = True
    load: StaticLoad | None = None
    defaulted: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if (self.injection is None) == (self.load is None):
            raise ValueError("a scene has exactly one of [injection] and [load]")
        JointAperture(self.joint_aperture, self.joint_reference_size)  # checks both

    @property
    def joints(self) -> JointAperture:
        """The intact joints' aperture and the cell size it holds at."""
        return JointAperture(self.joint_aperture, self.joint_reference_size)


class _Reader:
    """The scene document and the list of fields it left to their defaults."""

    def __init__(self, data: Mapping[str, Any]) -> None:
        self.data = data
        self.defaulted: list[str] = []

    def section(self, name: str) -> TomlTable:
        return TomlTable(self.data.get(name, {}), name)

    def get(self, table: TomlTable, key: str, kind: str, default: Any, **kw: Any) -> Any:
        # default: a dataclass field, (cls, name), so each default has one home
        if isinstance(default, tuple):
            default = field_default(*default)
        if not table.has(key):
            self.defaulted.append(table.sub(key))
        if kind == "number":
            return table.number(key, default, **kw)
        if kind == "string":
            return table.string(key, default, **kw)
        if kind == "flag":
            value = table.raw(key, default, "true or false")
            _check(isinstance(value, bool), table.sub(key), f"expected true or false: {value!r}")
            return value
        return table.quantity(key, kind, default)


def _at_least_one(table: TomlTable, key: str) -> int | None:
    """Read an optional integer count that must be at least 1 (None when not given)."""
    if not table.has(key):
        return None
    value = int(table.number(key, integer=True))
    _check(value >= 1, table.sub(key), f"expected an integer of at least 1, got {value}")
    return value


def _check(ok: bool, path: str, reason: str) -> None:
    if not ok:
        raise SceneError(path, reason)


def _read_rock(r: _Reader) -> tuple[ElasticMaterial, dict[str, Any], JointAperture]:
    """[rock]: the elastic material, the interface model's fields, the joints' aperture."""
    rock = r.section("rock")
    e = rock.quantity("youngs_modulus", "stress")
    nu = rock.number("poisson_ratio")
    _check(
        1e6 <= e <= 1e13, "rock.youngs_modulus", f"expected 1 MPa to 10 TPa, got {show_stress(e)}"
    )
    _check(-1.0 < nu < 0.5, "rock.poisson_ratio", f"expected a value in (-1, 0.5), got {nu!r}")
    t0 = rock.quantity("tensile_strength", "stress")
    c0 = rock.quantity("cohesion", "stress")
    for key, value in (("tensile_strength", t0), ("cohesion", c0)):
        _check(value >= 0.0, f"rock.{key}", f"must not be negative, got {show_stress(value)}")
    phi = math.degrees(
        r.get(
            rock,
            "friction_angle",
            "angle",
            math.radians(field_default(InterfaceModel, "friction_angle")),
        )
    )
    _check(0.0 <= phi < 90.0, "rock.friction_angle", f"expected 0 to 90 deg, got {phi:g} deg")
    weibull = rock.number("weibull_modulus", None) if rock.has("weibull_modulus") else None
    alpha = r.get(rock, "spring_factor", "number", (InterfaceModel, "alpha"))
    aperture = r.get(rock, "joint_aperture", "length", (Physics, "joint_aperture"))
    _check(
        0.0 < aperture <= 1e-3,
        "rock.joint_aperture",
        f"expected a hydraulic aperture in (0, 1 mm], got {aperture!r} m",
    )
    size = None
    if rock.has("joint_reference_size"):
        size = rock.quantity("joint_reference_size", "length")
        _check(
            1e-5 <= size <= 10.0,
            "rock.joint_reference_size",
            f"expected the cell size at which joint_aperture holds, 10 um to 10 m, got {size!r} m",
        )
    # optional, and off unless given: not listed among the defaults a run assumed
    length = rock.quantity("strength_length", "length") if rock.has("strength_length") else 0.0
    _check(
        0.0 <= length <= 10.0,
        "rock.strength_length",
        f"expected the length the rock resists over, 0 (a point) to 10 m, got {length!r} m",
    )
    rock.finish()

    model = {
        "alpha": alpha,
        "strength_length": length,
        "tensile_strength": t0,
        "cohesion": c0,
        "friction_angle": phi,
        "weibull_modulus": weibull,
    }
    return ElasticMaterial(e, nu), model, JointAperture(aperture, size)


def _read_stress(r: _Reader) -> InSituStress:
    """[stress]: the in-situ principal stresses (compression positive) and SH's azimuth."""
    st = r.section("stress")
    stresses = {}
    for key in ("sh_max", "sh_min", "sv"):
        value = st.quantity(key, "stress")
        _check(
            value == 0.0 or _SMALLEST_STRESS <= abs(value) <= _LARGEST_STRESS,
            f"stress.{key}",
            f"{value:g} Pa is not a plausible in-situ stress (1 kPa to 1 GPa); did you mean MPa?",
        )
        stresses[key] = value
    azimuth = math.degrees(r.get(st, "azimuth", "angle", 0.0))
    st.finish()

    return InSituStress(
        sh_max=stresses["sh_max"],
        sh_min=stresses["sh_min"],
        sv=stresses["sv"],
        azimuth_sh=azimuth,
    )


def _read_fluid(r: _Reader) -> Fluid:
    """[fluid]: the injected fluid."""
    fl = r.section("fluid")
    fluid_kw = {
        "viscosity": r.get(fl, "viscosity", "viscosity", (Fluid, "viscosity")),
        "bulk_modulus": r.get(fl, "bulk_modulus", "stress", (Fluid, "bulk_modulus")),
        "density": r.get(fl, "density", "density", (Fluid, "density")),
        "residual_aperture": r.get(fl, "residual_aperture", "length", (Fluid, "residual_aperture")),
    }
    fl.finish()

    return Fluid(**fluid_kw)


def _read_schedule(inj: TomlTable) -> Injection | None:
    """Read exactly one of rate, rate_schedule, pressure_schedule, pressure_rate.

    ``pressure_rate`` returns None: the caller builds the ramp from the initial
    pressure over the duration.
    """
    keys = ("rate", "rate_schedule", "pressure_schedule", "pressure_rate")
    given = [k for k in keys if inj.has(k)]
    _check(
        len(given) == 1,
        "injection",
        "give exactly one of " + ", ".join(keys) + (f" (got {', '.join(given)})" if given else ""),
    )
    if given[0] == "pressure_rate":
        return None
    if given[0] == "rate":
        return Injection.constant_rate(inj.quantity("rate", "flow_rate"))
    points = inj.raw(given[0])
    dim = "flow_rate" if given[0] == "rate_schedule" else "stress"
    _check(isinstance(points, list) and len(points) > 0, inj.sub(given[0]), "expected a list")
    pairs = []
    for i, pt in enumerate(points):
        path = f"{inj.sub(given[0])}[{i}]"
        _check(isinstance(pt, list) and len(pt) == 2, path, "expected [time, value]")
        pairs.append((parse_quantity(pt[0], "time", path), parse_quantity(pt[1], dim, path)))
    try:
        if given[0] == "rate_schedule":
            return Injection.rate_schedule(pairs)
        return Injection.pressure_schedule(pairs)
    except ValueError as exc:
        raise SceneError(inj.sub(given[0]), str(exc)) from None


def _read_pump(r: _Reader) -> dict[str, Any]:
    """[injection] (a coupled run) or [load] (one static solve): Physics' fields."""
    static = "load" in r.data
    if static and "injection" in r.data:
        raise SceneError(
            "load", "give [injection] (a coupled run) or [load] (one static solve), not both"
        )
    if static:
        ld = r.section("load")
        pressure = ld.quantity("crack_pressure", "stress")
        _check(
            abs(pressure) <= _LARGEST_STRESS,
            "load.crack_pressure",
            f"expected -1 GPa to 1 GPa, got {show_stress(pressure)}",
        )
        ld.finish()
        load: StaticLoad | None = StaticLoad(pressure)
        injection, duration, p0, extra, wellbore = None, 0.0, 0.0, 0.0, "cased"
        film, joints, rigid, pressure_step, wet = None, "dry", False, None, None
        until = "end"
    else:
        load = None
        inj = r.section("injection")
        injection = _read_schedule(inj)
        p0 = r.get(inj, "initial_pressure", "stress", (Physics, "initial_pressure"))
        pressure_step = None
        if injection is None:  # pressure_rate: a linear ramp from p0
            injection, duration, pressure_step = _read_ramp(inj, p0)
        else:
            for key in ("max_pressure", "pressure_step"):  # not "unknown key": misplaced
                _check(
                    not inj.has(key),
                    f"injection.{key}",
                    "belongs to a pressure ramp: give it with pressure_rate",
                )
            duration = inj.quantity("duration", "time")
        _check(duration > 0.0, "injection.duration", f"must be positive, got {duration:g} s")
        extra = r.get(  # a volume with its unit; a bare number is m3 (older scenes)
            inj,
            "extra_volume",
            "volume" if isinstance(inj.data.get("extra_volume"), str) else "number",
            (Physics, "extra_volume"),
        )
        _check(extra >= 0.0, "injection.extra_volume", f"must be >= 0 m3, got {extra!r}")
        # perforated wells are cased: only the tunnels are open hole
        wellbore = r.get(inj, "wellbore", "string", (Physics, "wellbore"), choices=WELLBORES)
        # a run-control choice, not a physical assumption: not listed among the defaults
        until = inj.string("until", field_default(Physics, "until"), choices=UNTIL)
        film = inj.quantity("wall_film", "length") if inj.has("wall_film") else None
        joints = r.get(
            inj,
            "wall_joints",
            "string",
            (Physics, "wall_joints"),
            choices=WALL_JOINTS,
        )
        wet = inj.quantity("joint_pressure", "stress") if inj.has("joint_pressure") else None
        _check(
            wet is None or 0.0 <= wet <= _LARGEST_STRESS,
            "injection.joint_pressure",
            "expected a pore pressure in [0, 1 GPa], "
            f"got {show_stress(wet if wet is not None else math.nan)}",
        )
        _check(
            wet is None or joints == "seepage",
            "injection.joint_pressure",
            'the joints\' starting pressure is taken by a seepage run (wall_joints = "seepage") '
            "only; the other rungs have no fluid in intact joints",
        )
        rigid = inj.raw("rigid_cavity") if inj.has("rigid_cavity") else False
        _check(
            isinstance(rigid, bool), "injection.rigid_cavity", f"expected true or false: {rigid!r}"
        )
        _check(
            film is None or 0.0 < film <= 1e-2,
            "injection.wall_film",
            f"expected a thickness in (0, 10 mm], got {film!r} m",
        )
        inj.finish()

    return {
        "injection": injection,
        "duration": duration,
        "initial_pressure": p0,
        "extra_volume": float(extra),
        "wellbore": wellbore,
        "wall_film": film,
        "wall_joints": joints,
        "joint_pressure": wet,
        "pressure_step": pressure_step,
        "rigid_cavity": rigid,
        "until": until,
        "load": load,
    }


def _read_ramp(inj: TomlTable, p0: float) -> tuple[Injection, float, float | None]:
    """``pressure_rate`` with ``duration`` or ``max_pressure``, and ``pressure_step``."""
    rate = inj.quantity("pressure_rate", "pressure_rate")
    _check(
        0.0 < rate <= 1e12,
        "injection.pressure_rate",
        f"expected a rising pressure, 0 to 1 TPa/s, got {rate:g} Pa/s",
    )
    _check(
        inj.has("duration") != inj.has("max_pressure"),
        "injection",
        "a pressure_rate ramp takes duration or max_pressure (where it ends), one of them",
    )
    if inj.has("duration"):
        duration = inj.quantity("duration", "time")
    else:
        top = inj.quantity("max_pressure", "stress")
        _check(
            top > p0,
            "injection.max_pressure",
            f"must exceed initial_pressure {show_stress(p0)}, got {show_stress(top)}",
        )
        duration = (top - p0) / rate
    step = inj.quantity("pressure_step", "stress") if inj.has("pressure_step") else None
    _check(
        step is None or step > 0.0,
        "injection.pressure_step",
        f"must be a positive pressure, got {show_stress(step if step is not None else math.nan)}",
    )
    return (
        Injection.pressure_schedule([(0.0, p0), (duration, p0 + rate * duration)]),
        duration,
        step,
    )


def _read_output(r: _Reader) -> dict[str, Any]:
    """[output]: the frame interval and whether to draw pictures."""
    out = r.section("output")
    interval = out.quantity("interval", "time") if out.has("interval") else None
    _check(
        interval is None or interval > 0.0,
        "output.interval",
        f"must be a positive time, got {interval!r} s",
    )
    pictures = (
        out.raw("pictures", True, "true or false")
        if out.has("pictures")
        else field_default(Physics, "pictures")
    )
    _check(isinstance(pictures, bool), "output.pictures", f"expected true or false: {pictures!r}")
    out.finish()

    return {"output_interval": interval, "pictures": pictures}


def _read_solver(r: _Reader) -> SolverSettings:
    """[solver]: the numerical choices."""
    so = r.section("solver")
    solver = SolverSettings(
        fidelity=r.get(
            so, "fidelity", "string", (SolverSettings, "fidelity"), choices=("uniform", "viscous")
        ),
        filling=r.get(
            so, "filling", "string", (SolverSettings, "filling"), choices=("saturation", "no_lag")
        ),
        degree=r.get(so, "degree", "number", (SolverSettings, "degree"), integer=True),
        time_step=r.get(so, "time_step", "time", (SolverSettings, "time_step")),
        max_time_step=r.get(so, "max_time_step", "time", (SolverSettings, "max_time_step")),
        break_rule=r.get(
            so,
            "break_rule",
            "string",
            (SolverSettings, "break_rule"),
            choices=("all", "most_overstressed", "cap"),
        ),
        max_breaks_per_iteration=_at_least_one(so, "max_breaks_per_iteration"),
        strength_points=r.get(
            so,
            "strength_points",
            "string",
            (SolverSettings, "strength_points"),
            choices=("vertices", "midpoint"),
        ),
        break_tolerance=r.get(so, "break_tolerance", "number", (SolverSettings, "break_tolerance")),
        break_landing=r.get(
            so,
            "break_landing",
            "string",
            (SolverSettings, "break_landing"),
            choices=("exact", "step", "tolerance"),
        ),
        max_pressure_change=r.get(
            so, "max_pressure_change", "number", (SolverSettings, "max_pressure_change")
        ),
        debris=r.get(
            so, "debris", "string", (SolverSettings, "debris"), choices=("stay", "released")
        ),
        linear_solver=r.get(
            so,
            "linear_solver",
            "string",
            (SolverSettings, "linear_solver"),
            choices=("auto", "direct", "iterative"),
        ),
        solid=r.get(so, "solid", "string", (SolverSettings, "solid"), choices=("full", "reduced")),
        band_threshold=r.get(so, "band_threshold", "number", (SolverSettings, "band_threshold")),
        band_rings=r.get(so, "band_rings", "number", (SolverSettings, "band_rings"), integer=True),
        contact_hysteresis=r.get(
            so, "contact_hysteresis", "flag", (SolverSettings, "contact_hysteresis")
        ),
    )
    _check(
        0.0 < solver.break_tolerance <= 1.0,
        "solver.break_tolerance",
        f"expected a fraction in (0, 1], got {solver.break_tolerance!r}",
    )
    # the steps grow as 1 / bound: at 0.1 % Rubin's 70 s take about 6,000 (576 at 1 %)
    _check(
        1e-3 <= solver.max_pressure_change <= 1.0 or solver.max_pressure_change == math.inf,
        "solver.max_pressure_change",
        "expected a fraction of the cavity pressure in [0.001, 1] (or inf: no bound), got "
        f"{solver.max_pressure_change!r}",
    )
    _check(solver.degree in (1, 2), "solver.degree", f"expected 1 or 2, got {solver.degree!r}")
    _check(
        0.0 < solver.band_threshold <= 1.0,
        "solver.band_threshold",
        f"expected a fraction of the strength in (0, 1], got {solver.band_threshold!r}",
    )
    _check(solver.band_rings >= 0, "solver.band_rings", f"expected >= 0, got {solver.band_rings}")
    _check(
        solver.solid == "full" or solver.degree == 1,
        "solver.solid",
        "the reduced solid needs degree = 1 (DG1 blocks)",
    )
    for key in ("time_step", "max_time_step"):
        value = getattr(solver, key)
        _check(value > 0.0, f"solver.{key}", f"must be a positive time, got {value:g} s")
    so.finish()

    return solver


def parse_physics(data: Mapping[str, Any]) -> Physics:
    """Read the physics sections of a parsed scene document (see the module docstring)."""
    r = _Reader(data)
    # every section is read, so one error message names what is wrong in each
    readers = (_read_rock, _read_stress, _read_fluid, _read_pump, _read_output, _read_solver)
    read: list[Any] = []
    errors: list[FieldError] = []
    for reader in readers:
        try:
            read.append(reader(r))
        except FieldError as exc:  # a scene error, or a unit's: both name their key
            errors.append(exc)
        except ValueError as exc:  # a range the dataclasses check themselves
            errors.append(_range_error(exc))
    SceneErrors.raise_any(errors)
    (rock, model, aperture), stress, fluid, pump, output, solver = read
    try:
        _check(
            pump.get("wall_joints") != "seepage" or solver.max_pressure_change == math.inf,
            "solver.max_pressure_change",
            'not taken by a seepage run (injection.wall_joints = "seepage"), whose steps '
            "follow solver.time_step and solver.max_time_step; leave it out "
            "(--set solver.max_pressure_change= drops a scene's)",
        )
        _check(
            pump.get("wall_joints") == "seepage" or solver.break_landing == "exact",
            "solver.break_landing",
            '"step" and "tolerance" are taken by a pumped seepage run (injection.wall_joints = '
            '"seepage") only; the other rungs shorten a step onto a break within '
            "solver.break_tolerance",
        )
        return Physics(
            rock=rock,
            interfaces=InterfaceModel(**model, break_rule=solver.break_rule),
            stress=stress,
            fluid=fluid,
            solver=solver,
            joint_aperture=aperture.value,
            joint_reference_size=aperture.reference_size,
            **pump,
            **output,
            defaulted=tuple(r.defaulted),
        )
    except ValueError as exc:  # a range the dataclasses check themselves
        raise _range_error(exc) from None


def _range_error(exc: ValueError) -> SceneError:
    """Return a dataclass's range error as the scene error of the key it names."""
    said = str(exc)
    key = next((k for name, k in _SCENE_KEYS.items() if said.startswith(f"{name} ")), "")
    return SceneError(key, said)


#: the scene key of each dataclass field a range check names (its words start with it)
_SCENE_KEYS = {
    "alpha": "rock.spring_factor",
    "poisson_ratio": "rock.poisson_ratio",
    "shear_ratio": "rock.shear_ratio",
    "friction_angle": "rock.friction_angle",
    "weibull_modulus": "rock.weibull_modulus",
    "strength_length": "rock.strength_length",
    "tensile_strength": "rock.tensile_strength",
    "cohesion": "rock.cohesion",
    "joint aperture": "rock.joint_aperture",
    "joint reference size": "rock.joint_reference_size",
    "sh_max": "stress.sh_max",
    "sh_min": "stress.sh_min",
    "sv": "stress.sv",
    "viscosity": "fluid.viscosity",
    "injection rate": "injection.rate",
    "injection pressure": "injection.pressure_schedule",
}


__all__ = [
    "PHYSICS_SECTIONS",
    "Physics",
    "SolverSettings",
    "StaticLoad",
    "parse_physics",
]
