"""How ``hfcdem`` and the demo scripts end: one table of exit codes, so they agree.

Scripts that drive hfcdem (a study over many scenes, a CI job) branch on these:

====  ===================  ==========================================================
code  name                 meaning
====  ===================  ==========================================================
0     ``OK``               done: the run reached its end or the model's validity limit
2     ``BAD_INPUT``        a scene, study or command-line field is wrong (the line
                           names it); nothing was meshed or written
3     ``OUTPUT_REFUSED``   the output folder holds another scene's results (kept;
                           ``--force`` overwrites them) or cannot be written, or the
                           geometry cannot be meshed
4     ``STOPPED``          a run, or a case of a study or report, stopped before its
                           end (its solver gave up); what it wrote stands
5     ``STALLED``          the report's watchdog: no progress line for its minutes
130   ``INTERRUPTED``      Ctrl-C; every output is written whole
====  ===================  ==========================================================

The demo scripts (:func:`hfcdem.workflows.demos.run_demo`) end as ``hfcdem run``
and ``hfcdem study`` do: 0, 2, 3, or 4 when a run they show stopped.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import IntEnum
from typing import Any


class ExitCode(IntEnum):
    """The process exit codes of ``hfcdem`` and the demos (module docstring)."""

    OK = 0
    BAD_INPUT = 2
    OUTPUT_REFUSED = 3
    STOPPED = 4
    STALLED = 5
    INTERRUPTED = 130


#: a few words per code, for ``hfcdem --help``
MEANINGS = {
    ExitCode.OK: "done (the run's end or the model's validity limit)",
    ExitCode.BAD_INPUT: "bad input (the line names the field)",
    ExitCode.OUTPUT_REFUSED: "output refused (another scene's results, unwritable) or unmeshable",
    ExitCode.STOPPED: "a run, or a case of a study or report, stopped before its end",
    ExitCode.STALLED: "the report's watchdog heard no progress",
    ExitCode.INTERRUPTED: "interrupted (Ctrl-C)",
}


def exit_codes_text() -> str:
    """Return the table of exit codes as ``hfcdem --help`` ends with it."""
    return "exit codes:\n" + "\n".join(f"  {int(c):>3}  {MEANINGS[c]}" for c in ExitCode)


def run_exit_code(summary: Mapping[str, Any]) -> ExitCode:
    """Return how a run with ``summary`` ends: OK at its end or the validity limit, else STOPPED.

    ``summary`` is a run's ``summary.json`` (``stopped``: None, or why it stopped).
    """
    if summary.get("stopped") is None or summary.get("validity_limit"):
        return ExitCode.OK
    return ExitCode.STOPPED


def exit_code_for(exc: BaseException) -> ExitCode | None:
    """Return the exit code that ends a command on ``exc``, or None for an unforeseen error.

    Bad input (:class:`~hfcdem.config.units.FieldError`, which scene and study
    errors are) is ``BAD_INPUT``; an output folder that is refused or cannot be
    written, and a geometry Gmsh cannot mesh, are ``OUTPUT_REFUSED``.
    """
    from hfcdem.config.units import FieldError
    from hfcdem.io.files import OutputDirError
    from hfcdem.mesh.tagged import MeshingError
    from hfcdem.workflows.run import OutputInUse

    if isinstance(exc, FieldError):
        return ExitCode.BAD_INPUT
    if isinstance(exc, OutputInUse | OutputDirError | MeshingError):
        return ExitCode.OUTPUT_REFUSED
    return None


__all__ = ["MEANINGS", "ExitCode", "exit_code_for", "exit_codes_text", "run_exit_code"]
