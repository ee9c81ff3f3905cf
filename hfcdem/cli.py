"""The ``hfcdem`` command line."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from hfcdem.io.command_line import parse_with_petsc_options, split_petsc_options
from hfcdem.workflows.exit_codes import ExitCode, exit_codes_text, run_exit_code


def _info(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from hfcdem.info import versions

    table = versions(MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        width = max(len(k) for k in table)
        for key, value in table.items():
            print(f"{key:<{width}}  {value}")
    return ExitCode.OK


def _scene_files(args: argparse.Namespace) -> list[Path]:
    files = [Path(f) for f in args.scenes]
    if args.all:
        files += sorted(Path(args.scene_dir).glob("*.toml"))
    return files


def _mesh(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from hfcdem.config.scene import load_scene
    from hfcdem.config.tables import SceneError
    from hfcdem.config.units import FieldError, parse_quantity
    from hfcdem.io.progress import printer
    from hfcdem.mesh.build import mesh_scene
    from hfcdem.mesh.tagged import MeshingError

    comm = MPI.COMM_WORLD

    say = printer(comm)

    files = _scene_files(args)
    if not files:
        say("hfcdem mesh: no scene files given (name them, or use --all)", err=True)
        return ExitCode.BAD_INPUT
    try:
        size = parse_quantity(args.size, "length", "--size") if args.size else None
        scenes = [load_scene(f, args.resolution, size) for f in files]
    except FieldError as exc:
        say(f"error: {exc}", err=True)
        return ExitCode.BAD_INPUT
    names = [s.name for s in scenes]
    if len(set(names)) != len(names):
        say(f"error: scene names repeat: {names}", err=True)
        return ExitCode.BAD_INPUT
    for scene in scenes:
        out = Path(args.output) / scene.name if len(scenes) > 1 else Path(args.output)
        try:
            report = mesh_scene(scene, out, comm, picture=not args.no_picture)
        except (MeshingError, SceneError) as exc:
            say(f"error: {exc}", err=True)
            return ExitCode.OUTPUT_REFUSED
        vol = report["volumes"]["rock_total"]
        say(
            f"{scene.name}: {report['cells']} cells, {report['vertices']} vertices in "
            f"{report['seconds_to_mesh']:.1f} s on {comm.size} rank(s); rock volume "
            f"{vol['rel_error']:+.2%} vs analytic; min quality "
            f"{report['element_quality']['min']:.3f} -> {out}"
        )
        for note in report.get("notes", []):
            say(f"  note: {note}")
        if "picture_error" in report:
            say(f"  warning: {report['picture_error']} (use --no-picture to skip it)", err=True)
    return ExitCode.OK


def _overrides(items: list[str] | None) -> dict[str, object]:
    """Parse ``KEY=VALUE`` pairs; VALUE is a TOML value, or else taken as a string.

    An empty VALUE (``KEY=``) removes the field, so its default applies.
    """
    import tomllib

    from hfcdem.config.tables import SceneError

    out: dict[str, object] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise SceneError("--set", f"expected KEY=VALUE, got {item!r}")
        if not value.strip():
            out[key.strip()] = None  # removed: the default applies
            continue
        try:
            out[key.strip()] = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = value.strip()
    return out


def _run(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from hfcdem.config.scene import load_scene
    from hfcdem.config.units import FieldError
    from hfcdem.io.progress import printer
    from hfcdem.mesh.tagged import MeshingError
    from hfcdem.workflows.run import OutputInUse, run_scene
    from hfcdem.workflows.time_step_check import halved_steps

    comm = MPI.COMM_WORLD

    say = printer(comm)

    try:
        scene = load_scene(args.scene, args.resolution, overrides=_overrides(args.set))
        halved = halved_steps(scene) if args.check_time_step else None
        summary = run_scene(scene, args.output, comm, force=args.force, say=say, resume=args.resume)
        code = _say_run(scene.name, summary, args.output, say)
        if halved is not None:
            dt = scene.physics.solver.time_step if scene.physics else math.nan
            code = max(code, _check_time_step(summary, halved, dt, args, say))
    except FieldError as exc:  # bad scene input: nothing was meshed or written
        say(f"error: {exc}", err=True)
        return ExitCode.BAD_INPUT
    except (OutputInUse, MeshingError) as exc:
        say(f"error: {exc}", err=True)
        return ExitCode.OUTPUT_REFUSED
    return code


def _check_time_step(
    summary: dict[str, Any],
    halved: dict[str, str],
    dt: float,
    args: argparse.Namespace,
    say: Any,
) -> int:
    """Run the scene again at half its time step; say and write how far the answers move."""
    from mpi4py import MPI

    from hfcdem.config.scene import load_scene
    from hfcdem.io.files import write_json
    from hfcdem.workflows.run import run_scene
    from hfcdem.workflows.time_step_check import HALF_STEP_DIR, check_words, compare_steps

    comm = MPI.COMM_WORLD
    out = Path(args.output)
    half_dir = out / HALF_STEP_DIR
    changed = ", ".join(f"{key} = {value}" for key, value in halved.items())
    say(
        f"checking the time step: the run again with {changed}, into {half_dir}/ "
        "(at least as long as the run above)"
    )
    scene = load_scene(args.scene, args.resolution, overrides={**_overrides(args.set), **halved})
    half = run_scene(
        scene,
        half_dir,
        comm,
        force=args.force,
        say=say,
        resume=args.resume and (half_dir / "checkpoint.json").exists(),
    )
    code = _say_run(scene.name, half, str(half_dir), say)
    check = compare_steps(summary, half, dt)
    write_json(out / "time_step_check.json", check, comm)
    say(check_words(check))
    return code


def _say_run(name: str, summary: dict[str, Any], output: str, say: Any) -> int:
    """Say a run's last line (results in ``output``); return its exit code."""
    from hfcdem.coupling.breakdown import FIRST_CRACK_END

    if summary.get("kind") == "static":
        say(
            f"{name}: crack pressure {summary['crack_pressure_MPa']:g} MPa, max opening "
            f"{summary['max_crack_opening_m'] * 1e6:.3f} um, "
            f"{summary['overstressed_interfaces']} springs past their strength, "
            f"{summary['wall_time_s']:.1f} s; results in {output}/"
        )
        return ExitCode.OK
    bd = summary["breakdown_pressure_MPa"]
    if summary.get("kind") == "seepage_ramp":
        first = summary["first_crack"]
        say(
            f"{name}: first break "
            + (
                f"{bd:.2f} MPa at {summary['breakdown_time_s']:.3g} s ({first['mode']})"
                if bd is not None
                else "not reached"
            )
            + f", {summary['joints_holding_pressure']:.1%} of the joints holding pressure, "
            f"{summary['wall_time_s']:.1f} s; results in {output}/"
        )
        return run_exit_code(summary)
    if summary.get("breakdown_note") == FIRST_CRACK_END:  # injection.until = "first crack"
        say(
            f"{name}: {first_crack_words(summary)}; the run ended there "
            f'(injection.until = "first crack"), {summary["tensile_failures"]} tensile / '
            f"{summary['shear_failures']} shear, {summary['wall_time_s']:.1f} s; results in "
            f"{output}/"
        )
        return run_exit_code(summary)
    if summary.get("until") == "first crack" and summary.get("first_crack_pressure_MPa") is None:
        peak = summary.get("peak_pressure_MPa")
        say(
            f"{name}: no first crack by the end of the injection "
            '(injection.until = "first crack" ran to injection.duration)'
            + (f"; highest pressure {peak:.2f} MPa" if peak is not None else "")
            + f", {summary['wall_time_s']:.1f} s; results in {output}/"
        )
        return run_exit_code(summary)
    if summary.get("kind") == "seepage_pumping":
        fc = summary["first_crack_pressure_MPa"]
        before = summary.get("earlier_sessions_wall_time_s")  # a resumed run's
        say(
            f"{name}: breakdown {breakdown_words(summary)}"
            + (
                f", first break {fc:.2f} MPa at {summary['first_crack_time_s']:.3g} s "
                f"({summary['first_crack']['mode']})"
                if fc is not None
                else ""
            )
            + f", {summary['tensile_failures']} tensile / {summary['shear_failures']} shear, "
            f"{summary['wall_time_s']:.1f} s"
            + (f" (and {before:.1f} s before the resume)" if before else "")
            + f"; results in {output}/"
        )
        return run_exit_code(summary)
    front = summary.get("fluid_front_m")
    say(
        f"{name}: breakdown {breakdown_words(summary)}"
        + (f", fluid front {front:.2f} m" if front is not None else "")
        + f", fracture degree {summary['fracture_degree']:.4f}, "
        f"{summary['tensile_failures']} tensile / {summary['shear_failures']} shear failures, "
        f"{summary['wall_time_s']:.1f} s; results in {output}/"
    )
    return run_exit_code(summary)


def first_crack_pressure_words(summary: dict[str, Any]) -> str:
    """Say the first crack's pressure, as a range where no step landed on it."""
    low = summary["first_crack_pressure_MPa"]
    high = summary.get("first_crack_pressure_bound_MPa")
    # (a pressure that fell before the crack can leave the highest before it above)
    if high is None or high <= low or f"{high:.2f}" == f"{low:.2f}":
        return f"{low:.2f} MPa"
    return f"between {low:.2f} and {high:.2f} MPa (no step landed on it)"


def first_crack_words(summary: dict[str, Any]) -> str:
    """Say a run's first crack: pressure, time, place, distance from the wellbore wall, mode."""
    first = summary.get("first_crack") or {}
    when = summary["first_crack_time_s"]
    said = [f"first crack {first_crack_pressure_words(summary)} at {when:.4g} s"]
    where = first.get("distance_from_wellbore_wall_m")
    if first.get("place"):
        said.append(str(first["place"]))
    if where is not None:
        said.append(f"{1e3 * where:.1f} mm from the wellbore wall")
    return ", ".join(said) + (f" ({first['mode']})" if first.get("mode") else "")


def breakdown_words(summary: dict[str, Any]) -> str:
    """Say a coupled run's breakdown as its last line does: the value, or why there is none.

    A note (no breakdown, or one the validity limit leaves in doubt) comes with
    the run's highest pressure, which is then the answer a user asks for.
    """
    bd, note = summary.get("breakdown_pressure_MPa"), summary.get("breakdown_note")
    peak = summary.get("peak_pressure_MPa")
    if note and peak is not None and "MPa" not in note:  # a pumped run's note quotes it
        note = f"{note}; highest pressure {peak:.2f} MPa"
    if bd:
        drop = summary.get("breakdown_drop_MPa")
        said = [f"the pressure fell {drop:.2f} MPa after it"] if drop is not None else []
        said += [note] if note else []
        return f"{bd:.2f} MPa at {summary['breakdown_time_s']:.3g} s" + (
            f" ({'; '.join(said)})" if said else ""
        )
    return f"none ({note})" if note else "none"


def _study(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from hfcdem.config.units import FieldError
    from hfcdem.io.progress import printer
    from hfcdem.workflows.convergence import study_kind
    from hfcdem.workflows.run import OutputInUse
    from hfcdem.workflows.study import load_study, run_study

    comm = MPI.COMM_WORLD

    say = printer(comm)

    try:
        if args.convergence or (args.study and study_kind(args.study) == "convergence"):
            return _convergence(args, say)
        if not args.study:
            say("error: give a study file, or --convergence SCENE.toml", err=True)
            return ExitCode.BAD_INPUT
        study = load_study(args.study, args.resolution)
        if args.values:
            study = study.with_values(_values(args.values))
        if args.set:
            study = study.with_fixed(_overrides(args.set))
        rows = run_study(study, args.output, comm, groups=args.groups, force=args.force, say=say)
    except FieldError as exc:
        say(f"error: {exc}", err=True)
        return ExitCode.BAD_INPUT
    except ValueError as exc:
        say(f"error: {exc}", err=True)
        return ExitCode.BAD_INPUT
    except OutputInUse as exc:  # a case directory holds a run with other settings
        say(f"error: {exc}", err=True)
        return ExitCode.OUTPUT_REFUSED
    stopped = [str(r["value"]) for r in rows if run_exit_code(r)]
    if stopped:  # the table is written; a script should still hear of it
        say(f"cases that stopped before their end: {', '.join(stopped)} (results.csv)", err=True)
        return ExitCode.STOPPED
    return ExitCode.OK


def _values(text: str) -> tuple[object, ...]:
    """Split ``a,b,c``; each item is a TOML value (``100``) or else a string (``10 mm``)."""
    import tomllib

    out: list[object] = []
    for item in text.split(","):
        try:
            out.append(tomllib.loads(f"v = {item.strip()}")["v"])
        except tomllib.TOMLDecodeError:
            out.append(item.strip())
    return tuple(out)


def _convergence(args: argparse.Namespace, say: Any) -> int:
    """Run a convergence study: a kind = "convergence" file, or --convergence SCENE."""
    from mpi4py import MPI

    from hfcdem.workflows.convergence import (
        convergence_study,
        load_convergence,
        run_convergence,
    )

    if args.groups != 1:
        say("error: a convergence study times its cases: run them one at a time", err=True)
        return ExitCode.BAD_INPUT
    values = _values(args.resolutions or args.values) if args.resolutions or args.values else ()
    if args.convergence:
        if args.study:
            say("error: give a study file or --convergence SCENE.toml, not both", err=True)
            return ExitCode.BAD_INPUT
        if not values:
            say("error: --convergence needs --resolutions or --values", err=True)
            return ExitCode.BAD_INPUT
        parameter = "resolution" if args.resolutions else args.parameter
        fixed = _overrides(args.set)
        study = convergence_study(args.convergence, parameter, values, fixed, args.resolution)
    else:
        study = load_convergence(args.study, args.resolution)
        if values:
            study = study.with_values(values)
        if args.set:
            study = study.with_fixed(_overrides(args.set))
    run_convergence(study, args.output, MPI.COMM_WORLD, force=args.force, say=say)
    return ExitCode.OK


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of the ``hfcdem`` command."""
    parser = argparse.ArgumentParser(
        prog="hfcdem",
        description="Hydraulic fracture initiation from perforation tunnels (CDEM on DOLFINx).",
        epilog=exit_codes_text(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    info = sub.add_parser("info", help="print the versions of hfcdem, DOLFINx, PETSc, Gmsh, MPI")
    info.set_defaults(func=_info)
    _add_mesh(sub)
    _add_run(sub)
    _add_study(sub)
    _add_reproduce(sub)
    return parser


def _add_mesh(sub: Any) -> None:
    mesh = sub.add_parser(
        "mesh",
        help="mesh scene files: .msh, .xdmf (ParaView), .png and mesh_report.json",
        description="Mesh one or more scene files (TOML).  One scene writes into OUTPUT; "
        "several write into OUTPUT/NAME.",
    )
    mesh.add_argument("scenes", nargs="*", metavar="SCENE.toml")
    mesh.add_argument("-o", "--output", required=True, metavar="DIR")
    mesh.add_argument(
        "--size", metavar="LENGTH", help="element size at the perforation, e.g. '3 mm'"
    )
    mesh.add_argument(
        "--resolution",
        metavar="NAME",
        help="a named resolution of the scene's [geometry.mesh.resolutions]; the catalogue "
        "scenes have 'coarse', the single-perforation ones 'paper' (about 100k cells)",
    )
    mesh.add_argument("--all", action="store_true", help="also mesh every scene in --scene-dir")
    mesh.add_argument("--scene-dir", default="meshes/scenes", metavar="DIR")
    mesh.add_argument("--no-picture", action="store_true", help="skip the PNG")
    mesh.set_defaults(func=_mesh)


def _add_run(sub: Any) -> None:
    run = sub.add_parser(
        "run",
        help="run a scene: inject, break, write summary.json, history.csv, pictures, fields",
        description="Run a scene file with [rock], [stress] and [injection] (or [load]) sections "
        "(serially or under mpirun).",
    )
    run.add_argument("scene", metavar="SCENE.toml")
    run.add_argument("-o", "--output", required=True, metavar="DIR")
    run.add_argument("--resolution", metavar="NAME", help="a named mesh resolution of the scene")
    run.add_argument(
        "--force", action="store_true", help="overwrite another scene's results in DIR"
    )
    run.add_argument(
        "--resume",
        action="store_true",
        help="continue a stopped run from its checkpoint (not a seepage pressure ramp or a "
        "static run: they keep none)",
    )
    run.add_argument(
        "--check-time-step",
        action="store_true",
        help="then run the scene again at half its time step, into DIR/half_step, and say how "
        "far the answers move (DIR/time_step_check.json); not for a static scene",
    )
    run.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="replace a scene field, e.g. --set injection.duration='120 s'; KEY= removes it "
        "(repeatable)",
    )
    run.set_defaults(func=_run)


def _add_study(sub: Any) -> None:
    study = sub.add_parser(
        "study",
        help="sweep a scene field over values, or run a convergence study (--convergence)",
        description="Run a study file (kind 'sweep': results.csv and study.png; kind "
        "'convergence': results.csv, convergence.csv and convergence.png), or a convergence "
        "study of SCENE.toml over --resolutions or --parameter and --values.",
    )
    study.add_argument("study", nargs="?", metavar="STUDY.toml")
    study.add_argument("-o", "--output", required=True, metavar="DIR")
    study.add_argument(
        "--convergence", metavar="SCENE.toml", help="a convergence study of this scene"
    )
    study.add_argument(
        "--resolutions",
        metavar="A,B,C",
        help="named resolutions to converge over, e.g. coarse,default,fine",
    )
    study.add_argument(
        "--parameter",
        default="resolution",
        help="with --convergence: the swept key (resolution, geometry.mesh.size, "
        "rock.spring_factor, solver.time_step, solver.max_time_step, solver.linear_solver, "
        "solver.solid, solver.band_threshold)",
    )
    study.add_argument(
        "--values", metavar="A,B,C", help="the swept values (replace a study file's)"
    )
    study.add_argument("--resolution", help="the mesh resolution of every case (not swept)")
    study.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="fix a scene field in every case (KEY= removes it)",
    )
    study.add_argument(
        "--groups", type=int, default=1, help="run this many cases at once (ranks split evenly)"
    )
    study.add_argument("--force", action="store_true", help="rerun cases that are done")
    study.set_defaults(func=_study)


def _reproduce(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from hfcdem.io.progress import printer
    from hfcdem.reproduce.runner import run_reproduction

    comm = MPI.COMM_WORLD
    say = printer(comm)
    only = [n.strip() for n in args.only.split(",") if n.strip()] if args.only else None
    try:
        records = run_reproduction(
            args.output,
            comm,
            tier="quick" if args.quick else "full",
            fidelity=args.fidelity,
            resolution=args.resolution,
            only=only,
            force=args.force,
            say=say,
            watchdog_s=60.0 * args.watchdog,
        )
    except ValueError as exc:
        say(f"error: {exc}", err=True)
        return ExitCode.BAD_INPUT
    if args.readme:
        from hfcdem.reproduce.report import update_readme

        error = None
        if comm.rank == 0:
            try:
                update_readme(Path(args.readme), (Path(args.output) / "summary.md").read_text())
            except (OSError, ValueError) as exc:
                error = str(exc)
        error = comm.bcast(error, root=0)
        if error:
            say(f"error: {error}", err=True)
            return ExitCode.BAD_INPUT
        say(f"{args.readme}: its results table is now this report's")
    limits = [r.name for r in records if r.status == "limit"]
    if limits:
        say(f"cases that ended at the model's validity limit: {', '.join(limits)} (see the report)")
    failed = [r.name for r in records if r.status in ("failed", "stopped")]
    if failed:
        say(f"cases that failed or stopped: {', '.join(failed)} (see the report)", err=True)
        return ExitCode.STOPPED
    return ExitCode.OK


def _minutes_arg(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"expected minutes >= 0 (0: never), got {text!r}")
    return value


def _add_reproduce(sub: Any) -> None:
    rep = sub.add_parser(
        "reproduce",
        help="run the cases of the four papers and write a report beside the papers' values",
        description="Run every case of the reproduction report (hfcdem/reproduce/cases.py) into "
        "DIR/cases/NAME, skipping cases done, and write DIR/report.html, report.md, results.csv "
        "and figures/.  Serially or under mpirun.",
    )
    rep.add_argument("-o", "--output", required=True, metavar="DIR")
    rep.add_argument(
        "--quick", action="store_true", help="the quick tier: a few cases, minutes on 2 cores"
    )
    rep.add_argument(
        "--fidelity",
        default="scene",
        choices=("scene", "uniform", "viscous", "seepage"),
        help="the flow model of every injection case (default: as each scene file says)",
    )
    rep.add_argument("--resolution", metavar="NAME", help="a named mesh resolution for every case")
    rep.add_argument("--only", metavar="A,B", help="run only these cases (names in the report)")
    rep.add_argument("--force", action="store_true", help="run again the cases already done")
    rep.add_argument(
        "--watchdog",
        type=_minutes_arg,
        default=30.0,
        metavar="MIN",
        help="end the run (exit 5) when no progress line comes for MIN minutes "
        "(default 30; 0: never); cases done are kept",
    )
    rep.add_argument(
        "--readme",
        metavar="FILE",
        help="write the report's summary table into FILE, between its 'hfcdem reproduce' markers",
    )
    rep.set_defaults(func=_reproduce)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``hfcdem`` command; return the process exit code.

    PETSc options may appear anywhere on the line (:func:`parse_with_petsc_options`).
    """
    parser = build_parser()
    args = parse_with_petsc_options(parser, argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return ExitCode.BAD_INPUT
    from mpi4py import MPI

    from hfcdem.io.files import OutputDirError
    from hfcdem.io.progress import printer

    say = printer(MPI.COMM_WORLD)
    try:
        return int(args.func(args))
    except OutputDirError as exc:
        say(f"error: {exc}", err=True)
        return ExitCode.OUTPUT_REFUSED
    except KeyboardInterrupt:  # Ctrl-C: one line, not a solver's traceback
        say(f"interrupted: {_AFTER_INTERRUPT.get(args.command, _WHOLE)}", err=True)
        return ExitCode.INTERRUPTED


_WHOLE = "every output is written whole, so nothing written before is lost"
#: what a user has after Ctrl-C, per command
_AFTER_INTERRUPT = {
    "run": "the steps written so far stand (history.csv, checkpoint.json); continue with "
    "--resume (a seepage pressure ramp starts again)",
    "study": "finished cases stand; run the same command again to go on (they are skipped)",
    "reproduce": "finished cases stand; run the same command again to go on (they are skipped)",
}


__all__ = [
    "breakdown_words",
    "build_parser",
    "main",
    "parse_with_petsc_options",
    "split_petsc_options",
]
