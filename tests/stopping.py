"""A run stopped from outside, as Ctrl-C or a time limit would stop it.

Not a test module: imported by test_run, test_study and test_reproduce.
"""

from hfcdem.workflows.observers import StepObserver


class Interrupted(Exception):
    """Raised by :class:`StopAt`; nothing in hfcdem catches it."""


class StopAt(StepObserver):
    """Interrupt a run after the step that reaches ``time``."""

    def __init__(self, time):
        self.time = time

    def step(self, frac, rec):
        if rec.time >= self.time:
            raise Interrupted
