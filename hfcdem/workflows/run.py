"""Run a scene: mesh it, build the CDEM solid and the fluid, inject, write what people read.

``hfcdem run SCENE.toml -o DIR`` calls :func:`run_scene`.  The scene file must
state its physics (``[rock]``, ``[stress]``, ``[injection]``; see
:mod:`hfcdem.config.physics`).  Boundary conditions follow the tag names:
symmetry planes are rollers, outer faces are fixed.  The fracturable zone is
the ``fracture_path`` facet group when the scene has one (a prescribed path),
else the ``fracturable`` cell group, else the whole rock.  The cavity is every
``wellbore*`` and ``perforation*`` facet group; a scene without one injects
at its injection point.

Written into DIR (rank 0): ``run.json`` at the start (the scene and its
defaults), a row of ``history.csv`` and ``checkpoint.json`` (the state, not the
history) after every step (:mod:`hfcdem.workflows.observers`), and at the end
``summary.json``, ``pressure.png`` (the injection pressure with the breakdown
marked) and ``fracture.vtu`` (fluid pressure, aperture, saturation and state per
fracture facet).  Over time, for ParaView (:mod:`hfcdem.io.series`): ``fields.bp``
(displacement, normal stresses) and ``interfaces.pvd`` (failure state, opening,
fluid pressure, saturation per interface).  A run that stops keeps what it wrote.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from hfcdem.config.geometry import Scene
from hfcdem.config.tables import SceneError
from hfcdem.config.units import FieldError
from hfcdem.coupling.breakdown import FIRST_CRACK_END, breakdown_note, detect_breakdown
from hfcdem.coupling.hydrofrac import (
    FlowSettings,
    HydraulicFracture,
    SimulationStopped,
    StepRecord,
)
from hfcdem.coupling.penetration import PressureRamp
from hfcdem.info import versions
from hfcdem.io.files import (
    prepare_output_dir,
    to_builtin,
    write_interfaces,
    write_json,
)
from hfcdem.io.history import HistoryFile
from hfcdem.io.plots import plot_lines
from hfcdem.io.series import FieldSeries
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState
from hfcdem.solvers import SolverError, ValidityLimit
from hfcdem.workflows.memory import free_petsc_garbage, peak_memory_mb, reset_peak_memory
from hfcdem.workflows.observers import (
    CheckpointWriter,
    FirstCrack,
    FrameWriter,
    HistoryWriter,
    ProgressLine,
    StepObserver,
    mesh_fingerprint,
    read_checkpoint,
)
from hfcdem.workflows.places import (
    place_counts,
    place_ratios,
    plot_first_crack_stress,
    stress_along_tunnels,
    wellbore_place,
)
from hfcdem.workflows.pumped_checkpoint import KIND as SEEPAGE_CHECKPOINT
from hfcdem.workflows.wall_stress import in_situ_wall_tension, wall_tension_warning

ROLLER_AXES = {"symmetry_x": 0, "symmetry_y": 1, "symmetry_z": 2}


class OutputInUse(RuntimeError):
    """The output directory holds another scene's results."""


def scene_fingerprint(scene: Scene) -> str:
    """Return a short hash of the resolved scene (geometry and physics)."""
    text = repr((scene.geometry, scene.physics, scene.resolution))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _claim_output(out: Path, scene: Scene, force: bool, comm: MPI.Comm) -> None:
    """Refuse to overwrite another scene's results unless ``force``."""
    record = out / "run.json"
    problem = None
    if comm.rank == 0 and record.exists() and not force:
        try:
            previous = json.loads(record.read_text())
        except (OSError, json.JSONDecodeError):
            previous = {}
        if previous.get("fingerprint") != scene_fingerprint(scene):
            problem = (
                f"{out} holds the results of scene {previous.get('scene', '?')!r} "
                f"(a different scene or settings); use --force to overwrite, or another -o"
            )
    elif comm.rank == 0 and not force and out.is_dir() and any(out.iterdir()):
        problem = (
            f"{out} holds files but no hfcdem run (no run.json): they could be "
            "overwritten; use another -o, or --force"
        )
    problem = comm.bcast(problem, root=0)
    if problem:
        raise OutputInUse(problem)


def build_solid(scene: Scene, tmesh: Any) -> CDEMSolid:
    """Build the CDEM solid of a scene, with boundary conditions from the tag names."""
    phys = scene.physics
    names = tmesh.facet_names
    if "fracture_path" in names:
        zone: Any = "fracture_path"
    elif "fracturable" in tmesh.cell_names:
        zone = "fracturable"
    else:
        zone = None
    rollers = {name: axis for name, axis in ROLLER_AXES.items() if name in names}
    fixed = tmesh.facet_groups("outer")
    walls = {}
    if phys.wellbore == "drilled":  # the wall keeps the pressure it was drilled at
        cavity = pressurised_groups(names, phys.wellbore)
        walls = dict.fromkeys(unloaded_wellbore_walls(names, cavity), phys.initial_pressure)
    return CDEMSolid(
        tmesh,
        phys.rock,
        phys.stress,
        phys.interfaces,
        zone=zone,
        degree=phys.solver.degree,
        rollers=rollers,
        fixed=fixed,
        walls=walls,
        strength_points=phys.solver.strength_points,
        solver=phys.solver.linear_solver,
        mode=phys.solver.solid,
        band=(phys.solver.band_threshold, phys.solver.band_rings),
    )


def pressurised_groups(names: Any, wellbore: str) -> tuple[str, ...]:
    """Return the facet groups the injection pressure loads.

    A ``"cased"`` or ``"drilled"`` wellbore keeps the pressure off its own wall
    when the scene has perforation tunnels (the casing carries it); otherwise
    every wellbore and tunnel wall is loaded.
    """
    tunnels = tuple(sorted(n for n in names if n.startswith("perforation")))
    if tunnels and wellbore in ("cased", "drilled"):
        return tunnels
    return tuple(sorted(n for n in names if n.startswith(("wellbore", "perforation"))))


def supporting_walls(
    names: Any, cavity: tuple[str, ...], wellbore: str = "cased"
) -> tuple[str, ...]:
    """Return the wellbore wall groups the pressure does not load (a cased wellbore's).

    They keep their in-situ traction and hold the blocks cut loose against them
    (:func:`~hfcdem.coupling.events.release_debris`).  A drilled wellbore's wall
    has none: its casing's springs hold the rock at the drilled state.
    """
    if not cavity or wellbore == "drilled":
        return ()
    return unloaded_wellbore_walls(names, cavity)


def unloaded_wellbore_walls(names: Any, cavity: tuple[str, ...]) -> tuple[str, ...]:
    """Return the wellbore wall groups not in ``cavity`` (sorted)."""
    return tuple(sorted(n for n in names if n.startswith("wellbore") and n not in cavity))


def wall_area(tmesh: Any, groups: tuple[str, ...]) -> float:
    """Return the total area (length in 2D) of facet groups ``groups``."""
    import dolfinx

    if not groups:
        return 0.0
    one = dolfinx.fem.Constant(tmesh.mesh, dolfinx.default_scalar_type(1.0))
    form = dolfinx.fem.form(sum(one * tmesh.ds(name) for name in groups))
    local = dolfinx.fem.assemble_scalar(form)
    return float(tmesh.mesh.comm.allreduce(local, op=MPI.SUM))


def _warn_unresolved(scene: Scene, say: Callable[[str], None]) -> None:
    """Say when a scene asks for what its mesh or its rung does not do, or for tension."""
    from hfcdem.workflows.convergence import characteristic_size

    phys = scene.physics
    pulled = [
        f"stress.{key} = {getattr(phys.stress, key) / 1e6:.4g} MPa"
        for key in ("sh_max", "sh_min", "sv")
        if getattr(phys.stress, key) < 0.0
    ]
    if pulled:
        say(
            f"warning: {', '.join(pulled)} is tension (in-situ stresses are compression "
            "positive): the rock is pulled apart before any injection"
        )
    length = phys.interfaces.strength_length
    h = characteristic_size(scene)
    if 0.0 < length < h:
        say(
            f"warning: rock.strength_length = {length * 1e3:.3g} mm is below the cells' size "
            f"at the cavity ({h * 1e3:.3g} mm): the filter cannot resolve it there, so the "
            "answer follows the mesh; refine the mesh or lengthen it"
        )
    if (
        phys.load is None
        and phys.wall_joints == "seepage"
        and "solver.fidelity" not in (phys.defaulted)
    ):
        say(
            "note: solver.fidelity is not used by a seepage run (injection.wall_joints = "
            '"seepage"): the joints carry the flow'
        )


def _check_loaded_walls(scene: Scene, names: Any) -> None:
    """Refuse an injection into a mesh with no wall or point to inject at (before writing)."""
    phys = scene.physics
    if phys.load is not None:
        return
    if not pressurised_groups(names, phys.wellbore) and (
        getattr(scene.geometry, "injection_point", None) is None
    ):
        raise SceneError(
            "geometry",
            "the scene has no wellbore, tunnel or injection point for [injection]; a crack "
            "plate takes a static [load]",
        )


def build_fracture(scene: Scene, solid: CDEMSolid) -> HydraulicFracture:
    """Build the coupled fluid-solid model of a scene."""
    phys = scene.physics
    names = solid.tmesh.facet_names
    _check_loaded_walls(scene, names)
    cavity = pressurised_groups(names, phys.wellbore)
    point = getattr(scene.geometry, "injection_point", None)
    inlet = None if cavity or point is None else tuple(point[: solid.gdim])
    settings = FlowSettings(
        cavity=cavity,
        supports=supporting_walls(names, cavity, phys.wellbore),
        debris=phys.solver.debris,
        injection_point=inlet,
        fidelity=phys.solver.fidelity,
        filling=phys.solver.filling,
        initial_pressure=phys.initial_pressure,
        extra_volume=phys.extra_volume,
        cavity_volume=(
            None if phys.wall_film is None else phys.wall_film * wall_area(solid.tmesh, cavity)
        ),
        dt_initial=phys.solver.time_step,
        dt_max=phys.solver.max_time_step,
        max_breaks_per_iteration=phys.solver.max_breaks_per_iteration,
        wet_wall_joints=phys.wall_joints in ("wet", "permeated"),
        permeate_joints=phys.wall_joints == "permeated",
        rigid_cavity=phys.rigid_cavity,
        break_tolerance=phys.solver.break_tolerance,
        max_pressure_change=phys.solver.max_pressure_change,
        contact_hysteresis=phys.solver.contact_hysteresis,
    )
    return HydraulicFracture(solid, phys.fluid, phys.injection, settings)


def run_scene(
    scene: Scene,
    output: str | Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    force: bool = False,
    say: Callable[[str], None] | None = None,
    resume: bool = False,
    observers: Sequence[StepObserver] = (),
) -> dict[str, Any]:
    """Run ``scene`` and write its results into ``output``; return the summary.

    ``resume``: continue from ``checkpoint.json`` of an earlier, stopped run of
    the same scene and mesh in ``output`` (written after every step).
    ``observers`` see every step after the built-in ones (history, checkpoint,
    frames, progress); an exception raised by one stops the run, keeping what
    was written.
    """
    from hfcdem.mesh.build import create_scene_mesh

    if scene.physics is None:
        raise SceneError(
            "",
            "the scene states no physics: add [rock], [stress] and [injection] (or [load]) "
            "sections",
        )
    loading = None
    if scene.physics.load is None and scene.physics.wall_joints == "seepage":
        from hfcdem.workflows.seepage_ramp import seepage_loading

        with in_scene_file(scene):
            # its checks, before an earlier run's files are touched
            loading = seepage_loading(scene)
    if resume and (scene.physics.load is not None or isinstance(loading, PressureRamp)):
        # checked before anything is written: the stopped run's files must survive
        what = (
            "a static [load] scene"
            if scene.physics.load is not None
            else 'a seepage pressure ramp (injection.wall_joints = "seepage", ended at its '
            "first break)"
        )
        raise SceneError(
            "",
            f"--resume: {what} keeps no checkpoint to continue from; run it again "
            "without --resume (into another -o, or with --force to replace its results)",
        )
    say = say or (lambda msg: None)
    wall0 = time.perf_counter()
    own_peak = comm.allreduce(reset_peak_memory(), op=MPI.LAND)  # the peak is this run's
    out = Path(output)
    _claim_output(out, scene, force, comm)
    out = prepare_output_dir(out, comm)
    phys = scene.physics
    if phys.defaulted:
        say("defaults: " + ", ".join(phys.defaulted))
    sm = create_scene_mesh(scene, comm)
    tmesh = sm.tmesh
    with in_scene_file(scene):
        _check_loaded_walls(scene, tmesh.facet_names)
    # an earlier run's files are touched only now, when the scene has meshed and
    # passed every check; a resume writes its record once the checkpoint is taken
    if not resume:
        _write_run_record(out, scene, comm)
        if comm.rank == 0:  # another run's answers must not pass for this one's
            (out / "summary.json").unlink(missing_ok=True)
            (out / "checkpoint.json").unlink(missing_ok=True)  # an earlier run's state
            (out / "time_step_check.json").unlink(missing_ok=True)  # of an earlier run
        comm.barrier()
    cells = tmesh.mesh.topology.index_map(tmesh.mesh.topology.dim).size_global
    solid = build_solid(scene, tmesh)
    dofs = solid.V.dofmap.index_map.size_global * solid.gdim
    say(f"{scene.name}: {cells} cells, {dofs} unknowns, {comm.size} rank(s)")
    _warn_unresolved(scene, say)
    if solid.mode == "reduced":
        say(
            "reduced solid: springs in a band around the cracks and cavity walls that grows "
            f"past {phys.solver.band_threshold:g} of the strength, continuous blocks elsewhere"
        )

    def record() -> dict[str, Any]:
        """Summary entries every run has: mesh, machine, versions, the scene as run."""
        return {
            "fingerprint": scene_fingerprint(scene),
            "cells": cells,
            "unknowns": dofs,
            "ranks": comm.size,
            "peak_memory_MB": peak_memory_mb(comm),
            "peak_memory_rank_max_MB": peak_memory_mb(comm, MPI.MAX),
            "peak_memory_scope": "run" if own_peak else "process",
            "wall_time_s": time.perf_counter() - wall0,
            "versions": versions(comm),
            "defaults_used": list(phys.defaulted),
            "resolved_scene": _resolved_scene(scene),
        }

    collective = False  # whether every rank is here together, so the solid can be freed
    try:
        if phys.load is not None:
            from hfcdem.workflows.static import run_static

            with in_scene_file(scene):
                summary = run_static(scene, solid, out, say, record)
        elif phys.wall_joints == "seepage":
            from hfcdem.workflows.seepage_ramp import run_seepage_ramp

            cavity = pressurised_groups(tmesh.facet_names, phys.wellbore)
            supports = supporting_walls(tmesh.facet_names, cavity, phys.wellbore)
            summary = run_seepage_ramp(
                scene, solid, cavity, out, say, record, supports, resume=resume
            )
            if resume:
                _write_run_record(out, scene, comm)  # as a coupled run's: once it went on
        else:
            summary = _run_coupled(scene, solid, out, say, record, resume, observers)
        collective = True
    except COLLECTIVE_ERRORS:
        collective = True  # raised on every rank; any other error may be one rank's own,
        raise  # and a collective destroy there would hang the others instead of failing
    finally:
        if collective:
            # at once: a traceback would keep the solid (its factor: GBs at the default
            # mesh) alive, and petsc4py keeps a parallel object it lets go as garbage of
            # the mesh's communicator until that is cleaned (the mesh must outlive it)
            solid.destroy()
            del solid
            free_petsc_garbage(tmesh.mesh.comm)
    return summary


#: errors raised on every rank together (each is decided from reduced or broadcast values)
COLLECTIVE_ERRORS = (SimulationStopped, SolverError, FieldError, OutputInUse)


@contextmanager
def in_scene_file(scene: Scene) -> Iterator[None]:
    """Name the scene's file in the scene errors raised inside, as loading it does."""
    try:
        yield
    except FieldError as exc:
        if not scene.source or not Path(scene.source).suffix:
            raise
        name = Path(scene.source).name
        raise SceneError(f"{name}: {exc.path}" if exc.path else name, exc.reason) from None


def _write_run_record(out: Path, scene: Scene, comm: MPI.Comm) -> None:
    """``run.json``: what is about to run, written before anything is meshed."""
    phys = scene.physics
    record = {
        "scene": scene.name,
        "fingerprint": scene_fingerprint(scene),
        "source": scene.source,
        "resolution": scene.resolution,
        "physics": _jsonable(asdict(phys)),
        "defaults_used": list(phys.defaulted),
        "ranks": comm.size,
    }
    write_json(out / "run.json", record, comm)


def _run_coupled(
    scene: Scene,
    solid: CDEMSolid,
    out: Path,
    say: Callable[[str], None],
    record: Callable[[], dict[str, Any]],
    resume: bool,
    observers: Sequence[StepObserver],
) -> dict[str, Any]:
    """Inject into the solid of an [injection] scene and write its results."""
    phys, comm = scene.physics, solid.comm
    frac = build_fracture(scene, solid)
    fingerprint = mesh_fingerprint(solid.tmesh)
    first = FirstCrack(lambda f: _first_crack(scene, f, stress=True))
    if resume:
        _resume(frac, out, fingerprint, first, say, comm)
        _write_run_record(out, scene, comm)  # only now: a refused resume leaves it as it was
    resumed = bool(frac.history)
    walls = in_situ_wall_tension(scene)
    warning = wall_tension_warning(walls)
    if warning:
        say(warning)
    if not resumed:
        failed = frac.settle()
        if failed:
            say(f"initial state: {failed} interfaces fail before injection (excavation)")
    t_end = phys.duration
    series = FieldSeries(out, frac, resume_from=frac.t if resumed else None)
    watchers: list[StepObserver] = [
        HistoryWriter(out / "history.csv", comm),
        first,
        CheckpointWriter(out / "checkpoint.json", fingerprint, first, comm),
        FrameWriter(series, t_end, phys.output_interval or t_end / 20.0, fresh=not resumed),
        ProgressLine(say, t_end),
        *observers,
    ]
    at_first = phys.until == "first crack"
    stopped, limit = _step_until(frac, t_end, watchers, say, at_first)
    # the curve starts from the initial state, so the rise to the peak is measured from it
    times = [0.0] + [r.time for r in frac.history]
    pressures = [phys.initial_pressure] + [r.injection_pressure for r in frac.history]
    # a run ended on its first crack as asked has no breakdown to seek: no drop can follow
    ended = at_first and stopped is None and frac.first_break_time is not None
    found = None if ended else detect_breakdown(times, pressures)
    points, data = frac.facet_fields()
    write_interfaces(out / "fracture.vtu", points, data, comm)
    summary = _summarise(scene, frac, found, pressures, first, stopped, limit, ended) | record()
    summary |= _inlet_answers(scene, frac)
    # closed form: the walls' largest tension under the in-situ stress alone
    summary["in_situ_wall_tension"] = [w.as_dict() for w in walls]
    write_json(out / "summary.json", summary, comm)
    if comm.rank == 0 and pressures:
        _plot_pressure(out / "pressure.png", times, pressures, found, scene.name)
    if phys.pictures:
        _picture_fracture(out / "fracture.png", scene, frac)
    if comm.rank == 0:
        plot_first_crack_stress(out, scene, first.where)
    comm.barrier()
    return summary


def _summarise(
    scene: Scene,
    frac: HydraulicFracture,
    found: Any,
    pressures: list[float],
    first: FirstCrack,
    stopped: str | None,
    limit: bool,
    ended_on_first_crack: bool = False,
) -> dict[str, Any]:
    """Collect the answers of a coupled run for ``summary.json``."""
    solid = frac.solid
    counts = solid.broken_counts()
    return {
        "scene": scene.name,
        "breakdown_pressure_MPa": found.pressure / 1e6 if found else None,
        "breakdown_time_s": found.time if found else None,
        # how far the pressure fell after it: a dip near the threshold is a fragile answer
        "breakdown_drop_MPa": found.drop / 1e6 if found else None,
        "breakdown_note": (
            FIRST_CRACK_END
            if ended_on_first_crack
            else breakdown_note(
                pressures,
                found,
                "crack" in solid.tmesh.facet_names,
                validity_limit=limit,
                stopped=stopped is not None and not limit,
            )
        ),
        "peak_pressure_MPa": max(pressures) / 1e6 if pressures else None,
        "first_crack_time_s": frac.first_break_time,
        "first_crack_pressure_MPa": _first_crack_pressure(frac),
        # the cavity pressure of the state the first crack broke in: the crack came
        # between the two (they differ where no step landed on it, e.g. in the first)
        "first_crack_pressure_bound_MPa": (
            frac.first_break_pressure / 1e6 if frac.first_break_pressure is not None else None
        ),
        "initial_failures": frac.initial_failures,
        "first_crack": first.where if first.where is not None else _first_crack(scene, frac),
        "fracture_degree": solid.fracture_degree(),
        "tensile_failures": counts["tensile"],
        "shear_failures": counts["shear"],
        "simulated_time_s": frac.t,
        "steps": len(frac.history),
        # since the start or the resume: attempts halved by solver.max_pressure_change
        "pressure_cuts": frac.stepper.pressure_cuts,
        "rebuilds": frac.rebuilds,
        "rebuild_seconds": frac.rebuild_seconds,
        "rebuild_causes": dict(frac.rebuild_causes),  # contact, break, band, fill, ...
        "reused_condensations": frac.reused_condensations,  # rebuilds that needed no solve
        # since the start or the resume: what the rebuilds cost the solid's solver
        "solid_operator": solid.operator.statistics(),
        # contact hysteresis at the last contact check: facets it held shut that would
        # open without it, and the largest share of the pressure by which they would
        "contact_held_shut": {
            "count": solid.held_shut.count,
            "excess": solid.held_shut.excess,
        },
        "debris_cells": frac.debris_cells,  # cells cut loose from the walls, in the fluid
        "held_cells": int(solid.held_cells.size),  # loose cells a supporting wall holds
        "solid": solid.mode,
        "free_interfaces": solid.band.count(),
        "solved_unknowns": solid.num_dofs,  # at the end (reduced: grows with the band)
        "max_mass_error": max((r.mass_error for r in frac.history), default=0.0),
        "stopped": stopped,
        "validity_limit": limit,
        "until": scene.physics.until,
    }


def _inlet_answers(scene: Scene, frac: HydraulicFracture) -> dict[str, Any]:
    """Return the fluid front and inlet opening of a scene injected at a point (KGD)."""
    point = getattr(scene.geometry, "injection_point", None)
    direction = getattr(scene.geometry, "crack_direction", None)
    if point is None or direction is None or frac.settings.cavity:
        return {}
    gdim = frac.solid.gdim
    return {
        "fluid_front_m": frac.wet_extent(point[:gdim], direction[:gdim]),
        "inlet_opening_m": frac.opening_at_cavity(),
    }


def _resume(
    frac: HydraulicFracture,
    out: Path,
    fingerprint: str,
    first: FirstCrack,
    say: Callable[[str], None],
    comm: MPI.Comm,
) -> None:
    """Restore a stopped run from ``checkpoint.json`` and ``history.csv`` (collective)."""
    checkpoint = out / "checkpoint.json"
    data = read_checkpoint(out, say, comm)
    if data is None:
        return
    if data.get("kind") == SEEPAGE_CHECKPOINT:
        raise SceneError(
            "",
            f"{checkpoint} is a pumped seepage run's: resume the scene that wrote it, or "
            "start again with --force",
        )
    if data.get("mesh") != fingerprint:
        raise SceneError(
            "",
            f"{checkpoint} was written on another mesh (fingerprint {data.get('mesh')}, "
            f"now {fingerprint}): resume with the scene, resolution and --set values of "
            "the stopped run, or start again with --force",
        )
    steps = int(data["steps"])
    rows = HistoryFile(out / "history.csv", (), comm).read(limit=steps)
    if len(rows) < steps:
        raise SceneError(
            "", f"{out / 'history.csv'} holds {len(rows)} steps, the checkpoint {steps}"
        )
    frac.restore(data, history=[StepRecord.from_row(r) for r in rows])
    first.where = data.get("first_crack")  # the break events themselves are not kept
    say(f"resumed at t = {frac.t:.6g} s ({steps} steps done)")


def _step_until(
    frac: HydraulicFracture,
    t_end: float,
    watchers: Sequence[StepObserver],
    say: Callable[[str], None],
    at_first_crack: bool = False,
) -> tuple[str | None, bool]:
    """Step to ``t_end`` (or, ``at_first_crack``, to the step of the first crack).

    Each record goes to the observers.  Returns why it stopped (None: it
    reached its planned end) and whether that was the model's validity limit
    (:class:`ValidityLimit`) rather than a failure.
    """
    stopped, limit = None, False
    for w in watchers:
        w.start(frac)
    try:
        while frac.t < t_end * (1.0 - 1e-12):
            if at_first_crack and frac.first_break_time is not None:  # also a resumed run's
                say(f"  t {frac.t:.4g} s: the first crack; the run ends here (injection.until)")
                break
            frac.dt = min(frac.dt, t_end - frac.t)
            debris = frac.debris_cells
            rec = frac.step()
            if frac.debris_cells != debris:
                say(
                    f"  t {rec.time:.4g} s: {frac.debris_cells} cell(s) cut loose from the "
                    "walls in all are debris: their broken faces take the cavity pressure"
                )
            for w in watchers:
                w.step(frac, rec)
    except SimulationStopped as exc:
        stopped, limit = str(exc), isinstance(exc, ValidityLimit)
        say(f"{'ended at the validity limit of the model' if limit else 'stopped'}: {exc}")
    finally:
        for w in watchers:
            w.finish(frac, stopped)
    return stopped, limit


def _picture_fracture(path: Path, scene: Scene, frac: HydraulicFracture) -> None:
    """Draw the failure state of the interfaces (the paper's Figs. 16-17)."""
    from hfcdem.io.plots import (
        owned_boundary_triangles,
        plot_interface_states,
        render_fracture_pattern,
    )

    solid = frac.solid
    own = solid.owned
    points, states = solid.vertex_coords[own], solid.state[own].astype(int)
    title = f"{scene.name}: failure state at t = {frac.t:.4g} s"
    if solid.gdim == 2:
        broken = points[states > 0].reshape(-1, 3)
        reach = np.abs(broken[:, :2]).max() if len(broken) else 0.0
        extent = solid.comm.allreduce(float(reach), op=MPI.MAX) * 1.3 or 1.0
        plot_interface_states(path, points, states, title, extent, solid.comm)
        return
    walls = owned_boundary_triangles(solid.tmesh, frac.settings.cavity)
    wellbore = getattr(scene.geometry, "wellbore", None)
    axis = "xyz".index(wellbore.axis) if wellbore is not None else 2
    render_fracture_pattern(path, points, states, walls, title, axis, solid.comm)


def _first_crack_pressure(frac: HydraulicFracture) -> float | None:
    """Injection pressure of the state located on the first crack (MPa).

    The highest of the steps before it: where a step landed on the crack, the
    pressure at which the first facet reached its strength; else a lower bound
    (the summary's ``first_crack_pressure_bound_MPa`` is the upper one).
    """
    t = frac.first_break_time
    if t is None:
        return None
    before = [r.injection_pressure for r in frac.history if r.time < t]
    return max([*before, frac.settings.initial_pressure]) / 1e6


def _first_crack(
    scene: Scene, frac: HydraulicFracture, stress: bool = False
) -> dict[str, Any] | None:
    """Where the injection's first crack is: the facet that reached its strength first.

    ``point_m``: its midpoint (the mean midpoint of the first step's breaks if it
    is not known, as after a resume); ``mode``: how it failed; ``interfaces``: how
    many broke in that step, ``interfaces_by_place``: in which parts of the
    tunnels.  ``distance_from_wellbore_wall_m``: the point's from the wellbore
    wall, measured across the wellbore axis (0 at a perforation root); None
    without a wellbore.  ``ratio_by_place``: the highest failure ratio in each part
    of the tunnels then (:func:`~hfcdem.workflows.places.place_ratios`), so a near
    tie shows.  With ``stress`` (called in the step of the first crack),
    ``sigma_xx``: the stress along the tunnels then (:func:`stress_along_tunnels`,
    the paper's Fig. 18).
    """
    t = frac.first_break_time
    solid = frac.solid
    width = solid.midpoints.shape[1]  # the same on every rank (3 even in 2D)
    local = [e.midpoints for e in solid.events if t is not None and e.load_factor == t]
    pts = np.concatenate(local).reshape(-1, width) if local else np.zeros((0, width))
    total = solid.comm.allreduce(pts.sum(axis=0), op=MPI.SUM)
    count = solid.comm.allreduce(len(pts), op=MPI.SUM)
    if count == 0:
        return None
    point = np.zeros(3)
    where: dict[str, Any] = {"interfaces": count}
    if frac.first_break_point is not None:
        first = frac.first_break_point
        point[: len(first)] = first
        where["mode"] = FacetState(frac.first_break_mode).name.lower()
    else:
        point[:width] = np.asarray(total)[:width] / count
    where = {"point_m": point.tolist()} | where | wellbore_place(scene, point)
    by_place = place_counts(scene, pts, solid.comm)
    if by_place:  # the mean midpoint of a root and a far-end facet is in the middle
        where["interfaces_by_place"] = by_place
    ratio = frac.first_break_ratio
    ratios = place_ratios(scene, solid.midpoints, ratio, solid.comm) if ratio is not None else None
    if ratios:
        where["ratio_by_place"] = ratios
    profile = stress_along_tunnels(scene, solid) if stress else None
    return where | ({"time_s": t, "sigma_xx": profile} if profile else {})


def _resolved_scene(scene: Scene) -> dict[str, Any]:
    """Return the scene as run, every default filled in (SI units)."""
    from dataclasses import is_dataclass

    geometry = asdict(scene.geometry) if is_dataclass(scene.geometry) else repr(scene.geometry)
    return {
        "name": scene.name,
        "source": scene.source,
        "resolution": scene.resolution,
        "geometry": _jsonable(geometry),
        "physics": _jsonable(asdict(scene.physics)),
    }


def _jsonable(value: Any) -> Any:
    return to_builtin(value, strict=True)


def _plot_pressure(path: Path, times: list[float], pressures: list[float], found: Any, name: str):
    """Draw the injection pressure with the breakdown marked (called on rank 0)."""
    curves = [(np.asarray(times), np.asarray(pressures) / 1e6, "injection pressure", "-")]
    if found is not None:
        label = f"breakdown {found.pressure / 1e6:.2f} MPa"
        curves.append((np.array([found.time]), np.array([found.pressure / 1e6]), label, "rv"))
    plot_lines(path, curves, "time (s)", "pressure (MPa)", name, MPI.COMM_SELF)


__all__ = [
    "COLLECTIVE_ERRORS",
    "ROLLER_AXES",
    "OutputInUse",
    "build_fracture",
    "build_solid",
    "in_scene_file",
    "pressurised_groups",
    "run_scene",
    "scene_fingerprint",
    "wall_area",
]
