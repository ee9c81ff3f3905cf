"""Run the report's cases, resumably, with a progress line and the time left.

Each case runs into ``DIR/cases/NAME`` through the workflow its file asks for
(:func:`hfcdem.workflows.run.run_scene`, :func:`~hfcdem.workflows.study.run_study`
or :func:`~hfcdem.workflows.convergence.run_convergence`); those skip what is
already done there, so an interrupted report continues where it stopped.  A
case that fails (bad input, a solver stop) is recorded with its message and
the report goes on.  ``case.json`` keeps each case's rows, status and wall time.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from mpi4py import MPI

from hfcdem.config.units import FieldError
from hfcdem.io.files import prepare_output_dir, write_json
from hfcdem.mesh.tagged import MeshingError
from hfcdem.reproduce.cases import FIDELITIES, Case, Tier, case_resolutions, select_cases
from hfcdem.reproduce.compare import CaseResult, Comparison
from hfcdem.reproduce.saturation import TO_SEEPAGE
from hfcdem.reproduce.watchdog import Watchdog
from hfcdem.solvers import SimulationStopped, SolverError

ROOT = Path(__file__).resolve().parents[2]  # the checkout: scene and study files

# what a case may fail with and the report survive (everything else is a bug)
CASE_ERRORS = (FieldError, SimulationStopped, SolverError, MeshingError, OSError)


@dataclass(frozen=True)
class CaseRecord:
    """One case as the report shows it: rows, status, resolution, cost."""

    name: str
    paper: str
    title: str
    # "ok", "failed", "stopped", "limit" (the model's validity limit), "not modelled",
    # "not run" (left out by --only and not done in the report's directory)
    status: str
    comparisons: tuple[Comparison, ...] = ()
    message: str = ""
    resolution: str = ""
    discretisation: str = ""
    note: str = ""
    wall_time_s: float = 0.0
    figures: tuple[str, ...] = ()  # paths relative to the report's directory
    skipped: bool = False
    commit: str = ""  # the code of the last run into the case ("": not known)


@dataclass
class _Clock:
    """Time left: the remaining estimates scaled by how the done cases compared."""

    spent: float = 0.0
    estimated: float = 0.0
    left: list[float] = field(default_factory=list)

    def remaining(self) -> float:
        # a few seconds of short cases say little about the long ones: scale only once
        # a minute of estimates has run, and by no more than 3x either way
        scale = 1.0
        if self.estimated >= 60.0 and self.spent > 0.0:
            scale = min(max(self.spent / self.estimated, 1.0 / 3.0), 3.0)
        return scale * sum(self.left)


def run_reproduction(
    output: str | Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    tier: str = "quick",
    fidelity: str = "scene",
    resolution: str | None = None,
    only: Sequence[str] | None = None,
    force: bool = False,
    say: Callable[[str], None] | None = None,
    watchdog_s: float = 0.0,
) -> list[CaseRecord]:
    """Run the cases of ``tier`` (or those named in ``only``) into ``output``; return them.

    The report always covers the whole tier: with ``only``, the tier's other
    cases are read back from ``output`` where they are done (nothing of them
    runs, and their ``case.json`` is left as it is), and listed as not run
    where they are not, so a partial rerun never writes a report of a few
    cases over the whole one.  Only the records of the cases run (or found
    done) for this call are returned.

    ``fidelity``: ``scene`` (as each scene file says), ``uniform`` or ``viscous``
    (``solver.fidelity`` of every injection scene) or ``seepage`` (the joints
    fill in time: ``injection.wall_joints``).  ``resolution``: a named mesh
    resolution for every case instead of the tier's; a name none of the cases
    to run has raises ValueError before anything is written.  ``force``: run
    again what is done.  ``watchdog_s``: end the process when no progress line
    comes for this long (:class:`~hfcdem.reproduce.watchdog.Watchdog`; 0:
    never).  Collective.
    """
    watchdog = Watchdog(watchdog_s)
    printer = say or (lambda msg: None)

    def heard(msg: str) -> None:
        watchdog.beat()
        printer(msg)

    with watchdog:
        return _run_all(output, comm, tier, fidelity, resolution, only, force, heard, watchdog)


def _run_all(
    output: str | Path,
    comm: MPI.Comm,
    tier: str,
    fidelity: str,
    resolution: str | None,
    only: Sequence[str] | None,
    force: bool,
    say: Callable[[str], None],
    watchdog: Watchdog,
) -> list[CaseRecord]:
    if fidelity not in FIDELITIES:
        raise ValueError(f"--fidelity: expected one of {', '.join(FIDELITIES)}, got {fidelity!r}")
    cases = select_cases(tier, only)
    if not cases:
        raise ValueError(f"no case of tier {tier!r} among {', '.join(only or [])}")
    if resolution is not None:
        _check_resolution(cases, resolution)
    out = prepare_output_dir(output, comm)
    commit = run_tag(comm)["commit"]  # the code this process runs, not HEAD at the end
    clock = _Clock(left=[_estimate(c, c.tiers[tier], out, comm.size, resolution) for c in cases])
    records = []
    others = [c for c in select_cases(tier) if c not in cases] if only else []
    for case in others:
        where = out / "cases" / case.name
        watchdog.beat(f"case {case.name} ({where}): reading it back")
        record = _run_case(
            case, case.tiers[tier], where, comm, fidelity, resolution, False, _quiet, read_only=True
        )
        # not named in --only: its case.json stays as its own run left it
        records.append(_finish(record, where, out, 0.0, comm, commit, write=False))
    if others:
        back = sum(1 for r in records if r.skipped)
        missing = sum(1 for r in records if r.status == "not modelled")
        say(
            f"--only: {back} of the tier's {len(others)} other cases read back from {out}; "
            f"{len(others) - back - missing} not run yet"
            + (f", {missing} not modelled" if missing else "")
            + " (listed as such in the report)"
        )
    for i, case in enumerate(cases, start=1):
        est = clock.left.pop(0)
        where = out / "cases" / case.name
        watchdog.beat(f"case {case.name} ({where})")
        say(f"[{i}/{len(cases)}] {case.name}: {case.title} ({_time_left(est, clock)})")
        t0 = time.perf_counter()
        record = _run_case(case, case.tiers[tier], where, comm, fidelity, resolution, force, say)
        spent = time.perf_counter() - t0 + _earlier_sessions(where, record, comm)
        if record.status in ("ok", "limit") and not record.skipped and math.isfinite(est):
            clock.spent += spent
            clock.estimated += est
        record = _finish(record, where, out, spent, comm, commit)
        records.append(record)
        met = sum(1 for c in record.comparisons if c.met)
        judged = sum(1 for c in record.comparisons if c.met is not None)
        if record.status == "not modelled":
            say(f"[{i}/{len(cases)}] {case.name}: not modelled, listed in the report")
            continue
        state = "done before" if record.skipped else f"{record.status} in {spent:.0f} s"
        say(
            f"[{i}/{len(cases)}] {case.name}: {state}; {judged} rows judged, {met} met"
            + (f" ({record.message})" if record.message else "")
        )
    meta = run_tag(comm) | {"commit": commit, "tier": tier, "fidelity": fidelity}
    meta["resolution"] = resolution
    meta["only"] = [c.name for c in cases] if only else None
    order = {c.name: k for k, c in enumerate(select_cases(tier))}
    records.sort(key=lambda r: order[r.name])  # the registry's order, as without --only
    if comm.rank == 0:
        from hfcdem.reproduce.report import write_report

        write_report(out, records, meta)
    comm.barrier()
    say(f"report: {out / 'report.html'} (and report.md, results.csv, figures/)")
    ran = {c.name for c in cases}
    return [r for r in records if r.name in ran]


def _check_resolution(cases: Sequence[Case], resolution: str) -> None:
    """Refuse a resolution none of ``cases`` names, before anything runs or is written.

    A name some of them have is let through: those without it fail alone, in the report.
    """
    known: set[str] = set()
    for case in cases:
        names = case_resolutions(case, ROOT)
        if names is None:  # an unreadable file: its run will say so
            return
        known |= names
    if resolution not in known:
        raise ValueError(
            f"--resolution: no case to run ({', '.join(c.name for c in cases)}) has a mesh "
            f"resolution named {resolution!r}; theirs: {', '.join(sorted(known))}"
        )


def _minutes(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.0f} min"


def _time_left(est: float, clock: _Clock) -> str:
    """Say a case's estimate and the whole run's (nan: none known at this resolution)."""
    rest = clock.remaining()
    if math.isfinite(est):
        whole = (
            f"about {_minutes(rest + est)} left in all"
            if math.isfinite(rest)
            else "no estimate for the others at this resolution"
        )
        return f"about {_minutes(est)}; {whole}"
    said = "no estimate at this resolution: the tier's is for its own mesh"
    if clock.left and math.isfinite(rest):
        said += f"; about {_minutes(rest)} for the others"
    return said


def _estimate(
    case: Case, tier: Tier, out: Path, ranks: int, resolution: str | None = None
) -> float:
    """Return the case's last wall time here, else its tier's one-rank estimate.

    nan when ``resolution`` (a ``--resolution``) is not the tier's and the case
    has not run here: a finer mesh costs hours where the tier's takes minutes.
    """
    try:
        data = json.loads((out / "cases" / case.name / "case.json").read_text())
        return float(data["wall_time_s"])
    except (OSError, ValueError, KeyError):
        if case.kind == "missing":
            return 0.0
        if resolution is not None and resolution != (tier.resolution or "default"):
            return math.nan
        return tier.estimate_s / max(1.0, 0.7 * ranks)


def _overrides(fidelity: str) -> dict[str, Any]:
    if fidelity == "scene":
        return {}
    if fidelity == "seepage":
        return dict(TO_SEEPAGE)
    return {"solver.fidelity": fidelity}


def _run_case(
    case: Case,
    tier: Tier,
    where: Path,
    comm: MPI.Comm,
    fidelity: str,
    resolution: str | None,
    force: bool,
    say: Callable[[str], None],
    read_only: bool = False,
) -> CaseRecord:
    """Run one case and compare it (collective); failures become the record's status.

    ``read_only``: read the case back only if it is done, else record it "not run".
    """
    base = CaseRecord(
        case.name,
        case.paper,
        case.title,
        "ok",
        discretisation=case.discretisation,
        note=case.note,
    )
    if case.kind == "missing" or case.source is None or case.compare is None:
        return _replace(base, status="not modelled")
    res = resolution or tier.resolution

    def progress(msg: str) -> None:
        say(f"    {msg}")

    try:
        result, text, skipped = _execute(
            case, tier, where, comm, fidelity, res, force, progress, read_only
        )
    except _NotDone:
        return _replace(base, status="not run", message=_NOT_RUN)
    except CASE_ERRORS as exc:
        if read_only:  # not asked for: it is not done in this form, not failed
            return _replace(base, status="not run", message=_NOT_RUN)
        return _replace(base, status="failed", message=f"{type(exc).__name__}: {exc}")
    compared: Any = None
    if comm.rank == 0:
        try:
            compared = tuple(case.compare(result))
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            compared = f"the comparison failed: {type(exc).__name__}: {exc}"
    compared = comm.bcast(compared, root=0)
    if isinstance(compared, str):
        return _replace(base, status="failed", message=compared, resolution=text)
    status, message = case_status(result)
    return _replace(
        base,
        status=status,
        message=message,
        comparisons=compared,
        resolution=text,
        figures=tuple(str(where / f) for f in case.figures),
        skipped=skipped,
    )


_NOT_RUN = "not run yet: name it in --only"


def _replace(record: CaseRecord, **changes: Any) -> CaseRecord:
    return dataclasses.replace(record, **changes)


def case_status(result: CaseResult) -> tuple[str, str]:
    """Return the status of a case that ran, and why its runs stopped.

    ``"ok"``: no run stopped; ``"limit"``: every stop was the model's validity
    limit (``summary.json``'s ``validity_limit``: the answers before it stand);
    ``"stopped"``: a run stopped otherwise (e.g. a solver gave up).
    """
    if result.summary:
        stopped = result.summary.get("stopped")
        stops = [(str(stopped), bool(result.summary.get("validity_limit")))] if stopped else []
    else:
        stops = [
            (f"{r.get('value')}: {r['stopped']}", bool(r.get("validity_limit")))
            for r in result.rows
            if r.get("stopped")
        ]
    status = "ok" if not stops else "limit" if all(limit for _, limit in stops) else "stopped"
    return status, "; ".join(message for message, _ in stops)


def _execute(
    case: Case,
    tier: Tier,
    where: Path,
    comm: MPI.Comm,
    fidelity: str,
    resolution: str | None,
    force: bool,
    say: Callable[[str], None],
    read_only: bool = False,
) -> tuple[CaseResult, str, bool]:
    """Run the case's workflow (it skips what is done); return its results and resolution.

    ``read_only``: raise :class:`_NotDone` rather than run anything.
    """
    from hfcdem.config.scene import load_scene
    from hfcdem.workflows.convergence import characteristic_size, load_convergence
    from hfcdem.workflows.convergence import run_convergence as converge
    from hfcdem.workflows.memory import release_memory
    from hfcdem.workflows.run import run_scene, scene_fingerprint
    from hfcdem.workflows.study import (
        case_done,
        case_rows,
        case_stopped,
        load_study,
        run_study,
    )

    assert case.source is not None
    path = ROOT / case.source
    if case.kind == "scene":
        scene = load_scene(path, resolution, overrides=dict(tier.fixed))
        if scene.physics.injection is not None and fidelity != "scene":
            scene = load_scene(path, resolution, overrides={**tier.fixed, **_overrides(fidelity)})
        skipped = case_done(where, scene_fingerprint(scene), keep_stopped=True) and not force
        _check_done(skipped, read_only)
        if skipped:
            summary = json.loads((where / "summary.json").read_text())
        else:
            # a case stopped from outside goes on from its checkpoint (read on rank 0)
            fingerprint = scene_fingerprint(scene)
            stopped = comm.bcast(
                case_stopped(where, fingerprint) if comm.rank == 0 else None, root=0
            )
            summary = run_scene(
                scene, where, comm, force=True, say=say, resume=bool(stopped and not force)
            )
            release_memory()
        text = _size_text(characteristic_size(scene), resolution, summary.get("cells"))
        return CaseResult(where, (scene,), summary=summary), text, skipped
    if case.kind == "study":
        study = load_study(path, resolution)
        if tier.values:
            study = study.with_values(tier.values)
        study = study.with_fixed(dict(tier.fixed))
        if fidelity != "scene" and study.case_scene(0).physics.injection is not None:
            study = study.with_fixed(_overrides(fidelity))
        scenes = tuple(study.case_scene(k) for k in range(len(study.values)))
        skipped = not force and _all_done(study, scenes, where, keep_stopped=True)
        _check_done(skipped, read_only)
        if read_only:  # done: its rows as they are, nothing of it rewritten
            rows = case_rows(study, where)
        else:
            # overwrite: the report owns DIR/cases/NAME, and a case whose settings (or the
            # code's fingerprint of them) changed runs again there, as it always has
            rows = run_study(
                study, where, comm, force=force, say=say, keep_stopped=True, overwrite=True
            )
        sizes = [characteristic_size(sc) for sc in scenes]
        text = _size_text(sizes[0], study.resolution, rows[0].get("cells"))
        if len(set(sizes)) > 1:  # a mesh series: its range
            cells = [r.get("cells") for r in rows]
            span = f", {cells[0]:,} -> {cells[-1]:,} cells" if None not in cells else ""
            text = f"h = {sizes[0] * 1e3:.4g} -> {sizes[-1] * 1e3:.4g} mm{span}"
        return CaseResult(where, scenes, rows=tuple(rows)), text, skipped
    conv = load_convergence(path, resolution)
    if tier.values:
        conv = conv.with_values(tier.values)
    if tier.fixed:
        conv = conv.with_fixed(dict(tier.fixed))
    scenes = tuple(conv.case_scene(k) for k in range(len(conv.values)))
    skipped = not force and _all_done(conv, scenes, where, keep_stopped=False)
    _check_done(skipped, read_only)
    kept = skipped and (where / "convergence.csv").exists()  # read back: its tables as they are
    result = converge(conv, where, comm, force=force, say=say, overwrite=True, write=not kept)
    sizes = sorted(characteristic_size(s) * 1e3 for s in scenes)
    text = f"h = {sizes[-1]:.4g} -> {sizes[0]:.4g} mm ({len(sizes)} meshes)"
    estimates = {k: asdict(e) for k, e in result.estimates.items()}
    return CaseResult(where, scenes, rows=result.rows, estimates=estimates), text, skipped


def _quiet(msg: str) -> None:
    """Say nothing: the workflows' lines while a done case is read back."""


class _NotDone(Exception):
    """A case left out by --only has not run in the report's directory."""


def _check_done(done: bool, read_only: bool) -> None:
    if read_only and not done:
        raise _NotDone


def _all_done(study: Any, scenes: Sequence[Any], where: Path, keep_stopped: bool) -> bool:
    """Whether every case of a study already finished in ``where`` (so nothing runs)."""
    from hfcdem.workflows.run import scene_fingerprint
    from hfcdem.workflows.study import case_directory, case_done

    return all(
        case_done(where / case_directory(k, v), scene_fingerprint(s), keep_stopped)
        for (k, v), s in zip(enumerate(study.values), scenes, strict=True)
    )


def _size_text(h: float, resolution: str | None, cells: Any) -> str:
    cells_text = f", {int(cells):,} cells" if isinstance(cells, int | float) else ""
    return f"{resolution or 'default'} (h = {h * 1e3:.4g} mm{cells_text})"


def _finish(
    record: CaseRecord,
    where: Path,
    out: Path,
    spent: float,
    comm: MPI.Comm,
    commit: str,
    write: bool = True,
) -> CaseRecord:
    """Keep the first run's wall time and commit when the case was done before; write case.json.

    ``write``: False for a case only read back (left out by --only): its file is left alone.
    """
    path = where / "case.json"
    if record.status == "not run":
        return record
    if record.skipped or record.status == "not modelled":
        old = comm.bcast(_read(path) if comm.rank == 0 else None, root=0)
        spent = float(old.get("wall_time_s", 0.0)) if old else 0.0
        commit = str(old.get("commit", "")) if old and record.skipped else ""
    shown = [str(Path(f).relative_to(out)) for f in record.figures if Path(f).exists()]
    figures = tuple(comm.bcast(shown if comm.rank == 0 else None, root=0))
    record = _replace(record, wall_time_s=spent, figures=figures, commit=commit)
    if write and record.status != "not modelled":
        prepare_output_dir(where, comm)
        write_json(path, _as_json(record), comm)
    return record


def _earlier_sessions(where: Path, record: CaseRecord, comm: MPI.Comm) -> float:
    """Wall time (s) of the sessions before a resumed case's last (0: not resumed)."""
    if record.skipped:
        return 0.0
    summary = comm.bcast(_read(where / "summary.json") if comm.rank == 0 else None, root=0)
    return float((summary or {}).get("earlier_sessions_wall_time_s") or 0.0)


def _read(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _as_json(record: CaseRecord) -> dict[str, Any]:
    data = asdict(record)
    data["comparisons"] = [
        {**asdict(c), "gap": c.gap, "met": c.met, "target": c.target} for c in record.comparisons
    ]
    return data


def _commit(root: Path) -> str | None:
    """Return the checkout's commit (12 hex digits), read from .git: the image has no git."""
    git = root / ".git"
    try:
        if git.is_file():  # a worktree: "gitdir: PATH"
            git = (root / git.read_text().split(":", 1)[1].strip()).resolve()
        head = (git / "HEAD").read_text().strip()
        if not head.startswith("ref:"):
            return head[:12]
        ref = head.split(":", 1)[1].strip()
        common = git / "commondir"
        base = (git / common.read_text().strip()).resolve() if common.exists() else git
        for where in (git, base):
            if (where / ref).exists():
                return (where / ref).read_text().strip()[:12]
        for line in (base / "packed-refs").read_text().splitlines():
            if line.endswith(" " + ref):
                return line.split()[0][:12]
    except (OSError, IndexError):
        return None
    return None


def run_tag(comm: MPI.Comm) -> dict[str, Any]:
    """Return the date, commit, machine and rank count the report is made with."""
    import datetime
    import os
    import platform

    commit = _commit(ROOT) or "unknown"
    memory = ""
    try:
        pages = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        memory = f", {pages / 2**30:.0f} GB"
    except (ValueError, OSError):
        pass
    return {
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit,
        "machine": f"{platform.machine()}, {os.cpu_count()} cores{memory}, "
        f"{platform.system()} {platform.release()}",
        "ranks": comm.size,
    }


__all__ = ["CASE_ERRORS", "CaseRecord", "CaseResult", "case_status", "run_reproduction", "run_tag"]
