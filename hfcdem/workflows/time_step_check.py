r"""How much of a run's answer is its time step: the same run at half the step.

``hfcdem run SCENE -o DIR --check-time-step`` runs the scene, then runs it
again with ``solver.time_step`` halved (and ``solver.max_time_step`` where the
scene gives one) into ``DIR/half_step/``, and says how far the half step moves
each answer: breakdown, highest pressure, first-crack pressure and time, and
for a crack that only propagates the fluid front and the inlet opening.  It
writes ``DIR/time_step_check.json`` and ends with one line, e.g.::

    time step: halving it (0.1 -> 0.05 s) moves the breakdown 61.21 -> 106.14 MPa
    (+42.33%), the first crack 14.42 -> 14.42 MPa (0.00%); at first order in the
    step, this run's own error is about twice the larger move (84.67%); a
    breakdown is in doubt (its note: time_step_check.json)

(``borehole_pumping.toml`` at coarse, pumped at 500 times its rate: the two
breakdowns are different peaks, the half step's in doubt; the first crack does
not move.)

The move from ``dt`` to ``dt / 2`` is measured.  The run's own error is an
estimate: if the answer converges at first order in the step (backward Euler
in time, and breaks found at the end of a step), Richardson extrapolation puts
the error of the run at ``dt`` at twice the move, and that of the run at
``dt / 2`` at the move itself.  The two conventions agree: a convergence study
(:mod:`hfcdem.workflows.richardson`) states the error of its *finest* case, and
with two cases its fallback is that same move; here the run asked for is the
coarser one.  A convergence study over three steps measures the order instead::

    hfcdem study --convergence SCENE.toml --parameter solver.time_step \
        --values "0.1 s,0.05 s,0.025 s" -o DIR

It costs a second run of at least the first one's wall time.  Which runs it
fits: those whose steps the scene fixes, so halving them refines the run.  A
seepage run (``injection.wall_joints = "seepage"``) steps at ``time_step``
(its quiet stretches up to ``max_time_step`` where given); an injection run of
the uniform or viscous rung starts at ``time_step`` and grows its steps up to
``max_time_step``, so it needs one given (else the first step alone would be
halved).  A static ``[load]`` scene has no time step.
"""

from __future__ import annotations

import math
from typing import Any

from hfcdem.config.geometry import Scene
from hfcdem.config.tables import SceneError

#: (summary key, words, unit) of the answers compared
ANSWERS = (
    ("breakdown_pressure_MPa", "breakdown", "MPa"),
    ("peak_pressure_MPa", "highest pressure", "MPa"),
    ("first_crack_pressure_MPa", "first crack", "MPa"),
    ("first_crack_time_s", "first-crack time", "s"),
    ("fluid_front_m", "fluid front", "m"),  # a crack that only propagates (KGD)
    ("inlet_opening_m", "inlet opening", "m"),
)

#: where the half-step run writes, inside the run's own output folder
HALF_STEP_DIR = "half_step"


def halved_steps(scene: Scene) -> dict[str, str]:
    """Return the overrides that halve ``scene``'s time steps (``SceneError`` where none fits)."""
    phys = scene.physics
    if phys is None or phys.load is not None:
        raise SceneError(
            "--check-time-step",
            "a static [load] scene has no time step; the check is for injection runs",
        )
    solver = phys.solver
    capped = math.isfinite(solver.max_time_step)
    if phys.wall_joints != "seepage" and not capped:
        raise SceneError(
            "--check-time-step",
            "this run's steps grow freely from solver.time_step (no solver.max_time_step), so "
            "halving the first step would not refine the run: give solver.max_time_step, e.g. "
            "--set solver.max_time_step='1 s', or run a convergence study over it "
            "(hfcdem study --convergence SCENE --parameter solver.max_time_step --values ...)",
        )
    halved = {"solver.time_step": f"{solver.time_step / 2.0!r} s"}
    if capped:
        halved["solver.max_time_step"] = f"{solver.max_time_step / 2.0!r} s"
    return halved


def compare_steps(full: dict[str, Any], half: dict[str, Any], dt: float) -> dict[str, Any]:
    """Set the answers of the run at ``dt`` (``full``) beside those at ``dt / 2`` (``half``).

    Per answer both values, the move ``half - full``, the move relative to
    ``half``, and ``first_order_error``: twice the move's size, the run's own
    error if the answer converges at first order in the step (an estimate).
    An answer either run lacks has None for the move.  Each run's breakdown
    note and stop are kept beside it: a move between two breakdowns one of
    which is in doubt is itself in doubt.
    """
    answers: dict[str, Any] = {}
    for key, _, _ in ANSWERS:
        a, b = full.get(key), half.get(key)
        entry: dict[str, Any] = {"full_step": a, "half_step": b, "change": None}
        if a is not None and b is not None:
            change = float(b) - float(a)
            entry["change"] = change
            entry["relative_change"] = change / abs(b) if b else None
            entry["first_order_error"] = 2.0 * abs(change)
            entry["first_order_relative_error"] = 2.0 * abs(change) / abs(b) if b else None
        answers[key] = entry
    return {
        "kind": full.get("kind"),
        "time_step_s": dt,
        "half_step_s": dt / 2.0,
        "half_step_dir": HALF_STEP_DIR,
        "answers": answers,
        "notes": {
            "full_step": full.get("breakdown_note"),
            "half_step": half.get("breakdown_note"),
        },
        "stopped": {"full_step": full.get("stopped"), "half_step": half.get("stopped")},
        "wall_time_s": {
            "full_step": full.get("wall_time_s"),
            "half_step": half.get("wall_time_s"),
        },
    }


def check_words(check: dict[str, Any]) -> str:
    """Say the check in one line: the breakdown (or front, or highest pressure), the first crack."""
    dt, half = check["time_step_s"], check["half_step_s"]
    answers = check["answers"]
    found = [s for s in ("full_step", "half_step") if answers["breakdown_pressure_MPa"][s]]
    # the breakdown where both runs found one; the front of a crack that only propagates
    # (its highest pressure is its first step's); else the highest pressure
    main = "breakdown_pressure_MPa" if len(found) == 2 else "peak_pressure_MPa"
    if main == "peak_pressure_MPa" and answers["fluid_front_m"]["change"] is not None:
        main = "fluid_front_m"
    cracked = answers["first_crack_pressure_MPa"]
    second = "first_crack_pressure_MPa" if cracked["full_step"] and cracked["half_step"] else None
    moved, relative = [], []
    for key, words, unit in ANSWERS:
        entry = answers[key]
        if key not in (main, second) or entry["change"] is None:
            continue
        if key == "breakdown_pressure_MPa" and check.get("kind") == "seepage_ramp":
            words = "first break"  # a ramp ends at it and calls it its breakdown
        said = f"{words} {entry['full_step']:.2f} -> {entry['half_step']:.2f} {unit}"
        if entry["relative_change"] is not None:
            rel = entry["relative_change"]
            said += f" ({rel:+.2%})" if abs(rel) >= 5e-5 else " (0.00%)"
            relative.append(abs(entry["relative_change"]))
        moved.append(said)
    if not moved:
        return f"time step: no answer at both {dt:.3g} s and {half:.3g} s; see time_step_check.json"
    line = f"time step: halving it ({dt:.3g} -> {half:.3g} s) moves the " + ", the ".join(moved)
    if relative:
        line += (
            "; at first order in the step, this run's own error is about twice the larger "
            f"move ({2.0 * max(relative):.2%})"
        )
    if len(found) == 1:
        step = dt if found == ["full_step"] else half
        line += f"; only the run at {step:.3g} s found a breakdown"
    elif any(check["notes"].values()) and main == "breakdown_pressure_MPa":
        line += "; a breakdown is in doubt (its note: time_step_check.json)"
    return line


__all__ = ["ANSWERS", "HALF_STEP_DIR", "check_words", "compare_steps", "halved_steps"]
