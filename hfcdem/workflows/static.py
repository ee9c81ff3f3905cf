"""Run a static scene: one solve of the CDEM solid under a pressure held in its crack.

A scene with a ``[load]`` section instead of ``[injection]`` (see
:mod:`hfcdem.config.physics`) is solved once: no fluid flows, the pressure acts
on both faces of the pre-existing crack (tag ``crack``) and the in-situ stress
acts everywhere.  The springs hold whatever the load, which is what a
comparison with an elastic solution needs; the summary counts the springs
loaded past their strength.  (Letting them break under a held pressure is an
unstable crack: it runs to the boundary.  Growth is what an injection scene is
for.)

For a ``crack_plate`` scene the crack-face displacement is compared with
Sneddon's infinite-plate solution (the perforation paper's eq. 21) at the
paper's 11 monitoring points, under the net pressure: the crack pressure less
the in-situ compression normal to the crack (Griffith with a background
stress, the HFDDA paper's eq. 17).

Written into DIR: ``summary.json``, ``crack_opening.csv`` and
``crack_opening.png`` (opening along the crack), ``fields.bp`` (displacement,
normal stresses) and ``interfaces.pvd`` (state, opening, normal traction and
failure ratio per interface) for ParaView.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from hfcdem import analytic
from hfcdem.config.geometry import Scene
from hfcdem.config.plates import CrackPlate
from hfcdem.config.tables import SceneError
from hfcdem.io.files import write_csv, write_json
from hfcdem.io.plots import plot_lines
from hfcdem.io.sampling import evaluate_at_points
from hfcdem.io.series import FieldSeries
from hfcdem.solid.cdem import CDEMSolid, Loads
from hfcdem.solid.interfaces import FacetState

MONITORING_POINTS = 11  # along the crack, tips included (the paper's Fig. 6)


class StaticState:
    """The solved solid under one load, in the shape :class:`FieldSeries` writes."""

    def __init__(self, solid: CDEMSolid, loads: Loads) -> None:
        self.solid, self.loads = solid, loads

    def current_loads(self) -> Loads:
        """Return the loads of the solid's displacement."""
        return self.loads

    def interface_fields(self, loads: Loads) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Vertex coordinates (F, nv, 3) and per-facet data of the owned interfaces."""
        solid = self.solid
        snap = solid.snapshot(loads)
        ratio, _ = solid.overstress(loads)
        own = solid.owned
        data = {
            "state": solid.state[own].astype(float),
            "opening_m": snap.opening[own],
            "normal_traction_MPa": snap.normal_traction[own] / 1e6,
            "failure_ratio": ratio[own],
        }
        return solid.vertex_coords[own], data


def crack_face_displacement(solid: CDEMSolid, x: np.ndarray, axis: int = 1) -> np.ndarray:
    """Half the jump of displacement component ``axis`` across the crack line y = 0 at ``x``.

    Points on the crack are probed just above and below it, so each side's
    block is evaluated; the result is the same on every rank.
    """
    eps = 1e-10
    up = np.column_stack([x, np.full_like(x, eps)])
    down = np.column_stack([x, np.full_like(x, -eps)])
    return 0.5 * (
        evaluate_at_points(solid.u, up)[:, axis] - evaluate_at_points(solid.u, down)[:, axis]
    )


def net_crack_pressure(scene: Scene) -> float:
    """Crack pressure less the in-situ compression normal to the crack (Pa).

    The crack of a ``crack_plate`` lies along x; the stress tensor is tension-positive.
    """
    assert scene.physics.load is not None
    sigma = scene.physics.stress.tensor(2)
    return float(scene.physics.load.crack_pressure + sigma[1, 1])


def compare_sneddon(
    solid: CDEMSolid, half_length: float, pressure: float, symmetric: bool
) -> dict[str, Any]:
    """Crack-face u_y at the paper's 11 monitoring points next to Sneddon's eq. (21).

    ``symmetric``: the mesh is the half x >= 0, so points at x < 0 are read at -x.
    """
    material = solid.material
    x = np.linspace(-half_length, half_length, MONITORING_POINTS)
    probe = np.abs(x) if symmetric else x.copy()
    # the tips themselves are on the crack's end vertices: step just inside
    probe = np.clip(probe, -half_length * (1 - 1e-9), half_length * (1 - 1e-9))
    ours = crack_face_displacement(solid, probe)
    exact = 0.5 * analytic.sneddon_opening(
        x, half_length, pressure, material.youngs_modulus, material.poisson_ratio
    )
    centre = MONITORING_POINTS // 2
    inner = slice(1, -1)  # the tips have zero opening: no relative error there
    return {
        "points": np.column_stack([x, ours, exact]).tolist(),  # x, u_y, Sneddon's u_y (m)
        "centre_uy_um": float(ours[centre] * 1e6),
        "sneddon_centre_uy_um": float(exact[centre] * 1e6),
        # None under no net pressure: eq. (21) is zero there, nothing to compare to
        "centre_relative_error": (
            float(ours[centre] / exact[centre] - 1.0) if exact[centre] != 0.0 else None
        ),
        "max_relative_error_inner": (
            float(np.max(np.abs(ours[inner] / exact[inner] - 1.0)))
            if np.all(exact[inner] != 0.0)
            else None
        ),
    }


def run_static(
    scene: Scene,
    solid: CDEMSolid,
    out: Path,
    say: Callable[[str], None],
    record: Callable[[], dict[str, Any]],
) -> dict[str, Any]:
    """Solve ``scene`` (which has a ``[load]``) once and write its results; return the summary.

    ``record``: the run's common summary entries (cells, versions, wall time, ...).
    """
    comm = solid.comm
    load = scene.physics.load
    loads = Loads(crack_pressure=load.crack_pressure)
    if not comm.allreduce(int(np.count_nonzero(solid.is_crack & solid.owned)), op=MPI.SUM):
        raise SceneError("load.crack_pressure", "the scene has no pre-existing crack (tag 'crack')")
    t0 = time.perf_counter()
    solid.solve(loads)
    say(f"solved ({time.perf_counter() - t0:.1f} s)")
    ratio, _ = solid.overstress(loads)
    overstressed = int(comm.allreduce(int(np.count_nonzero(ratio > 1.0)), op=MPI.SUM))
    # opening of every crack facet at its midpoint, gathered on rank 0 along x
    snap = solid.snapshot(loads)
    springs = (solid.state == FacetState.INTACT) & solid.owned
    tension = snap.normal_traction[springs].max(initial=-np.inf)
    worst = float(comm.allreduce(float(tension), op=MPI.MAX))
    if overstressed:
        say(
            f"{overstressed} springs are past their strength (largest tension "
            f"{worst / 1e6:.3g} MPa): held elastic here, the crack would grow"
        )
    mine = solid.is_crack & solid.owned
    rows = np.column_stack([solid.midpoints[mine][:, 0], snap.opening[mine]])
    gathered = comm.gather(rows, root=0)
    profile = np.concatenate(gathered) if gathered is not None else np.zeros((0, 2))
    profile = profile[np.argsort(profile[:, 0])] if len(profile) else profile
    max_opening = float(comm.allreduce(float(snap.opening[mine].max(initial=0.0)), op=MPI.MAX))

    summary: dict[str, Any] = {
        "scene": scene.name,
        "kind": "static",
        "crack_pressure_MPa": load.crack_pressure / 1e6,
        "max_crack_opening_m": max_opening,
        "overstressed_interfaces": overstressed,
        "max_spring_tension_MPa": worst / 1e6 if np.isfinite(worst) else None,
    }
    reference = None
    if isinstance(scene.geometry, CrackPlate):
        net = net_crack_pressure(scene)
        reference = compare_sneddon(
            solid,
            0.5 * scene.geometry.crack.length,
            net,
            "x" in scene.geometry.symmetry,
        )
        reference["net_pressure_MPa"] = net / 1e6
        if net <= 0.0:  # eq. (21) opens the crack only under a net pressure
            say(
                f"warning: the crack's net pressure (load.crack_pressure less the stress "
                f"across it) is {net / 1e6:.4g} MPa: the faces are pressed shut, held apart "
                "only by the springs' contact, and eq. (21) does not apply"
            )
        for xi, ours, ref in reference["points"]:
            gap = f"{ours / ref - 1:+.2%}" if ref > 0 else "(tip)"
            say(f"x {xi:+.4f} m: u_y {ours * 1e6:8.3f} um, eq. (21) {ref * 1e6:8.3f} um {gap}")
        r = reference
        error = r["centre_relative_error"]
        say(
            f"centre: u_y {r['centre_uy_um']:.3f} um, Sneddon "
            f"{r['sneddon_centre_uy_um']:.3f} um"
            + (f" ({error:+.2%})" if error is not None else "")
        )
        summary["sneddon"] = reference
    summary |= record()
    write_json(out / "summary.json", summary, comm)
    rows_out = [(float(x), float(w)) for x, w in zip(profile[:, 0], profile[:, 1], strict=True)]
    write_csv(out / "crack_opening.csv", ["x_m", "opening_m"], rows_out, comm)
    series = FieldSeries(out, StaticState(solid, loads))
    series.write(0.0)
    series.close()
    if comm.rank == 0:
        _plot_opening(out / "crack_opening.png", profile, reference, scene)
    comm.barrier()
    return summary


def _plot_opening(
    path: Path, profile: np.ndarray, reference: dict[str, Any] | None, scene: Scene
) -> None:
    """Draw the crack-face displacement against Sneddon's (called on rank 0)."""
    curves = []
    if reference is not None and isinstance(scene.geometry, CrackPlate):
        a = 0.5 * scene.geometry.crack.length
        fine = np.linspace(-a, a, 201)
        rock = scene.physics.rock
        exact = 0.5 * analytic.sneddon_opening(
            fine, a, net_crack_pressure(scene), rock.youngs_modulus, rock.poisson_ratio
        )
        pts = np.asarray(reference["points"])
        curves += [
            (fine, exact * 1e6, "Sneddon, eq. (21), under p - sigma_n", "k-"),
            (pts[:, 0], pts[:, 1] * 1e6, "hfcdem, monitoring points", "o"),
        ]
    if len(profile):
        curves.append((profile[:, 0], 0.5 * profile[:, 1] * 1e6, "hfcdem, facet midpoints", "."))
    title = f"{scene.name}: crack pressure {scene.physics.load.crack_pressure / 1e6:g} MPa"
    if isinstance(scene.geometry, CrackPlate) and net_crack_pressure(scene) != (
        scene.physics.load.crack_pressure
    ):
        title += f", net {net_crack_pressure(scene) / 1e6:g} MPa"
    ylabel = "crack-face displacement u_y = w / 2 (um)"
    plot_lines(path, curves, "x along the crack (m)", ylabel, title, MPI.COMM_SELF)


__all__ = [
    "MONITORING_POINTS",
    "StaticState",
    "compare_sneddon",
    "crack_face_displacement",
    "net_crack_pressure",
    "run_static",
]
