"""A scene run with ``wall_joints = "seepage"``: a pressure ramp, or pumping, with seepage.

The scene's injection must be one linear ramp: ``pressure_rate`` (with
``max_pressure`` or ``duration``), or a ``pressure_schedule`` ``[[0 s, P0],
[t1, P1]]``.  The cavity pressure follows it to ``duration`` (at most ``t1``)
in steps of ``injection.pressure_step`` (or ``solver.time_step``) while the
joints of the fracturable zone fill from dry (saturation filling, hydraulic
aperture ``rock.joint_aperture``) and load the solid
(:func:`hfcdem.coupling.penetration.ramp_breakdown`).  The run ends at the
first break: under a rising pressure that is the breakdown (initiation)
pressure of the classical criteria, Hubbert-Willis when the joints are still
dry and Haimson-Fairhurst when they stand at the cavity pressure.

A constant ``rate`` pumps into the cavity for the scene's ``duration`` and goes
on past the first break (:func:`hfcdem.coupling.pumping.pump_with_seepage`):
cracks joined to the cavity take its fluid, the pressure drops as they open,
and the breakdown is the peak before the drop (``summary.json`` kind
``"seepage_pumping"``).

Written: ``summary.json``, ``history.csv`` (cavity pressure and fluid in the
joints per step), ``joints.vtu`` (saturation and pressure of every joint at the
break or the end, and the interface states, for ParaView) and ``pressure.png``.
A pumped run also writes ``joints.pvd``: the same fields over time
(``joints/frame_K.vtu``, every ``output.interval``, by default 20 frames),
where the seepage front and the cracks can be watched move (the paper's Fig. 14).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from hfcdem.config.physics import Physics
from hfcdem.config.scene import Scene
from hfcdem.config.tables import SceneError
from hfcdem.config.units import show_stress
from hfcdem.coupling.breakdown import FIRST_CRACK_END, end_words, peak_is_lower_bound
from hfcdem.coupling.penetration import CavityPumping, PressureRamp, ramp_breakdown
from hfcdem.coupling.pumping import COST_COLUMNS, PumpingResult, pump_with_seepage
from hfcdem.io.files import write_csv, write_interfaces, write_json
from hfcdem.io.history import HistoryFile
from hfcdem.io.plots import plot_lines
from hfcdem.io.series import InterfaceFrames
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState
from hfcdem.workflows.observers import mesh_fingerprint
from hfcdem.workflows.places import (
    place_ratios,
    plot_first_crack_stress,
    stress_along_tunnels,
    wellbore_place,
)
from hfcdem.workflows.pumped_checkpoint import CheckpointFile, earlier_run

#: the columns of a pumped run's ``history.csv``, one row per step
PUMPED_COLUMNS = (
    "time_s",
    "cavity_pressure_Pa",
    "fluid_in_joints_m3",
    "crack_volume_m3",
    "tensile",
    "shear",
    "joints_holding_pressure",
)


def _held_at(phys: Physics) -> str:
    """`` at cells of N mm`` when the apertures follow the mesh size (else nothing)."""
    size = phys.joint_reference_size
    return "" if size is None else f" at cells of {size * 1e3:.3g} mm (following the mesh)"


def seepage_loading(scene: Scene) -> PressureRamp | CavityPumping:
    """Return how a ``wall_joints = "seepage"`` scene loads its cavity (clear errors).

    A constant ``rate`` pumps into the cavity (:class:`CavityPumping`); a linear
    pressure ramp drives it (:class:`PressureRamp`).
    """
    phys = scene.physics
    inj = phys.injection
    points: tuple[tuple[float, float], ...] = inj.points if inj is not None else ()
    steps = max(1, math.ceil(phys.duration / phys.solver.time_step - 1e-9))
    if inj is not None and inj.rate_controlled:
        if len(points) != 1:
            raise SceneError(
                "injection.rate_schedule",
                "wall_joints = 'seepage' pumps at one constant rate: give rate",
            )
        if phys.wall_film is not None:
            raise SceneError(
                "injection.wall_film",
                "seepage runs store fluid in the cavity of the mesh (plus extra_volume) and "
                "in the joints: drop wall_film",
            )
        longest = phys.solver.max_time_step  # quiet stretches grow their steps up to it
        return CavityPumping(
            points[0][1],
            phys.duration,
            steps,
            phys.initial_pressure,
            phys.extra_volume,
            max_dt=longest if math.isfinite(longest) else None,
            land_on_breaks=phys.solver.break_landing != "step",
            landing_tolerance=(
                phys.solver.break_tolerance if phys.solver.break_landing == "tolerance" else 0.0
            ),
            joint_pressure=phys.joint_pressure,
            until_first_break=phys.until == "first crack",
        )
    if phys.joint_pressure is not None:
        raise SceneError(
            "injection.joint_pressure",
            "a seepage pressure ramp starts its joints dry: joint_pressure is for a pumped rate",
        )
    if phys.solver.break_landing != "exact":
        raise SceneError(
            "solver.break_landing",
            'a seepage pressure ramp stops at its first break: "step" and "tolerance" are for '
            "a pumped rate",
        )
    if inj is None or len(points) != 2 or points[0][0] != 0.0:
        raise SceneError(
            "injection",
            "wall_joints = 'seepage' runs a pressure ramp (pressure_rate, or pressure_schedule = "
            "[['0 s', P0], [t1, P1]]) or pumps at a constant rate",
        )
    p0, (t1, p1) = points[0][1], points[1]
    if not p1 > p0:
        raise SceneError(
            "injection.pressure_schedule",
            f"the ramp must rise, got {show_stress(p0)} -> {show_stress(p1)}",
        )
    if phys.duration > t1 * (1 + 1e-12):
        raise SceneError(
            "injection.duration",
            f"the seepage ramp ends at the schedule's last time {t1:g} s, got {phys.duration:g} s",
        )
    rate = (p1 - p0) / t1
    if phys.pressure_step is not None:  # the same pressure resolution at any rate
        steps = max(1, math.ceil(rate * phys.duration / phys.pressure_step - 1e-9))
    return PressureRamp(rate, p0 + rate * phys.duration, steps, initial_pressure=p0)


def run_seepage_ramp(
    scene: Scene,
    solid: CDEMSolid,
    cavity: tuple[str, ...],
    out: Path,
    say: Callable[[str], None],
    record: Callable[[], dict[str, Any]],
    supports: tuple[str, ...] = (),
    resume: bool = False,
) -> dict[str, Any]:
    """Run the ramp of a seepage scene on ``solid`` and write its results into ``out``.

    ``supports``: walls that hold the blocks cut loose against them (a pumped run);
    ``resume``: a pumped run goes on from the checkpoint of a stopped one in ``out``
    (:mod:`hfcdem.workflows.pumped_checkpoint`).
    """
    phys, comm = scene.physics, solid.comm
    ramp = seepage_loading(scene)
    if solid.mode == "reduced":
        say(
            "reduced solid with seepage: every interface of the fracturable zone keeps its "
            "springs (the joints' pressure loads them all); the rock outside it is continuous"
        )
    if isinstance(ramp, CavityPumping):
        what = f"pumping {ramp.rate:.4g} m3/s into the cavity for {ramp.duration:.4g} s"
        if not ramp.land_on_breaks:
            what += " (breaks at the end of each step: solver.break_landing = 'step')"
        elif ramp.landing_tolerance > 0.0:
            what += (
                " (a step lands on its first break only when it moves the cavity pressure by "
                f"more than {ramp.landing_tolerance:.3g} of it: solver.break_landing = 'tolerance')"
            )
    else:
        what = f"a ramp of {ramp.rate / 1e6:.4g} MPa/s"
    say(
        f"seepage: {what} from {ramp.initial_pressure / 1e6:.4g} MPa, {ramp.steps} steps; "
        f"joints of hydraulic aperture {phys.joint_aperture * 1e6:.3g} um{_held_at(phys)} "
        + (
            "fill from dry"
            if phys.joint_pressure is None
            else f"start full at {phys.joint_pressure / 1e6:.4g} MPa"
        )
    )
    if isinstance(ramp, CavityPumping):
        return _run_pumped(scene, solid, (cavity, supports), ramp, out, say, record, resume)
    result = ramp_breakdown(solid, cavity, phys.fluid, phys.joints, ramp, progress=say)
    if result.stopped:
        say(f"stopped: {result.stopped}")
    rows = [list(row) for row in result.history]
    write_csv(
        out / "history.csv",
        ["time_s", "cavity_pressure_Pa", "fluid_in_joints_m3", "break_fraction_of_step"],
        [[r[0], r[1], r[2], r[3] if math.isfinite(r[3]) else -1.0] for r in rows],
        comm,
    )
    _write_joints(out / "joints.vtu", solid, result.joint_pressure, result.saturation)
    pb = result.pressure
    location = result.location
    summary: dict[str, Any] = {
        "scene": scene.name,
        "kind": "seepage_ramp",
        "breakdown_pressure_MPa": pb / 1e6 if pb is not None else None,
        "breakdown_time_s": result.time,
        "first_crack_pressure_MPa": pb / 1e6 if pb is not None else None,
        "first_crack_time_s": result.time,
        "first_crack": _first_crack(scene, location, result.mode),
        "peak_pressure_MPa": (
            max((r[1] for r in result.history), default=ramp.initial_pressure) / 1e6
            if pb is None
            else pb / 1e6
        ),
        "initial_failures": result.initial_failures,
        "intact_joints": solid.intact_count(),  # at the end: what was left to break
        "fracture_degree": solid.fracture_degree(),
        "joints_holding_pressure": result.wet_fraction,
        "wall_joint_pressure_ratio": result.wall_joint_pressure,
        "joint_aperture_m": phys.joint_aperture,
        "joint_reference_size_m": phys.joint_reference_size,
        "pressure_rate_MPa_per_s": ramp.rate / 1e6 if isinstance(ramp, PressureRamp) else None,
        "cavity_storage_m3_per_Pa": result.cavity_storage,
        "max_mass_error": result.max_mass_error,
        "steps": result.steps,
        "stopped": result.stopped,  # a ramp that breaks nothing is an answer, not a stop
    } | record()
    write_json(out / "summary.json", summary, comm)
    if comm.rank == 0 and rows:
        times = np.array([0.0] + [r[0] for r in rows])
        pressures = np.array([ramp.initial_pressure] + [r[1] for r in rows]) / 1e6
        curves = [(times, pressures, "cavity pressure", "-")]
        if pb is not None:
            label = f"first break {pb / 1e6:.2f} MPa"
            curves.append((np.array([result.time]), np.array([pb / 1e6]), label, "rv"))
        plot_lines(
            out / "pressure.png", curves, "time (s)", "pressure (MPa)", scene.name, MPI.COMM_SELF
        )
    comm.barrier()
    if result.stopped:
        pass
    elif pb is None:
        top = max((r[1] for r in result.history), default=ramp.initial_pressure)
        if summary["intact_joints"]:
            say(
                f"no joint broke up to {top / 1e6:.4g} MPa "
                f"({summary['intact_joints']} joints intact)"
            )
        else:
            say(
                f"no intact joint was left to break: the {result.initial_failures} that failed "
                "before the ramp were all it had (the rock is weaker than its in-situ stress)"
            )
    else:
        say(
            f"first break {pb / 1e6:.4g} MPa at {result.time:.4g} s "
            f"({summary['first_crack']['mode']}); {result.wet_fraction:.1%} of the joints "
            f"hold pressure, wall joints at {result.wall_joint_pressure:.3f} of the cavity's"
        )
    return summary


def _write_joints(
    path: Path, solid: CDEMSolid, pressure: np.ndarray | None, saturation: np.ndarray | None
) -> None:
    """Write every owned joint's saturation, pressure and state (per local facet) as VTU."""
    write_interfaces(path, *_joint_fields(solid, pressure, saturation), solid.comm)


def _joint_fields(
    solid: CDEMSolid, pressure: np.ndarray | None, saturation: np.ndarray | None
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Owned facets' vertices and their saturation, pressure (Pa) and state."""
    own = solid.owned
    zero = np.zeros(solid.num_facets)
    pj = pressure if pressure is not None else zero
    sat = saturation if saturation is not None else zero
    data = {"saturation": sat[own], "pressure": pj[own], "state": solid.state[own].astype(float)}
    return solid.vertex_coords[own], data


def _first_crack(
    scene: Scene,
    location: np.ndarray | None,
    mode: int | None,
    stress: dict[str, Any] | None = None,
) -> dict[str, Any] | None:
    """Return the summary's first crack: its point in 3D coordinates (m), its mode and place.

    ``stress``: the stress along the tunnels then (``time_s``, ``sigma_xx``), if measured.
    """
    if location is None:
        return None
    point = [*map(float, location), *([0.0] * (3 - len(location)))]
    where = {"point_m": point, "mode": FacetState(int(mode or 0)).name.lower()}
    return where | wellbore_place(scene, np.asarray(point)) | (stress or {})


def _run_pumped(
    scene: Scene,
    solid: CDEMSolid,
    walls: tuple[tuple[str, ...], tuple[str, ...]],
    pumping: CavityPumping,
    out: Path,
    say: Callable[[str], None],
    record: Callable[[], dict[str, Any]],
    resume: bool = False,
) -> dict[str, Any]:
    """Pump for the scene's duration past the first break; write the results into ``out``.

    ``walls``: the cavity's wall groups and the supporting ones; ``resume``: go
    on from the checkpoint of a stopped run in ``out``.
    """
    (cavity, supports), phys, comm = walls, scene.physics, solid.comm
    fingerprint = mesh_fingerprint(solid.tmesh)
    earlier = earlier_run(out, fingerprint, PUMPED_COLUMNS, say, comm) if resume else None
    interval = phys.output_interval or pumping.duration / 20.0
    since = None if earlier is None else float(earlier.checkpoint["t"])
    series = InterfaceFrames(out, "joints", pumping.duration, interval, comm, resume_from=since)

    def frame(t: float, pressure: np.ndarray, saturation: np.ndarray) -> None:
        series.offer(t, *_joint_fields(solid, pressure, saturation))

    # measured at the first break: kept in the checkpoint for a resumed run's summary
    stress: dict[str, Any] = {} if earlier is None else dict(earlier.checkpoint["workflow"])
    # the sessions before a resume, up to their last checkpoint: the case's cost in all
    earlier_wall = 0.0 if earlier is None else float(earlier.checkpoint.get("wall_s", 0.0))
    checkpoints = CheckpointFile(
        out / "checkpoint.json", fingerprint, stress, comm, earlier_wall=earlier_wall
    )

    def at_first_break(t: float, ratio: np.ndarray) -> None:
        ratios = place_ratios(scene, solid.midpoints, ratio, comm)
        if ratios:
            stress.update(ratio_by_place=ratios)
        profile = stress_along_tunnels(scene, solid)
        if profile:
            stress.update(time_s=t, sigma_xx=profile)

    # written step by step, so that a run stopped from outside keeps its history; a resumed
    # run's files keep the rows up to its checkpoint, replaced only at its first new step
    history = HistoryFile(out / "history.csv", PUMPED_COLUMNS, comm)
    step_costs = HistoryFile(out / "step_costs.csv", COST_COLUMNS, comm)
    kept = ([], []) if earlier is None else (earlier.history, earlier.costs)
    pending = [True]

    def start_files() -> None:
        history.start([dict(zip(PUMPED_COLUMNS, row, strict=True)) for row in kept[0]])
        step_costs.start([dict(zip(COST_COLUMNS, row, strict=True)) for row in kept[1]])
        pending[0] = False

    if earlier is None:
        start_files()

    def records(row: tuple[float, ...], cost: tuple[float, ...]) -> None:
        if pending[0]:
            start_files()
        history.append(dict(zip(PUMPED_COLUMNS, row, strict=True)))
        step_costs.append(dict(zip(COST_COLUMNS, cost, strict=True)))

    result = pump_with_seepage(
        solid,
        cavity,
        phys.fluid,
        phys.joints,
        pumping,
        progress=say,
        frames=frame,
        supports=supports,
        at_first_break=at_first_break,
        contact_hysteresis=phys.solver.contact_hysteresis,
        records=records,
        checkpoint=checkpoints.offer,
        resume=earlier,
    )
    if result.stopped:
        say(f"stopped: {result.stopped}")
    _write_joints(out / "joints.vtu", solid, result.joint_pressure, result.saturation)
    first, pb = result.first_pressure, result.breakdown
    location = result.first_location
    summary: dict[str, Any] = {
        "scene": scene.name,
        "kind": "seepage_pumping",
        "breakdown_pressure_MPa": pb / 1e6 if pb is not None else None,
        "breakdown_time_s": result.breakdown_time,
        "breakdown_drop_MPa": (
            result.breakdown_drop / 1e6 if result.breakdown_drop is not None else None
        ),
        "peak_pressure_MPa": result.peak_pressure / 1e6,
        "peak_time_s": result.peak_time,
        "peak_cut_off": result.peak_cut_off,
        "breakdown_note": pumping_note(result),
        "first_crack_pressure_MPa": first / 1e6 if first is not None else None,
        "first_crack_time_s": result.first_time,
        "first_crack": _first_crack(scene, location, result.first_mode, stress),
        "tensile_failures": result.tensile,
        "shear_failures": result.shear,
        "fracture_degree": solid.fracture_degree(),
        "initial_failures": result.initial_failures,
        "joints_holding_pressure": result.history[-1][6] if result.history else 0.0,
        "joint_aperture_m": phys.joint_aperture,
        "joint_reference_size_m": phys.joint_reference_size,
        # None: the joints started dry
        "joint_pressure_at_start_MPa": (
            None if pumping.joint_pressure is None else pumping.joint_pressure / 1e6
        ),
        "pumping_rate_m3_per_s": pumping.rate,
        "max_mass_error": result.max_mass_error,
        "secant_balances": result.secant_balances,
        "unsettled_retries": result.unsettled_retries,
        "rebalances": result.rebalances,
        "solid_solves": result.solid_solves,
        "factorisations": result.factorisations,
        "low_rank_events": result.low_rank_events,
        "debris_cells": result.debris_cells,
        "steps": result.steps,
        "stopped": result.stopped,
        "validity_limit": result.validity_limit,
        "until": phys.until,
        "earlier_sessions_wall_time_s": earlier_wall,
    } | record()
    write_json(out / "summary.json", summary, comm)
    if comm.rank == 0 and result.history:
        h = np.array(result.history)
        times = np.concatenate([[0.0], h[:, 0]])
        pressures = np.concatenate([[pumping.initial_pressure], h[:, 1]]) / 1e6
        curves = [(times, pressures, "cavity pressure", "-")]
        if first is not None and result.first_time is not None:
            label = f"first break {first / 1e6:.2f} MPa"
            curves.append((np.array([result.first_time]), np.array([first / 1e6]), label, "^"))
        if pb is not None and result.breakdown_time is not None:
            label = f"breakdown {pb / 1e6:.2f} MPa"
            curves.append((np.array([result.breakdown_time]), np.array([pb / 1e6]), label, "rv"))
        plot_lines(
            out / "pressure.png", curves, "time (s)", "pressure (MPa)", scene.name, MPI.COMM_SELF
        )
        plot_first_crack_stress(out, scene, summary["first_crack"])
    comm.barrier()
    return summary


def pumping_note(result: PumpingResult) -> str | None:
    """Say why a pumped run has no breakdown, or why its breakdown is in doubt (else None).

    The validity limit, or a stop, leaves a breakdown in doubt when the pressure
    rose past it before the run ended: the run's highest pressure then bounds the
    breakdown from below (:func:`hfcdem.coupling.breakdown.peak_is_lower_bound`,
    the rule of the other rungs and of the report).
    """
    if result.ended_on_first_break:
        return FIRST_CRACK_END
    early = result.validity_limit or result.stopped is not None
    cut_short = peak_is_lower_bound(result.peak_pressure, result.breakdown, early)
    ended = end_words(result.validity_limit)
    if result.breakdown is not None:
        if not cut_short:
            return None
        return (
            f"the pressure rose past it to {result.peak_pressure / 1e6:.4g} MPa (at "
            f"{result.peak_time:.4g} s) before {ended}: "
            "the breakdown is at least the highest pressure"
        )
    if result.steps == 0 and result.stopped:
        return f"the run stopped before its first step ({result.stopped})"
    if result.peak_time <= 0.0:
        return (
            "the pressure never rose above its starting value: the joints took more "
            "than the pump delivered"
        )
    peak = f"its peak {result.peak_pressure / 1e6:.4g} MPa (at {result.peak_time:.4g} s)"
    if cut_short:
        return (
            f"{ended} before a sustained drop after a "
            f"break confirmed {peak}: the peak is a lower bound"
        )
    if result.first_time is None:
        return "no interface broke by the end of the run"
    if result.history and result.peak_time >= result.history[-1][0]:
        return "the pressure still rises at the end of the run"
    return f"no sustained drop after a break confirmed {peak} before the end"


__all__ = ["PUMPED_COLUMNS", "pumping_note", "run_seepage_ramp", "seepage_loading"]
