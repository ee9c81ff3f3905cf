"""The ``hfcdem`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence


def _info(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from hfcdem.info import versions

    table = versions(MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        width = max(len(k) for k in table)
        for key, value in table.items():
            print(f"{key:<{width}}  {value}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of the ``hfcdem`` command."""
    parser = argparse.ArgumentParser(
        prog="hfcdem",
        description="Hydraulic fracture initiation from perforation tunnels (CDEM on DOLFINx).",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    info = sub.add_parser("info", help="print the versions of hfcdem, DOLFINx, PETSc, Gmsh, MPI")
    info.set_defaults(func=_info)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``hfcdem`` command; return the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    return int(args.func(args))
