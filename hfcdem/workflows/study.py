"""Parameter studies: one scene, one field swept over values, every case run and tabled.

A study file (TOML) names a scene file, the dotted key to sweep and its values,
and optional fixed overrides::

    name = "kgd_rate"
    scene = "../meshes/scenes/kgd_strip.toml"   # relative to the study file
    resolution = "coarse"                       # optional named mesh resolution

    [sweep]
    parameter = "injection.rate"
    values = ["1e-3 m3/s", "2e-3 m3/s", "4e-3 m3/s"]

    [sweep.with]                                # optional: keys moved with the swept
    "injection.duration" = ["8 s", "4 s", "2 s"]  # one, a value per case

    [set]                                       # optional, applied to every case
    "fluid.viscosity" = "1 mPa.s"

``hfcdem study STUDY.toml -o DIR`` runs the cases into ``DIR/case_K_VALUE``
(``case_1_1-1``, ``case_0_30_deg``) one after another, or ``--groups G`` at
once with the ranks split into G groups.  A case whose directory already holds
its own finished results is skipped; one that holds another scene's run (the
study's settings changed) stops the study before anything runs, unless
``--force``.  Then it
writes ``results.csv`` and ``study.png`` (breakdown or peak pressure and fracture
degree against the swept value).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, Self

from mpi4py import MPI

from hfcdem.config.geometry import Scene
from hfcdem.config.scene import apply_overrides, parse_scene
from hfcdem.config.tables import SceneError
from hfcdem.config.units import UNITS, FieldError, parse_quantity
from hfcdem.io.files import prepare_output_dir


@dataclass(frozen=True)
class SceneSweep:
    """What every study holds: the base scene document, the swept key, its values, the fixed.

    A kind of study says how case ``k``'s scene is made (:meth:`case_scene`) and
    what else it must check before anything runs (:meth:`validated`).
    """

    name: str
    scene_path: Path
    base: Mapping[str, Any]
    parameter: str
    values: tuple[Any, ...]
    fixed: Mapping[str, Any]
    resolution: str | None = None

    def case_scene(self, k: int) -> Scene:
        """Return the validated scene of case ``k``; errors name the case and the key."""
        raise NotImplementedError

    def validated(self) -> Self:
        """Return the study once every case's scene is checked (before any meshing)."""
        if not self.values:
            raise SceneError("sweep.values", "expected a non-empty list")
        for k in range(len(self.values)):
            self.case_scene(k)
        return self

    def with_values(self, values: tuple[Any, ...]) -> Self:
        """Return the study with other swept values (validated)."""
        return dataclasses.replace(self, values=tuple(values)).validated()

    def with_fixed(self, extra: Mapping[str, Any]) -> Self:
        """Return the study with more fields fixed in every case (validated)."""
        return dataclasses.replace(self, fixed={**self.fixed, **extra}).validated()

    def case_error(self, k: int, exc: FieldError) -> SceneError:
        """Return ``exc`` of case ``k``'s scene as an error that names the case first."""
        where = f"case {k} ({self.parameter} = {self.values[k]!r})"
        return SceneError(f"{where}: {exc.path}" if exc.path else where, exc.reason)


@dataclass(frozen=True)
class Study(SceneSweep):
    """A validated parameter study; ``together`` moves more keys with the swept one."""

    together: Mapping[str, tuple[Any, ...]] = dataclasses.field(default_factory=dict)

    def validated(self) -> Self:
        """Return the study once every case's scene is checked; keys moved together must fit."""
        moved = {len(v) for v in self.together.values()}
        if self.values and moved and moved != {len(self.values)}:
            raise SceneError(
                "sweep.values",
                f"{len(self.values)} values, but sweep.with moves "
                f"{', '.join(self.together)} with {max(moved)}",
            )
        return super().validated()

    def case_document(self, k: int) -> dict[str, Any]:
        """Return the scene document of case ``k`` (overrides applied)."""
        doc = copy.deepcopy(dict(self.base))
        changes = {
            **self.fixed,
            self.parameter: self.values[k],
            **{key: values[k] for key, values in self.together.items()},
        }
        apply_overrides(doc, changes, self.resolution)
        # named for the case, not the base scene: pictures and summaries say which case they show
        doc["name"] = f"{self.name}_{case_directory(k, self.values[k])}"
        return doc

    def case_scene(self, k: int) -> Scene:
        """Return the validated scene of case ``k``; errors name the case and the key."""
        try:
            return parse_scene(
                self.case_document(k),
                f"{self.name}_case{k}",
                self.resolution,
                None,
                str(self.scene_path),
            )
        except FieldError as exc:
            raise self.case_error(k, exc) from None


def load_study(path: str | Path, resolution: str | None = None) -> Study:
    """Read and validate a study file; every case's scene is checked before anything runs.

    ``resolution`` replaces the file's mesh resolution.
    """
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise SceneError("", f"cannot read study file {p}: {exc}") from None
    known = {"kind", "name", "scene", "resolution", "sweep", "set"}
    if data.get("kind", "sweep") != "sweep":
        raise SceneError(
            "kind",
            f"{data.get('kind')!r}: load_study reads kind = 'sweep' studies (a 'convergence' "
            "study is read by hfcdem.workflows.convergence.load_convergence)",
        )
    for key in data:
        if key not in known:
            raise SceneError(key, f"unknown key; a study takes: {', '.join(sorted(known))}")
    if "scene" not in data or not isinstance(data["scene"], str):
        raise SceneError("scene", "missing; expected the path of a scene file")
    scene_path = (p.parent / data["scene"]).resolve()
    try:
        base = tomllib.loads(scene_path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise SceneError("scene", f"cannot read {scene_path}: {exc}") from None
    sweep = data.get("sweep")
    if not isinstance(sweep, dict):
        raise SceneError("sweep", "missing; expected a table with parameter and values")
    parameter = sweep.get("parameter")
    values = sweep.get("values")
    if not isinstance(parameter, str) or not parameter:
        raise SceneError("sweep.parameter", "expected a dotted scene key such as 'injection.rate'")
    if not isinstance(values, list) or not values:
        raise SceneError("sweep.values", "expected a non-empty list")
    fixed = data.get("set", {})
    if not isinstance(fixed, dict):
        raise SceneError("set", "expected a table of dotted keys")
    for key in sweep:
        if key not in ("parameter", "values", "with"):
            raise SceneError(f"sweep.{key}", "unknown key; a sweep takes: parameter, values, with")
    together = sweep.get("with", {})
    if not isinstance(together, dict):
        raise SceneError("sweep.with", "expected a table of dotted keys, each with a list")
    for key, moved in together.items():
        if not isinstance(moved, list) or len(moved) != len(values):
            raise SceneError(
                f"sweep.with.{key}",
                f"expected a list of {len(values)} values, one per swept value",
            )
    study = Study(
        name=str(data.get("name", p.stem)),
        scene_path=scene_path,
        base=base,
        parameter=parameter,
        values=tuple(values),
        fixed=fixed,
        resolution=resolution or data.get("resolution"),
        together={key: tuple(v) for key, v in together.items()},
    )
    return study.validated()  # bad input stops here, before any meshing


def breakdown_text(summary: Mapping[str, Any]) -> str:
    """Describe a run's breakdown: "64.50 MPa", or the peak when none was found."""
    bd = summary.get("breakdown_pressure_MPa")
    if bd:
        return f"{bd:.2f} MPa"
    peak = summary.get("peak_pressure_MPa")
    return "no drop confirmed" + (f" (peak {peak:.2f} MPa)" if peak else "")


def pick_metric(rows: list[dict[str, Any]]) -> tuple[dict[Any, float], str]:
    """Return the pressure to rank cases by, and its name.

    The paper calls the peak injection pressure the breakdown pressure; a run
    that cracked but whose pressure then only levels off (no confirmed drop)
    still has that peak.  So every case that cracked is ranked by its peak
    pressure; when one did not crack, by nothing (an empty dict).
    """
    cracked = {r["value"]: r.get("peak_pressure_MPa") for r in rows if r.get("first_crack_time_s")}
    peaks = {k: float(v) for k, v in cracked.items() if v is not None}
    if len(peaks) != len(rows):
        return {}, "peak pressure"
    return peaks, "peak pressure"


def numeric(value: Any) -> float | None:
    """Return the SI number of a swept value (a number, or a quantity with its unit)."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    if isinstance(value, str):
        for dimension in UNITS:
            try:
                return parse_quantity(value, dimension)
            except FieldError:
                continue
    return None


class CaseSource(Protocol):
    """What :func:`run_cases` needs of a study: a name, the swept key, values, scenes."""

    @property
    def name(self) -> str:
        """The study's name."""
        ...

    @property
    def parameter(self) -> str:
        """The swept key."""
        ...

    @property
    def values(self) -> tuple[Any, ...]:
        """The swept values, one case each."""
        ...

    def case_scene(self, k: int) -> Scene:
        """Return the validated scene of case ``k``."""
        ...


def run_study(
    study: Study,
    output: str | Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    groups: int = 1,
    force: bool = False,
    say: Callable[[str], None] | None = None,
    keep_stopped: bool = False,
    overwrite: bool = False,
) -> list[dict[str, Any]]:
    """Run every case not already done; return one result row per case.

    Raises :class:`~hfcdem.workflows.run.OutputInUse` before anything runs when
    a case's directory holds a run (finished or not) of another scene, such as
    the same study with other settings, unless ``force`` (run every case again)
    or ``overwrite`` (run over such cases, skip those done).  ``keep_stopped``:
    a case that stopped (its solver gave up) counts as done.  ``results.csv``
    and ``study.png`` list the study's values only, whatever other case
    directories ``output`` holds.
    """
    say = say or (lambda msg: None)
    if not (force or overwrite):
        claim_cases(study, Path(output), comm)
    out = prepare_output_dir(output, comm)
    run_cases(study, out, comm, groups=groups, force=force, keep_stopped=keep_stopped)
    rows = case_rows(study, out)
    if comm.rank == 0:
        _write_results(out, study, rows)
    comm.barrier()
    say(f"{study.name}: {len(rows)} cases; results in {out}/results.csv and study.png")
    return rows


def claim_cases(study: CaseSource, out: Path, comm: MPI.Comm) -> None:
    """Refuse to run over another scene's run in a case directory (collective).

    Rank 0 decides and tells the others, so that every rank raises or none does.
    """
    from hfcdem.workflows.run import OutputInUse, scene_fingerprint

    problem = None
    if comm.rank == 0:
        for k, value in enumerate(study.values):
            case_dir = out / case_directory(k, value)
            previous = _run_record(case_dir)
            if previous is None:
                continue
            if previous.get("fingerprint") != scene_fingerprint(study.case_scene(k)):
                problem = (
                    f"{case_dir} holds a run of {previous.get('scene', '?')!r} with other "
                    "settings (or of another scene); use --force to overwrite, or another -o"
                )
                break
    problem = comm.bcast(problem, root=0)
    if problem:
        raise OutputInUse(problem)


def _run_record(case_dir: Path) -> dict[str, Any] | None:
    """Return ``case_dir``'s run.json (written as a run starts); None when there is none.

    One that cannot be read is an empty dict: another run's, as far as anyone can tell.
    """
    path = case_dir / "run.json"
    if not path.exists():
        return None
    try:
        record = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return {}
    return record if isinstance(record, dict) else {}


def run_cases(
    study: CaseSource,
    out: Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    groups: int = 1,
    force: bool = False,
    order: Sequence[int] | None = None,
    keep_stopped: bool = False,
) -> None:
    """Run the cases of ``study`` into ``out/case_K_VALUE``, skipping those done (collective).

    ``order``: the case indices in the order to run them (default: as listed).
    ``groups``: run that many cases at once, the ranks split between them.
    ``keep_stopped``: a case that stopped counts as done (else it runs again).
    """
    from hfcdem.workflows.memory import release_memory
    from hfcdem.workflows.run import run_scene, scene_fingerprint

    if not 1 <= groups <= comm.size:
        raise ValueError(f"groups must be in [1, {comm.size}] (the rank count), got {groups}")
    color = comm.rank % groups
    sub = comm.Split(color, comm.rank)
    try:
        for slot, k in enumerate(range(len(study.values)) if order is None else order):
            if slot % groups != color:
                continue
            scene = study.case_scene(k)
            case_dir = out / case_directory(k, study.values[k])
            fingerprint = scene_fingerprint(scene)
            if case_done(case_dir, fingerprint, keep_stopped) and not force:
                if sub.rank == 0:
                    print(f"case {k}: done before, skipped", flush=True)
                continue
            # a case stopped from outside goes on from its checkpoint
            resume = not force and sub.bcast(
                case_stopped(case_dir, fingerprint) if sub.rank == 0 else None, root=0
            )
            label = f"case {k}: {study.parameter} = {study.values[k]}"
            if sub.rank == 0:
                print(label, flush=True)

            def progress(msg: str, lab: str = label) -> None:
                if sub.rank == 0:
                    print(f"  [{lab}] {msg}", flush=True)

            run_scene(scene, case_dir, sub, force=True, say=progress, resume=bool(resume))
            release_memory()  # else the next, larger case grows past this one's freed heap
    finally:
        sub.Free()
    comm.barrier()


def case_rows(study: CaseSource, out: Path) -> list[dict[str, Any]]:
    """Return one row per case: its index, value, numeric value and ``summary.json``."""
    rows = []
    for k, value in enumerate(study.values):
        summary_path = out / case_directory(k, value) / "summary.json"
        summary = json.loads(summary_path.read_text()) if summary_path.exists() else {}
        rows.append({"case": k, "value": value, "x": numeric(value), **summary})
    return rows


def case_directory(k: int, value: Any) -> str:
    """Return the folder name of case ``k``: its index and its value, path-safe."""
    slug = re.sub(r"[^A-Za-z0-9.+-]+", "_", str(value)).strip("_.")[:40]
    return f"case_{k}_{slug}" if slug else f"case_{k}"


def case_done(case_dir: Path, fingerprint: str, keep_stopped: bool = False) -> bool:
    """Whether ``case_dir`` holds a finished run of the scene with ``fingerprint``.

    ``keep_stopped``: a run its solver stopped counts as finished too.
    """
    try:
        run = json.loads((case_dir / "run.json").read_text())
        summary = json.loads((case_dir / "summary.json").read_text())
    except (OSError, json.JSONDecodeError):
        return False
    return (
        run.get("fingerprint") == fingerprint
        and summary.get("fingerprint", fingerprint) == fingerprint
        and (keep_stopped or summary.get("stopped") is None)
    )


def case_stopped(case_dir: Path, fingerprint: str) -> bool:
    """Whether ``case_dir`` holds a run of the scene with ``fingerprint`` stopped from outside.

    A run with ``checkpoint.json`` and no ``summary.json`` (Ctrl-C, a time
    limit): ``hfcdem run --resume`` goes on from it.
    """
    try:
        run = json.loads((case_dir / "run.json").read_text())
    except (OSError, json.JSONDecodeError):
        return False
    return (
        run.get("fingerprint") == fingerprint
        and (case_dir / "checkpoint.json").is_file()
        and not (case_dir / "summary.json").exists()
    )


STATIC_COLUMNS = [
    "case",
    "x",
    "max_crack_opening_m",
    "sneddon_centre_relative_error",
    "overstressed_interfaces",
    "max_spring_tension_MPa",
    "wall_time_s",
]


def _write_results(out: Path, study: Study, rows: list[dict[str, Any]]) -> None:
    if rows and all(r.get("kind") == "static" for r in rows):
        _write_static_results(out, study, rows)
        return
    cols = [
        "case",
        "x",
        "breakdown_pressure_MPa",
        "breakdown_drop_MPa",
        "peak_pressure_MPa",
        "first_crack_pressure_MPa",
        "first_crack_time_s",
        "fracture_degree",
        "tensile_failures",
        "shear_failures",
        "wall_time_s",
    ]
    ramps = bool(rows) and all(r.get("kind") == "seepage_ramp" for r in rows)
    if ramps:  # the first break of a pressure ramp: how far the fluid got
        cols += ["joints_holding_pressure", "wall_joint_pressure_ratio"]

    _write_table(out / "results.csv", rows, cols)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    categorical = any(r["x"] is None for r in rows)  # e.g. profile names
    xs = [r["case"] if categorical else r["x"] for r in rows]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    bd = [_num(r.get("breakdown_pressure_MPa")) for r in rows]
    pk = [_num(r.get("peak_pressure_MPa")) for r in rows]
    a1.plot(xs, pk, "s--", label="peak pressure (highest in the run)")
    a1.plot(xs, bd, "o-", label="breakdown pressure")
    fc = [_num(r.get("first_crack_pressure_MPa")) for r in rows]
    a1.plot(xs, fc, "^:", label="first crack")
    a1.set_ylabel("pressure (MPa)")
    if ramps:
        share = [_num(r.get("joints_holding_pressure")) * 100 for r in rows]
        wall = [_num(r.get("wall_joint_pressure_ratio")) * 100 for r in rows]
        a2.plot(xs, share, "o-", label="joints holding pressure")
        a2.plot(xs, wall, "s--", label="wall joints' pressure / cavity's")
        a2.set_ylabel("at the first break (%)")
        a2.legend()
    else:
        a2.plot(xs, [_num(r.get("fracture_degree")) for r in rows], "o-", label="fracture degree")
        a2.set_ylabel("fracture degree")
        counts = [(_num(r.get("tensile_failures")), _num(r.get("shear_failures"))) for r in rows]
        if any(t + s > 0 for t, s in counts):  # NaN sums compare False
            a3 = a2.twinx()
            shear = [100 * s / (t + s) if t + s > 0 else float("nan") for t, s in counts]
            a3.plot(xs, shear, "^:", color="C1", label="shear share of the failures")
            a3.set_ylabel("failures in shear (%)")
            lines = a2.get_lines() + a3.get_lines()
            a2.legend(lines, [str(ln.get_label()) for ln in lines])
    _label_axes((a1, a2), study, rows, xs, categorical)
    a1.legend()
    fig.suptitle(study.name)
    fig.tight_layout()
    fig.savefig(out / "study.png", dpi=110)
    plt.close(fig)


def _num(v: Any) -> float:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else float("nan")


def _write_table(path: Path, rows: list[dict[str, Any]], cols: list[str]) -> None:
    from hfcdem.io.files import write_atomic

    lines = [",".join(["value", *cols])]
    for r in rows:
        label = str(r["value"]).replace(",", ";")
        lines.append(",".join([label] + [f"{_num(r.get(c)):.10g}" for c in cols]))
    write_atomic(path, "\n".join(lines) + "\n")


def _write_static_results(out: Path, study: Study, rows: list[dict[str, Any]]) -> None:
    """Table and plot the crack opening (and the error against Sneddon) of static cases."""
    for r in rows:
        r["sneddon_centre_relative_error"] = r.get("sneddon", {}).get("centre_relative_error")
    _write_table(out / "results.csv", rows, STATIC_COLUMNS)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    categorical = any(r["x"] is None for r in rows)
    xs = [r["case"] if categorical else r["x"] for r in rows]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    a1.plot(xs, [_num(r.get("max_crack_opening_m")) * 1e6 for r in rows], "o-")
    a1.set_ylabel("largest crack opening (um)")
    errors = [_num(r.get("sneddon_centre_relative_error")) * 100 for r in rows]
    a2.plot(xs, errors, "o-")
    a2.axhline(0.0, color="k", lw=0.8)
    a2.set_ylabel("centre u_y against Sneddon (%)")
    _label_axes((a1, a2), study, rows, xs, categorical)
    fig.suptitle(study.name)
    fig.tight_layout()
    fig.savefig(out / "study.png", dpi=110)
    plt.close(fig)


def _label_axes(axes: Any, study: Study, rows: list[dict[str, Any]], xs: list, categorical: bool):
    """Name the swept value on the x axes (the values themselves when they are names)."""
    for ax in axes:
        ax.set_xlabel(study.parameter + ("" if categorical else " (SI)"))
        if categorical:
            ax.set_xticks(xs, [str(r["value"]) for r in rows])
        elif len(xs) > 1 and min(xs) > 0.0 and max(xs) >= 100.0 * min(xs):
            ax.set_xscale("log")  # values over decades (rates, viscosities)
        ax.grid(alpha=0.3)


__all__ = [
    "STATIC_COLUMNS",
    "CaseSource",
    "SceneSweep",
    "Study",
    "breakdown_text",
    "case_directory",
    "case_done",
    "case_rows",
    "claim_cases",
    "load_study",
    "numeric",
    "pick_metric",
    "run_cases",
    "run_study",
]
