"""Run a scene: mesh it, build the CDEM solid and the fluid, inject, write what people read.

``hfcdem run SCENE.toml -o DIR`` calls :func:`run_scene`.  The scene file must
state its physics (``[rock]``, ``[stress]``, ``[injection]``; see
:mod:`hfcdem.config.physics`).  Boundary conditions follow the tag names:
symmetry planes are rollers, outer faces are fixed.  The fracturable zone is
the ``fracture_path`` facet group when the scene has one (a prescribed path),
else the ``fracturable`` cell group, else the whole rock.  The cavity is every
``wellbore*`` and ``perforation*`` facet group; a scene without one injects
at its injection point.

Written into DIR (rank 0, atomically): ``run.json`` at the start (the scene and
its defaults), ``history.csv`` after every step, and at the end
``summary.json``, ``pressure.png`` (the injection pressure with the breakdown
marked) and ``fracture.vtu`` (fluid pressure, aperture, saturation and state per
fracture facet).  Over time, for ParaView (:mod:`hfcdem.io.series`): ``fields.bp``
(displacement, normal stresses) and ``interfaces.pvd`` (failure state, opening,
fluid pressure, saturation per interface).  A run that stops keeps what it wrote.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from hfcdem.config.geometry import Scene
from hfcdem.config.tables import SceneError
from hfcdem.coupling.hydrofrac import FlowSettings, HydraulicFracture, SimulationStopped
from hfcdem.info import versions
from hfcdem.io.files import prepare_output_dir, to_builtin, write_interfaces, write_json
from hfcdem.io.series import FieldSeries, output_times
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.workflows.breakdown import detect_breakdown

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
    fixed = tuple(sorted(n for n in names if n.startswith("outer")))
    return CDEMSolid(
        tmesh,
        phys.rock,
        phys.stress,
        phys.interfaces,
        zone=zone,
        degree=phys.solver.degree,
        rollers=rollers,
        fixed=fixed,
        strength_points=phys.solver.strength_points,
        solver=phys.solver.linear_solver,
    )


def pressurised_groups(names: Any, wellbore: str) -> tuple[str, ...]:
    """Return the facet groups the injection pressure loads.

    A ``"cased"`` wellbore keeps the pressure off its own wall when the scene has
    perforation tunnels (the casing carries it); otherwise every wellbore and
    tunnel wall is loaded.
    """
    tunnels = tuple(sorted(n for n in names if n.startswith("perforation")))
    if tunnels and wellbore == "cased":
        return tunnels
    return tuple(sorted(n for n in names if n.startswith(("wellbore", "perforation"))))


def wall_area(tmesh: Any, groups: tuple[str, ...]) -> float:
    """Return the total area (length in 2D) of facet groups ``groups``."""
    import dolfinx

    if not groups:
        return 0.0
    one = dolfinx.fem.Constant(tmesh.mesh, dolfinx.default_scalar_type(1.0))
    form = dolfinx.fem.form(sum(one * tmesh.ds(name) for name in groups))
    local = dolfinx.fem.assemble_scalar(form)
    return float(tmesh.mesh.comm.allreduce(local, op=MPI.SUM))


def build_fracture(scene: Scene, solid: CDEMSolid) -> HydraulicFracture:
    """Build the coupled fluid-solid model of a scene."""
    phys = scene.physics
    names = solid.tmesh.facet_names
    cavity = pressurised_groups(names, phys.wellbore)
    point = getattr(scene.geometry, "injection_point", None)
    if not cavity and point is None:
        raise SceneError("geometry", "the scene has no wellbore, tunnel or injection point")
    inlet = None if cavity or point is None else tuple(point[: solid.gdim])
    settings = FlowSettings(
        cavity=cavity,
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
    )
    return HydraulicFracture(solid, phys.fluid, phys.injection, settings)


def run_scene(
    scene: Scene,
    output: str | Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    force: bool = False,
    say: Callable[[str], None] | None = None,
    resume: bool = False,
) -> dict[str, Any]:
    """Run ``scene`` and write its results into ``output``; return the summary.

    ``resume``: continue from ``checkpoint.json`` of an earlier, stopped run of
    the same scene in ``output`` (written after every step).
    """
    from hfcdem.mesh.build import create_scene_mesh

    if scene.physics is None:
        raise SceneError(
            "",
            "the scene states no physics: add [rock], [stress] and [injection] (or [load]) "
            "sections",
        )
    say = say or (lambda msg: None)
    wall0 = time.perf_counter()
    out = Path(output)
    _claim_output(out, scene, force, comm)
    out = prepare_output_dir(out, comm)
    phys = scene.physics
    write_json(
        out / "run.json",
        {
            "scene": scene.name,
            "fingerprint": scene_fingerprint(scene),
            "source": scene.source,
            "resolution": scene.resolution,
            "physics": _jsonable(asdict(phys)),
            "defaults_used": list(phys.defaulted),
            "ranks": comm.size,
        },
        comm,
    )
    if phys.defaulted:
        say("defaults: " + ", ".join(phys.defaulted))
    sm = create_scene_mesh(scene, comm)
    tmesh = sm.tmesh
    cells = tmesh.mesh.topology.index_map(tmesh.mesh.topology.dim).size_global
    solid = build_solid(scene, tmesh)
    dofs = solid.V.dofmap.index_map.size_global * solid.gdim
    say(f"{scene.name}: {cells} cells, {dofs} unknowns, {comm.size} rank(s)")

    def record() -> dict[str, Any]:
        """Summary entries every run has: mesh, machine, versions, the scene as run."""
        return {
            "cells": cells,
            "unknowns": dofs,
            "ranks": comm.size,
            "peak_memory_MB": _peak_memory_mb(comm),
            "wall_time_s": time.perf_counter() - wall0,
            "versions": versions(comm),
            "defaults_used": list(phys.defaulted),
            "resolved_scene": _resolved_scene(scene),
        }

    if phys.load is not None:
        from hfcdem.workflows.static import run_static

        return run_static(scene, solid, out, say, record)
    frac = build_fracture(scene, solid)
    checkpoint = out / "checkpoint.json"
    first: dict[str, Any] | None = None  # where the first crack broke, once it has
    if resume:
        data = comm.bcast(
            json.loads(checkpoint.read_text()) if comm.rank == 0 and checkpoint.exists() else None,
            root=0,
        )
        if data is None:
            say("nothing to resume: no checkpoint.json; starting from t = 0")
        else:
            frac.restore(data)
            first = data.get("first_crack")  # the break events themselves are not kept
            say(f"resumed at t = {frac.t:.6g} s ({len(frac.history)} steps done)")
    resumed = bool(frac.history)
    if not resumed:
        failed = frac.settle()
        if failed:
            say(f"initial state: {failed} interfaces fail before injection (excavation)")
    stopped = None
    t_end = phys.duration
    series = FieldSeries(out, frac, resume_from=frac.t if resumed else None)
    interval = phys.output_interval or t_end / 20.0
    next_frame = iter(output_times(frac.t, t_end, interval))
    due = next(next_frame, math.inf)
    if not resumed:
        series.write(0.0)
    try:
        while frac.t < t_end * (1.0 - 1e-12):
            frac.dt = min(frac.dt, t_end - frac.t)
            rec = frac.step()
            frac.write_history(out / "history.csv")
            if first is None and frac.first_break_time is not None:
                first = _first_crack(scene, frac)
            write_json(checkpoint, frac.checkpoint() | {"first_crack": first}, comm)
            if rec.time >= due * (1.0 - 1e-12):
                series.write(rec.time)
                while due <= rec.time * (1.0 + 1e-12):
                    due = next(next_frame, math.inf)
            eta = rec.wall_time / rec.time * (t_end - rec.time) if rec.time > 0 else math.nan
            say(
                f"t {rec.time:8.4g} s  p {rec.injection_pressure / 1e6:8.3f} MPa  "
                f"broken {rec.tensile + rec.shear:5d}  dt {rec.dt:8.3g} s  "
                f"wall {rec.wall_time:6.1f} s  eta {eta:6.1f} s"
            )
    except SimulationStopped as exc:
        stopped = str(exc)
        say(f"stopped: {exc}")
    finally:
        if frac.history:
            frac.write_history(out / "history.csv")
    if stopped is not None and series.frames and series.frames[-1][0] < frac.t:
        series.write(frac.t)  # the state the run stopped in
    series.close()
    # the curve starts from the initial state, so the rise to the peak is measured from it
    times = [0.0] + [r.time for r in frac.history]
    pressures = [phys.initial_pressure] + [r.injection_pressure for r in frac.history]
    found = detect_breakdown(times, pressures)
    counts = solid.broken_counts()
    points, data = frac.facet_fields()
    write_interfaces(out / "fracture.vtu", points, data, comm)
    summary = {
        "scene": scene.name,
        "breakdown_pressure_MPa": found.pressure / 1e6 if found else None,
        "breakdown_time_s": found.time if found else None,
        "peak_pressure_MPa": max(pressures) / 1e6 if pressures else None,
        "first_crack_time_s": frac.first_break_time,
        "first_crack_pressure_MPa": _first_crack_pressure(frac),
        "initial_failures": frac.initial_failures,
        "first_crack": first if first is not None else _first_crack(scene, frac),
        "fracture_degree": solid.fracture_degree(),
        "tensile_failures": counts["tensile"],
        "shear_failures": counts["shear"],
        "simulated_time_s": frac.t,
        "steps": len(frac.history),
        "rebuilds": frac.rebuilds,
        "rebuild_seconds": frac.rebuild_seconds,
        "max_mass_error": max((r.mass_error for r in frac.history), default=0.0),
        "stopped": stopped,
        **record(),
    }
    write_json(out / "summary.json", summary, comm)
    if comm.rank == 0 and pressures:
        _plot_pressure(out / "pressure.png", times, pressures, found, scene.name)
    if phys.pictures:
        _picture_fracture(out / "fracture.png", scene, frac)
    comm.barrier()
    return summary


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
    """Injection pressure of the state located on the first crack (MPa)."""
    t = frac.first_break_time
    if t is None:
        return None
    before = [r.injection_pressure for r in frac.history if r.time < t]
    return max([*before, frac.settings.initial_pressure]) / 1e6


def _peak_memory_mb(comm: MPI.Comm) -> float:
    """Peak resident memory of all ranks together (MB), from getrusage."""
    import resource

    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # kB on Linux
    return float(comm.allreduce(kb, op=MPI.SUM)) / 1024.0


def _first_crack(scene: Scene, frac: HydraulicFracture) -> dict[str, Any] | None:
    """Where the injection's first interfaces broke (their mean midpoint).

    ``distance_from_wellbore_wall_m``: from the wellbore wall, measured across the
    wellbore axis (0 at a perforation root); None without a wellbore.
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
    point[:width] = np.asarray(total)[:width] / count
    out: dict[str, Any] = {"point_m": point.tolist(), "interfaces": count}
    wellbore = getattr(scene.geometry, "wellbore", None)
    if wellbore is not None:
        across = point.copy()
        across["xyz".index(wellbore.axis)] = 0.0
        out["distance_from_wellbore_wall_m"] = float(np.linalg.norm(across) - wellbore.radius)
    return out


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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(times, [p / 1e6 for p in pressures], "-", label="injection pressure")
    if found is not None:
        ax.plot(
            [found.time],
            [found.pressure / 1e6],
            "rv",
            ms=9,
            label=f"breakdown {found.pressure / 1e6:.2f} MPa",
        )
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pressure (MPa)")
    ax.set_title(name)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


__all__ = [
    "ROLLER_AXES",
    "OutputInUse",
    "build_fracture",
    "build_solid",
    "pressurised_groups",
    "run_scene",
    "scene_fingerprint",
    "wall_area",
]
