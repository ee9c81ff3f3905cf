"""A command line with PETSc options on it: the ``hfcdem`` command's and the demos'.

PETSc options may stand anywhere on the line; they go to PETSc's options
database (where they override the solvers' defaults under their prefixes) and
the rest to the command's own parser.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence


def split_petsc_options(argv: Sequence[str]) -> tuple[list[str], dict[str, str]]:
    """Split ``argv`` into the command's own arguments and PETSc options.

    A PETSc option is a single dash and a name with an underscore
    (``-hfcdem_solid_pc_factor_mat_solver_type``, ``-mat_mumps_icntl_14``,
    ``-log_view``), with the next token as its value unless that is an option
    (a flag gets the empty value).  Returns the remaining arguments and the
    options by name (without the dash).
    """
    ours: list[str] = []
    petsc: dict[str, str] = {}
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        tok = tokens[i]
        name = tok[1:]
        if tok.startswith("-") and not tok.startswith("--") and "_" in name and name[0].isalpha():
            nxt = tokens[i + 1] if i + 1 < len(tokens) else None
            if nxt is not None and not (nxt.startswith("-") and not _is_number(nxt)):
                petsc[name] = nxt
                i += 1
            else:
                petsc[name] = ""
        else:
            ours.append(tok)
        i += 1
    return ours, petsc


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def parse_with_petsc_options(
    parser: argparse.ArgumentParser, argv: Sequence[str] | None = None
) -> argparse.Namespace:
    """Parse ``argv`` (default: the command line) with ``parser``, PETSc options apart.

    PETSc options anywhere on the line (e.g. ``-hfcdem_cdem_ksp_type cg``, see
    :func:`split_petsc_options`) go to PETSc's options database, where they
    override the solvers' defaults.  The demos parse their lines with it too.
    """
    ours, petsc = split_petsc_options(sys.argv[1:] if argv is None else argv)
    if petsc:
        from petsc4py import PETSc

        db = PETSc.Options()
        for name, value in petsc.items():
            db.setValue(name, value)
    return parser.parse_args(ours)


__all__ = ["parse_with_petsc_options", "split_petsc_options"]
