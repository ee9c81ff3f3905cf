"""The exit codes ``hfcdem`` and the demos share (hfcdem.workflows.exit_codes)."""

from __future__ import annotations

import pytest

from hfcdem.config.tables import SceneError
from hfcdem.config.units import FieldError
from hfcdem.io.files import OutputDirError
from hfcdem.mesh.tagged import MeshingError
from hfcdem.workflows.exit_codes import ExitCode, exit_code_for, exit_codes_text, run_exit_code
from hfcdem.workflows.run import OutputInUse


@pytest.mark.parametrize(
    ("error", "code"),
    [
        (FieldError("injection.rate", "expected a positive rate"), 2),
        (SceneError("geometry.mesh.size", "expected a length"), 2),
        (OutputInUse("results/x holds another scene's results"), 3),
        (OutputDirError("cannot write results/x"), 3),
        (MeshingError("the model has no named cell group"), 3),
    ],
)
def test_each_foreseen_error_has_its_documented_code(error, code):
    assert exit_code_for(error) == code


def test_an_unforeseen_error_has_no_code_so_its_traceback_is_kept():
    assert exit_code_for(RuntimeError("a bug")) is None
    assert exit_code_for(KeyboardInterrupt()) is None


def test_the_codes_are_the_documented_numbers():
    # scripts branch on these numbers (README, "Exit codes"): renumbering one breaks them
    assert {c.name: int(c) for c in ExitCode} == {
        "OK": 0,
        "BAD_INPUT": 2,
        "OUTPUT_REFUSED": 3,
        "STOPPED": 4,
        "STALLED": 5,
        "INTERRUPTED": 130,
    }


def test_hfcdem_help_ends_with_every_code():
    from hfcdem.cli import build_parser

    text = build_parser().format_help()
    assert text.rstrip().endswith(exit_codes_text().rstrip())
    assert "    2  bad input (the line names the field)" in text
    assert [line.split()[0] for line in exit_codes_text().splitlines()[1:]] == [
        str(int(c)) for c in ExitCode
    ]


def test_a_run_ends_ok_at_its_end_or_the_validity_limit_else_stopped():
    assert run_exit_code({"stopped": None}) == 0
    assert run_exit_code({"stopped": "a block came loose", "validity_limit": True}) == 0
    assert run_exit_code({"stopped": "did not settle in 200 iterations"}) == 4
