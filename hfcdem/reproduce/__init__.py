"""Reproduce the four papers: every case beside the paper's number, in one report.

``hfcdem reproduce -o DIR`` runs the cases of :mod:`hfcdem.reproduce.cases`
(each from a scene or study file of the checkout) into ``DIR/cases/NAME``,
skipping what is done, and writes ``DIR/report.html``, ``DIR/report.md`` and
``DIR/results.csv`` (:mod:`hfcdem.reproduce.report`): per row the paper's
value, ours, the gap, the target and whether it is met, the resolution, the
estimated discretisation error and the wall time.
"""

from hfcdem.reproduce.cases import CASES, PAPERS, TIERS, Case, select_cases
from hfcdem.reproduce.compare import Comparison
from hfcdem.reproduce.runner import CaseResult, run_reproduction

__all__ = [
    "CASES",
    "PAPERS",
    "TIERS",
    "Case",
    "CaseResult",
    "Comparison",
    "run_reproduction",
    "select_cases",
]
