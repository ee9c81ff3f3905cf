r"""Convergence studies: how much of an answer is the mesh (or the spring factor, the time step).

One scene runs at several resolutions; each case's answers (breakdown, peak and
first-crack pressure, first-crack time and place, fracture degree; for a static
scene the crack opening) are tabled with the mesh (cells, the element size h at
the perforation), the wall time and the peak memory, and the discretisation
error of each answer is estimated by Richardson extrapolation from the three
finest cases (:mod:`hfcdem.workflows.richardson`).

A study file says ``kind = "convergence"``; otherwise it reads like a
parameter study (:mod:`hfcdem.workflows.study`)::

    kind = "convergence"
    name = "no2_convergence"
    scene = "../meshes/scenes/perforation_no2.toml"   # relative to the study file
    resolution = "coarse"         # the mesh of every case, unless the mesh is swept

    [sweep]
    parameter = "resolution"      # the scene's named resolutions ("default": none)
    values = ["coarse", "default", "fine"]

    [set]                         # applied to every case; may add resolutions
    "injection.duration" = "100 s"
    "geometry.mesh.resolutions.fine" = { size = "3 mm", size_far = "220 mm" }

The swept parameter and the measure the error is extrapolated in (to 0):

- ``resolution`` or ``geometry.mesh.size`` (element sizes such as "10 mm"):
  h, the element size at the perforation: the mean over the tunnel's section
  diameters of ``size`` capped to ``pi d / circle_elements``; on a borehole
  plate the wall size, on crack and KGD plates ``size``.
- ``rock.spring_factor``: 1 / alpha (the spring softening falls as 1/alpha).
- ``solver.time_step``, ``solver.max_time_step``: the step (s).
- ``solver.linear_solver``, ``solver.solid``: names, no measure: the table gives
  the spread (``solid``: the full-DG reference against the reduced band).
- ``solver.band_threshold``: the threshold itself (0 would free every interface,
  the full mode).

Run it, or give the scene and the values on the command line::

    hfcdem study studies/perforation_no2_convergence.toml -o results/no2_convergence
    hfcdem study --convergence meshes/scenes/sneddon_plate.toml \
        --resolutions coarse,default -o results/sneddon_convergence
    hfcdem study --convergence SCENE.toml --parameter geometry.mesh.size \
        --values "20 mm,10 mm,5 mm" --set 'injection.duration="5 s"' -o DIR

Cases run one at a time, coarse to fine, into ``DIR/case_K_VALUE`` (a case
already finished there is skipped, as in a parameter study).  A case that
stopped early (``summary.json``'s ``stopped``) is tabled with ``completed`` 0
and left out of the estimates.  Written into DIR
(atomically): ``results.csv`` (one row per case), ``convergence.csv`` (per
answer: the finest value, the extrapolated one, the estimated error, the order
and the method, e.g. ``two-finest: not monotone``), ``convergence.json`` (both)
and ``convergence.png`` (each answer against h, log x, with the extrapolated
value and the error band; wall time and peak memory against h).

Peak memory is each rank's resident high-water mark during the case, summed and
the largest one (:mod:`hfcdem.workflows.memory`; where the mark cannot be
restarted, the process's peak so far, so cases run coarse to fine: a coarse
case after a fine one would report the fine one's peak).  Cases are never run
at once (``--groups``): their timings would share the cores.
"""

from __future__ import annotations

import copy
import json
import math
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Self

import numpy as np
from mpi4py import MPI

from hfcdem.config.geometry import PerforatedBlock, Scene
from hfcdem.config.plates import BoreholeSquare, KGDStrip
from hfcdem.config.scene import apply_overrides, parse_scene
from hfcdem.config.scene import set_field as _set
from hfcdem.config.tables import SceneError
from hfcdem.config.units import FieldError
from hfcdem.io.files import atomic_path, prepare_output_dir, write_atomic, write_json
from hfcdem.workflows.richardson import SPREAD, Extrapolation, extrapolate
from hfcdem.workflows.study import SceneSweep, case_rows, claim_cases, numeric, run_cases

# swept key -> (what the error is extrapolated in, axis label, axis unit per SI unit);
# None: names only
MEASURES: dict[str, tuple[str, str, float] | None] = {
    "resolution": ("h", "element size h at the cavity or crack (mm)", 1e3),
    "geometry.mesh.size": ("h", "element size h at the cavity or crack (mm)", 1e3),
    "rock.spring_factor": ("1/alpha", "1 / spring factor alpha", 1.0),
    "solver.time_step": ("dt", "first time step (s)", 1.0),
    "solver.max_time_step": ("dt_max", "largest time step (s)", 1.0),
    "solver.linear_solver": None,
    "solver.solid": None,
    "solver.band_threshold": ("threshold", "band threshold (share of strength)", 1.0),
}

# (summary key, label): the answers whose discretisation error is estimated
INJECTION_ANSWERS = (
    ("breakdown_pressure_MPa", "breakdown pressure (MPa)"),
    ("peak_pressure_MPa", "peak pressure (MPa)"),
    ("first_crack_pressure_MPa", "first-crack pressure (MPa)"),
    ("first_crack_time_s", "first-crack time (s)"),
    ("first_crack_distance_m", "first crack from the wall (m)"),
    ("fracture_degree", "fracture degree"),
)
STATIC_ANSWERS = (
    ("max_crack_opening_m", "largest crack opening (m)"),
    ("sneddon_centre_uy_um", "crack-centre u_y (um)"),
)
COST_COLUMNS = ("wall_time_s", "peak_memory_MB", "peak_memory_rank_max_MB")
ESTIMATE_COLUMNS = ("answer", "finest", "limit", "error", "relative_error", "order", "method")


def characteristic_size(scene: Scene) -> float:
    """Return the element size at the perforation (crack, borehole) of ``scene`` (m)."""
    geom = scene.geometry
    mesh = geom.mesh
    if isinstance(geom, PerforatedBlock):
        sizes = [mesh.wall_size(d) for p in geom.perforations for d in p.profile.diameters]
        return float(np.mean(sizes)) if sizes else float(geom.wellbore_size)
    if isinstance(geom, BoreholeSquare):
        return float(geom.wall_size)
    if isinstance(geom, KGDStrip):
        return float(geom.path_start)  # the facets the fracture runs along
    return float(mesh.size)


@dataclass(frozen=True)
class ConvergenceStudy(SceneSweep):
    """A validated convergence study: the base scene, the swept key and its values."""

    def __post_init__(self) -> None:
        if self.parameter not in MEASURES:
            raise SceneError(
                "sweep.parameter",
                f"{self.parameter!r}: a convergence study sweeps one of {', '.join(MEASURES)}",
            )
        if not self.values:
            raise SceneError("sweep.values", "expected a non-empty list")
        if len(set(map(str, self.values))) != len(self.values):
            raise SceneError("sweep.values", f"values repeat: {list(self.values)}")

    @property
    def measure(self) -> str | None:
        """What the answers are extrapolated in (``"h"``, ``"1/alpha"``, ...), or None."""
        entry = MEASURES[self.parameter]
        return entry[0] if entry else None

    def validated(self) -> Self:
        """Return the study once every case's scene is checked and the measures differ."""
        measures = [self.case_measure(k) for k in range(len(self.values))]  # parses each scene
        known = [m for m in measures if m is not None]
        if len(set(known)) != len(known):
            raise SceneError(
                "sweep.values",
                f"cases share a {self.measure}: "
                f"{dict(zip(self.values, measures, strict=True))} "
                "(e.g. a size below the circle cap pi d / circle_elements)",
            )
        return self

    def case_scene(self, k: int) -> Scene:
        """Return the validated scene of case ``k``; errors name the case and the key."""
        doc = copy.deepcopy(dict(self.base))
        value = self.values[k]
        resolution, size = self.resolution, None
        if self.parameter == "resolution":
            resolution = str(value)
        apply_overrides(doc, self.fixed, resolution)
        try:
            if self.parameter == "geometry.mesh.size":
                size = numeric(value)
                if size is None:
                    raise SceneError("", f"expected a length such as '10 mm', got {value!r}")
            elif self.parameter != "resolution":
                _set(doc, self.parameter, value)
            return parse_scene(doc, self.name, resolution, size, str(self.scene_path))
        except FieldError as exc:
            raise self.case_error(k, exc) from None

    def case_measure(self, k: int) -> float | None:
        """Return the measure of case ``k`` (h in m, 1/alpha, dt in s), or None."""
        scene = self.case_scene(k)
        if self.measure == "h":
            return characteristic_size(scene)
        if self.measure == "1/alpha":
            return 1.0 / scene.physics.interfaces.alpha
        if self.measure is not None:
            return numeric(self.values[k])
        return None


def load_convergence(path: str | Path, resolution: str | None = None) -> ConvergenceStudy:
    """Read and validate a ``kind = "convergence"`` study file (module docstring)."""
    p = Path(path)
    data = _read_toml(p, "study file")
    known = {"kind", "name", "scene", "resolution", "sweep", "set"}
    for key in data:
        if key not in known:
            raise SceneError(key, f"unknown key; a convergence study takes: {sorted(known)}")
    if data.get("kind") != "convergence":
        raise SceneError("kind", f"expected 'convergence', got {data.get('kind')!r}")
    if not isinstance(data.get("scene"), str):
        raise SceneError("scene", "missing; expected the path of a scene file")
    sweep = data.get("sweep")
    if not isinstance(sweep, dict):
        raise SceneError("sweep", "missing; expected a table with parameter and values")
    values = sweep.get("values")
    if not isinstance(values, list):
        raise SceneError("sweep.values", "expected a list")
    fixed = data.get("set", {})
    if not isinstance(fixed, dict):
        raise SceneError("set", "expected a table of dotted keys")
    return convergence_study(
        p.parent / data["scene"],
        str(sweep.get("parameter", "resolution")),
        values,
        fixed,
        resolution or data.get("resolution"),
        str(data.get("name", p.stem)),
    )


def convergence_study(
    scene_path: str | Path,
    parameter: str,
    values: list[Any] | tuple[Any, ...],
    fixed: Mapping[str, Any] | None = None,
    resolution: str | None = None,
    name: str | None = None,
) -> ConvergenceStudy:
    """Return the validated convergence study of the scene file ``scene_path``."""
    path = Path(scene_path).resolve()
    study = ConvergenceStudy(
        name=name or f"{path.stem}_convergence",
        scene_path=path,
        base=_read_toml(path, "scene"),
        parameter=parameter,
        values=tuple(values),
        fixed=dict(fixed or {}),
        resolution=resolution,
    )
    return study.validated()


def study_kind(path: str | Path) -> str:
    """Return the ``kind`` of a study file: ``"sweep"`` (the default) or ``"convergence"``."""
    return str(_read_toml(Path(path), "study file").get("kind", "sweep"))


def _read_toml(path: Path, what: str) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        where = "scene" if what == "scene" else ""
        raise SceneError(where, f"cannot read {what} {path}: {exc}") from None


@dataclass(frozen=True)
class ConvergenceResult:
    """The cases (one row each, coarse to fine as listed) and the estimate of each answer."""

    rows: tuple[dict[str, Any], ...]
    estimates: Mapping[str, Extrapolation]
    answers: tuple[tuple[str, str], ...]


def run_convergence(
    study: ConvergenceStudy,
    output: str | Path,
    comm: MPI.Comm = MPI.COMM_WORLD,
    force: bool = False,
    say: Callable[[str], None] | None = None,
    overwrite: bool = False,
    write: bool = True,
) -> ConvergenceResult:
    """Run the cases not done (coarse to fine), estimate the errors, write the tables and plot.

    As :func:`~hfcdem.workflows.study.run_study`: a case directory holding a run
    with other settings stops it before anything runs
    (:class:`~hfcdem.workflows.run.OutputInUse`), unless ``force`` (run every
    case again) or ``overwrite`` (run over such cases, skip those done).
    ``write=False``: leave the tables and plot as they are (a study read back).
    """
    say = say or (lambda msg: None)
    if not (force or overwrite):
        claim_cases(study, Path(output), comm)
    out = prepare_output_dir(output, comm)
    measures = [study.case_measure(k) for k in range(len(study.values))]
    order = sorted(range(len(measures)), key=lambda k: -(measures[k] or 0.0))
    run_cases(study, out, comm, force=force, order=order)
    rows = case_rows(study, out)
    for row, k in zip(rows, range(len(rows)), strict=True):
        row.update(_derived(row, study.case_scene(k), measures[k]))
    static = bool(rows) and all(r.get("kind") == "static" for r in rows)
    answers = STATIC_ANSWERS if static else INJECTION_ANSWERS
    estimates = {key: _estimate(study, rows, key) for key, _ in answers}
    result = ConvergenceResult(tuple(rows), estimates, answers)
    if comm.rank == 0 and write:
        _write_outputs(out, study, result)
    comm.barrier()
    for line in format_table(study, result).splitlines():
        say(line)
    say(f"{study.name}: {len(rows)} cases; tables in {out}/results.csv and convergence.csv")
    return result


def _derived(row: Mapping[str, Any], scene: Scene, measure: float | None) -> dict[str, Any]:
    """Columns computed from a case's summary and scene: h, the crack's place, Sneddon's u_y."""
    first = row.get("first_crack") or {}
    distance = first.get("distance_from_wellbore_wall_m")
    if distance is None and first.get("point_m") is not None:
        distance = float(np.linalg.norm(first["point_m"]))  # from the injection point
    return {
        "x": measure,
        "h_m": characteristic_size(scene),
        "first_crack_distance_m": distance,
        "sneddon_centre_uy_um": (row.get("sneddon") or {}).get("centre_uy_um"),
        "completed": 1.0 if row.get("wall_time_s") is not None and not row.get("stopped") else 0.0,
    }


def _estimate(study: ConvergenceStudy, rows: list[dict[str, Any]], key: str) -> Extrapolation:
    """Estimate the error of answer ``key`` from the completed cases."""
    done = [r for r in rows if r["completed"]]
    values = [_num(r.get(key)) for r in done]
    if study.measure is None:  # names: no measure to extrapolate in, only the spread
        finite = [v for v in values if math.isfinite(v)]
        spread = max(finite) - min(finite) if finite else math.nan
        first = finite[0] if finite else math.nan
        return Extrapolation(first, None, spread, None, f"{SPREAD}: named cases", len(finite))
    return extrapolate([_num(r["x"]) for r in done], values)


def _num(v: Any) -> float:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else math.nan


def _case_columns(answers: tuple[tuple[str, str], ...], static: bool) -> list[str]:
    counts = ["overstressed_interfaces"] if static else ["tensile_failures", "shear_failures"]
    head = ["case", "x", "h_m", "cells", "unknowns", "ranks", "completed"]
    return head + [key for key, _ in answers] + counts + list(COST_COLUMNS)


def _write_outputs(out: Path, study: ConvergenceStudy, result: ConvergenceResult) -> None:
    """results.csv, convergence.csv, convergence.json and convergence.png (rank 0)."""
    static = result.answers is STATIC_ANSWERS
    cols = _case_columns(result.answers, static)
    lines = [",".join(["value", *cols])]
    for r in result.rows:
        label = str(r["value"]).replace(",", ";")
        lines.append(",".join([label] + [f"{_num(r.get(c)):.10g}" for c in cols]))
    write_atomic(out / "results.csv", "\n".join(lines) + "\n")
    est = [_estimate_row(key, e) for key, e in result.estimates.items()]
    text = [",".join(ESTIMATE_COLUMNS)]
    text += [",".join(str(row[c]) for c in ESTIMATE_COLUMNS) for row in est]
    write_atomic(out / "convergence.csv", "\n".join(text) + "\n")
    record = {
        "name": study.name,
        "scene": str(study.scene_path),
        "parameter": study.parameter,
        "measure": study.measure,
        "cases": [{c: r.get(c) for c in ["value", *cols]} for r in result.rows],
        "estimates": est,
    }
    write_json(out / "convergence.json", record, MPI.COMM_SELF)
    from hfcdem.workflows.convergence_plot import plot_convergence

    axis = MEASURES[study.parameter]
    with atomic_path(out / "convergence.png") as tmp:
        plot_convergence(tmp, study.name, axis[1:] if axis else None, result)


def _estimate_row(key: str, e: Extrapolation) -> dict[str, Any]:
    def show(v: float | None) -> str:
        return "" if v is None or not math.isfinite(v) else f"{v:.10g}"

    return {
        "answer": key,
        "finest": show(e.finest),
        "limit": show(e.limit),
        "error": show(e.error),
        "relative_error": show(e.relative_error),
        "order": show(e.order),
        "method": e.method,
    }


def format_table(study: ConvergenceStudy, result: ConvergenceResult) -> str:
    """Return the cases and the error estimates as aligned text (what the command prints)."""
    keys = [key for key, _ in result.answers]
    head = ["value", study.measure or "-", "cells", *keys, "wall_s", "mem_MB", "rank_MB"]
    body = []
    for r in result.rows:
        cells = [str(r["value"]), _g(r.get("x")), _g(r.get("cells"))]
        cells += [_g(r.get(k)) for k in keys] + [_g(r.get(c)) for c in COST_COLUMNS]
        body.append(cells)
    lines = _align([head, *body])
    lines.append("")
    est = [["answer", "finest", "extrapolated", "error", "rel.", "order", "method"]]
    for key, e in result.estimates.items():
        rel = f"{e.relative_error:.2%}" if math.isfinite(e.relative_error) else "-"
        est.append([key, _g(e.finest), _g(e.limit), _g(e.error), rel, _g(e.order), e.method])
    return "\n".join(lines + _align(est))


def _g(v: Any) -> str:
    x = _num(v)
    return f"{x:.5g}" if math.isfinite(x) else "-"


def _align(table: list[list[str]]) -> list[str]:
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) for row in table]


def read_convergence(output: str | Path) -> dict[str, Any]:
    """Return ``convergence.json`` of a finished study in ``output``."""
    return json.loads((Path(output) / "convergence.json").read_text())


__all__ = [
    "ESTIMATE_COLUMNS",
    "INJECTION_ANSWERS",
    "MEASURES",
    "STATIC_ANSWERS",
    "ConvergenceResult",
    "ConvergenceStudy",
    "characteristic_size",
    "convergence_study",
    "format_table",
    "load_convergence",
    "read_convergence",
    "run_convergence",
    "study_kind",
]
