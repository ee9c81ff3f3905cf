"""What the demo scripts share: their options, their printer and their ending.

A demo (``demos/*.py``) is a literate script: its cells show a scene or a
study and set the answer beside a reference.  What every one of them needs
besides is here, so that its cells keep to what it shows:

- :func:`demo_parser`: ``-o``, and for a scene or study demo ``--resolution``,
  ``--duration``, ``--force`` (and ``--groups`` for a study), with the line
  parsed by :func:`hfcdem.io.command_line.parse_with_petsc_options`, so PETSc options
  may follow;
- :func:`run_scene_file`, :func:`run_study_file`: a scene or study file of
  the repository run with those options;
- :func:`run_demo`: the script's ending.  Bad input (a ``--duration`` that is
  no time, a scene value out of range) ends with one line naming the field and
  exit 2, an output folder holding another scene's results with one line and
  exit 3, as ``hfcdem run`` does (:mod:`hfcdem.workflows.exit_codes`), instead of
  a traceback on every rank.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from mpi4py import MPI

from hfcdem.config.scene import load_scene
from hfcdem.io.command_line import parse_with_petsc_options
from hfcdem.io.progress import printer
from hfcdem.workflows.exit_codes import ExitCode, exit_code_for, run_exit_code
from hfcdem.workflows.run import run_scene
from hfcdem.workflows.study import load_study, run_study


def demo_parser(
    doc: str | None,
    output: str,
    *,
    scene: bool = True,
    study: bool = False,
    duration_example: str = "120 s",
) -> argparse.ArgumentParser:
    """Return a demo's parser: ``-o`` (default ``output``), and the scene or study options.

    ``doc``: the demo's docstring, whose first line describes it.  ``scene``:
    add ``--resolution`` (default ``coarse``) and ``--duration``; ``study``:
    the demo runs a study (``--groups``, and ``--force`` runs its cases again);
    without either, only ``-o`` and ``--force``.
    """
    parser = argparse.ArgumentParser(description=(doc or "").split("\n")[0])
    parser.add_argument("-o", "--output", default=output, help="output folder")
    if scene or study:
        parser.add_argument(
            "--resolution", default="coarse", help="mesh resolution of the scene (or 'default')"
        )
        parser.add_argument(
            "--duration", default=None, help=f"injection time, e.g. '{duration_example}'"
        )
    if study:
        parser.add_argument("--groups", type=int, default=1, help="cases run at once")
    parser.add_argument(
        "--force",
        action="store_true",
        help=(
            "run every case again, over other settings' runs"
            if study
            else "overwrite another scene's results"
        ),
    )
    return parser


def parse_demo_line(
    parser: argparse.ArgumentParser, argv: Sequence[str] | None = None
) -> tuple[argparse.Namespace, Callable[..., None]]:
    """Parse a demo's line (PETSc options apart); return it and a rank-0 printer."""
    return parse_with_petsc_options(parser, argv), printer(MPI.COMM_WORLD)


def run_scene_file(
    path: Path, args: argparse.Namespace, say: Callable[..., None]
) -> dict[str, Any]:
    """Run the scene file ``path`` with a demo's options; return the run's summary."""
    overrides = {"injection.duration": args.duration} if args.duration else None
    scene = load_scene(path, args.resolution, overrides=overrides)
    return run_scene(scene, args.output, MPI.COMM_WORLD, force=args.force, say=say)


def run_study_file(
    path: Path,
    args: argparse.Namespace,
    say: Callable[..., None],
    values: Sequence[Any] | None = None,
) -> list[dict[str, Any]]:
    """Run the study file ``path`` with a demo's options; return its rows.

    ``values`` replaces the swept values (a subset of the study's, say).
    """
    study = load_study(path, resolution=args.resolution)
    if values:
        study = study.with_values(tuple(values))
    if args.duration:
        study = study.with_fixed({"injection.duration": args.duration})
    return run_study(
        study, args.output, MPI.COMM_WORLD, groups=args.groups, force=args.force, say=say
    )


def run_demo(main: Callable[[], Any]) -> None:
    """Run a demo's ``main``; end bad input or a refused output with one line, not a traceback.

    The exit codes are ``hfcdem``'s (:mod:`hfcdem.workflows.exit_codes`): 2 for a
    scene field that is wrong (the line names it and what it expects), 3 for an
    output folder that holds another scene's results (kept; ``--force``
    overwrites them) or cannot be written, or a geometry that cannot be meshed;
    4 when ``main`` returns the summary of a run, or a study's rows, of which one
    stopped before its end.
    Every rank raises or returns these together, so every rank exits.
    """
    say = printer(MPI.COMM_WORLD)
    try:
        result = main()
    except Exception as exc:
        code = exit_code_for(exc)
        if code is None:  # unforeseen: the traceback is the report
            raise
        say(f"error: {exc}", err=True)
        raise SystemExit(code) from None
    # a demo that shows a run ends as hfcdem run does, one that shows a study's rows as
    # hfcdem study does: 4 when a run stopped before its end
    runs = [result] if isinstance(result, Mapping) else result if isinstance(result, list) else []
    if any(isinstance(r, Mapping) and "stopped" in r and run_exit_code(r) for r in runs):
        raise SystemExit(ExitCode.STOPPED)


__all__ = ["demo_parser", "parse_demo_line", "run_demo", "run_scene_file", "run_study_file"]
