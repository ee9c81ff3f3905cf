"""Places along a perforation tunnel, in the paper's terms, and the stress along it.

The paper says where things happen by the tunnel's parts: the root (where the
tunnel leaves the wellbore), the middle and the far end.  :func:`wellbore_place`
names a point's part from its distance to the wellbore wall, measured across
the wellbore axis; :func:`stress_along_tunnels` bins the rock's stress around
the tunnels by that distance (the paper's Fig. 18: sigma_xx at the first
cracks, largest at the root).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import dolfinx
import numpy as np
from mpi4py import MPI

from hfcdem.config.geometry import PerforatedBlock
from hfcdem.config.scene import Scene
from hfcdem.io.sampling import interpolate_expression

#: the figure of sigma_xx along the tunnels at the first crack (the paper's Fig. 18)
STRESS_FIGURE = "sigma_xx.png"

#: stress components by name: index pairs into the stress tensor
COMPONENTS = {"xx": (0, 0), "yy": (1, 1), "zz": (2, 2), "xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def wall_distances(scene: Scene, points: np.ndarray) -> np.ndarray | None:
    """Return each point's distance from the wellbore wall (m), across the wellbore axis.

    0 at a perforation root, negative inside the wellbore; None without a wellbore.
    """
    wellbore = getattr(scene.geometry, "wellbore", None)
    if wellbore is None:
        return None
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    across = np.zeros((len(pts), 3))
    across[:, : pts.shape[1]] = pts
    across[:, "xyz".index(wellbore.axis)] = 0.0
    return np.asarray(np.linalg.norm(across, axis=1) - wellbore.radius)


def tunnel_length(scene: Scene) -> float | None:
    """Return the longest perforation tunnel's length (m); None without tunnels."""
    tunnels = getattr(scene.geometry, "perforations", ())
    return max(t.profile.stations[-1] for t in tunnels) if tunnels else None


def wellbore_place(scene: Scene, point: np.ndarray) -> dict[str, Any]:
    """Return a point's ``distance_from_wellbore_wall_m`` and, with tunnels, its ``place``.

    The distance is measured across the wellbore axis (0 at a perforation root);
    nothing without a wellbore.  With tunnels also ``fraction_of_tunnel``: the
    distance over the tunnels' length (1 at the tip), so a point near a line
    between two places shows as such (the thirds' lines at 1/3 and 2/3).
    """
    distances = wall_distances(scene, np.asarray(point)[None, :])
    if distances is None:
        return {}
    distance = float(distances[0])
    out: dict[str, Any] = {"distance_from_wellbore_wall_m": distance}
    length = tunnel_length(scene)
    if length is not None:
        out["place"] = tunnel_place(distance, length)
        out["fraction_of_tunnel"] = distance / length
    return out


def tunnel_place(distance: float, length: float) -> str:
    """Name a distance from the wellbore wall in the paper's terms, for a tunnel ``length`` long.

    The tunnel's thirds: ``root``, ``middle``, ``far end``; ``beyond the tip`` past it.
    """
    if distance <= length / 3.0:
        return "root"
    if distance <= 2.0 * length / 3.0:
        return "middle"
    return "far end" if distance <= length else "beyond the tip"


#: the tunnel's parts in order from the wellbore wall (:func:`tunnel_place`)
PLACES = ("root", "middle", "far end", "beyond the tip")


def _parts(scene: Scene, points: np.ndarray) -> np.ndarray | None:
    """Name each point's part of the tunnels (:data:`PLACES`); None without tunnels."""
    length = tunnel_length(scene)
    distances = wall_distances(scene, points) if length is not None else None
    if length is None or distances is None:
        return None
    return np.array([tunnel_place(float(d), length) for d in distances], dtype=object)


def place_counts(scene: Scene, points: np.ndarray, comm: MPI.Comm) -> dict[str, int] | None:
    """Return how many of the ranks' ``points`` lie in each part of the tunnels (collective).

    Parts without a point are left out; None without tunnels.
    """
    names = _parts(scene, np.asarray(points, dtype=float))
    if names is None:
        return None
    local = np.array([np.count_nonzero(names == name) for name in PLACES], dtype=np.int64)
    total = np.zeros_like(local)
    comm.Allreduce(local, total, op=MPI.SUM)
    return {name: int(n) for name, n in zip(PLACES, total, strict=True) if n}


def place_ratios(
    scene: Scene, midpoints: np.ndarray, ratio: np.ndarray, comm: MPI.Comm
) -> dict[str, float] | None:
    """Return the highest failure ratio of the facets in each part of the tunnels (collective).

    ``ratio`` is a solid's failure ratio per local facet (1: at its strength; 0 for
    facets that may not break, e.g. broken, ghost or glued ones), ``midpoints`` the
    facets' midpoints.  Read at the first break, it says how near the other parts
    came to breaking first: a part at 0.998 is a near tie, and which one breaks
    first is then a question of the step path, not of the rock.  Parts without a
    facet that may break read 0.  None without tunnels.
    """
    names = _parts(scene, midpoints)
    if names is None:
        return None
    local = np.array([np.max(ratio[names == name], initial=0.0) for name in PLACES], float)
    highest = np.zeros_like(local)
    comm.Allreduce(local, highest, op=MPI.MAX)
    return {name: float(v) for name, v in zip(PLACES, highest, strict=True)}


def _from_sh(v: np.ndarray) -> np.ndarray:
    """Angle (deg) of each row of ``v`` from the SH axis (x), folded into 0-90."""
    norm = np.linalg.norm(v, axis=1)
    return np.degrees(np.arccos(np.clip(np.abs(v[:, 0]) / np.maximum(norm, 1e-300), 0.0, 1.0)))


def turn_past_tips(scene: Scene, centroids: np.ndarray, areas: np.ndarray) -> dict[str, Any] | None:
    """How the broken interfaces beyond the tunnels' tips turn toward SH (the paper's Fig. 8).

    For each interface farther from the wellbore wall than the tunnels are long,
    the angle from SH (x) of its direction across the wellbore axis, against that
    of the tunnel it lies nearest in direction: ``turn_deg`` is their
    area-weighted mean difference (positive: nearer SH than the tunnel).  Also
    ``past_tip`` (how many), ``farthest_past_tip_m`` and ``cell_angle_deg``, the
    angle one cell of the scene's finest size subtends at the tips.  None
    without tunnels, or when the wellbore runs along SH.
    """
    from hfcdem.mesh.frames import tunnel_frame

    geom = scene.geometry
    if not isinstance(geom, PerforatedBlock) or not geom.perforations:
        return None
    wellbore, length = geom.wellbore, tunnel_length(scene) or 0.0
    if wellbore.axis == "x":
        return None
    pts = np.atleast_2d(np.asarray(centroids, dtype=float))
    across = pts.copy()
    across[:, "xyz".index(wellbore.axis)] = 0.0
    distance = np.linalg.norm(across, axis=1) - wellbore.radius
    past = distance > length
    tip_radius = wellbore.radius + length
    out: dict[str, Any] = {
        "past_tip": int(past.sum()),
        "farthest_past_tip_m": float(max(distance.max(initial=length) - length, 0.0)),
        "cell_angle_deg": float(np.degrees(geom.mesh.size / tip_radius)),
        "turn_deg": None,
    }
    if past.any():
        directions = np.array([tunnel_frame(geom, k).d for k in range(len(geom.perforations))])
        u = across[past]
        nearest = directions[np.argmax(u @ directions.T, axis=1)]
        turn = _from_sh(nearest) - _from_sh(u)
        out["turn_deg"] = float(np.average(turn, weights=np.asarray(areas)[past]))
    return out


def stress_along_tunnels(
    scene: Scene, solid: Any, component: str = "xx", bins: int = 12
) -> dict[str, Any] | None:
    """Return the rock's total stress around the tunnels, by distance from the wellbore wall.

    The rock is every owned cell beside an interface of the fracturable zone
    (each cell counted once, on its owning rank, so the answer does not depend
    on the rank count); a cell's stress is its mean (DG0), tension positive.
    The tunnel's length is cut into ``bins`` equal lengths; per bin the largest
    and the mean stress (MPa; None for an empty bin).  ``peak``: the largest
    stress of the zone, where it is and its place (:func:`wellbore_place`);
    ``tensile_cells``: how many of the ``cells`` are in tension.
    Collective; None for a scene without tunnels or a 2D solid.
    """
    if component not in COMPONENTS:
        raise ValueError(f"component: expected one of {', '.join(COMPONENTS)}, got {component!r}")
    length = tunnel_length(scene)
    if length is None or getattr(scene.geometry, "wellbore", None) is None or solid.gdim != 3:
        return None
    i, j = COMPONENTS[component]
    mesh, comm = solid.mesh, solid.comm
    tdim = mesh.topology.dim
    rock = solid.breakable
    cells = np.unique(solid.cells[rock].ravel())
    cells = cells[(cells >= 0) & (cells < mesh.topology.index_map(tdim).size_local)]
    sigma = interpolate_expression(solid.total_stress()[i, j] / 1e6, mesh, ("DG", 0))
    dofs = sigma.function_space.dofmap.list[cells, 0] if len(cells) else np.zeros(0, np.int32)
    values = sigma.x.array[dofs]
    centres = dolfinx.mesh.compute_midpoints(mesh, tdim, cells.astype(np.int32))
    distance = wall_distances(scene, centres)
    assert distance is not None
    edges = np.linspace(0.0, length, bins + 1)
    which = np.clip(np.searchsorted(edges, distance, side="right") - 1, 0, bins - 1)
    inside = (distance >= 0.0) & (distance <= length)
    largest = np.full(bins, -np.inf)
    np.maximum.at(largest, which[inside], values[inside])
    total = np.bincount(which[inside], values[inside], minlength=bins).astype(float)
    count = np.bincount(which[inside], minlength=bins).astype(float)
    # buffer reductions: element-wise over the bins
    comm.Allreduce(MPI.IN_PLACE, largest, op=MPI.MAX)
    comm.Allreduce(MPI.IN_PLACE, total, op=MPI.SUM)
    comm.Allreduce(MPI.IN_PLACE, count, op=MPI.SUM)
    k = int(np.argmax(values)) if len(values) else -1
    mine = (float(values[k]), centres[k].tolist()) if k >= 0 else (-np.inf, None)
    value, point = max(comm.allgather(mine), key=lambda vp: vp[0])
    if point is None:
        return None
    return {
        "component": f"sigma_{component}",
        "unit": "MPa",
        "cells": int(comm.allreduce(len(cells), op=MPI.SUM)),
        "tensile_cells": int(comm.allreduce(int(np.sum(values > 0.0)), op=MPI.SUM)),
        "distance_m": (0.5 * (edges[:-1] + edges[1:])).tolist(),
        "largest_MPa": [float(v) if np.isfinite(v) else None for v in largest],
        "mean_MPa": [float(s / n) if n else None for s, n in zip(total, count, strict=True)],
        "peak_MPa": value,
        "peak_point_m": point,
    } | {f"peak_{k}": v for k, v in wellbore_place(scene, np.asarray(point)).items()}


def plot_stress_along_tunnels(path: Any, profiles: Mapping[str, Any], title: str) -> None:
    """Draw the largest (solid) and mean (dashed) stress against distance, one colour per run.

    ``profiles``: label -> a :func:`stress_along_tunnels` result.  The tunnel's
    thirds (root, middle, far end) are shaded.  Not collective: call it on one rank.
    """
    if profiles:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        length = 0.0
        for n, (label, prof) in enumerate(profiles.items()):
            x = 1e3 * np.asarray(prof["distance_m"])
            length = max(length, x[-1] + 0.5 * (x[1] - x[0]) if len(x) > 1 else 2 * x[-1])
            big = np.array([np.nan if v is None else v for v in prof["largest_MPa"]])
            mean = np.array([np.nan if v is None else v for v in prof["mean_MPa"]])
            ax.plot(x, big, "-o", color=f"C{n}", ms=3, label=f"{label}: largest")
            ax.plot(x, mean, "--", color=f"C{n}", label=f"{label}: mean")
        for k, name in enumerate(("root", "middle", "far end")):
            if k % 2 == 0:
                ax.axvspan(k * length / 3, (k + 1) * length / 3, color="0.93", zorder=0)
            ax.text((k + 0.5) * length / 3, 0.02, name, transform=ax.get_xaxis_transform(),
                    ha="center", fontsize=8, color="grey")  # fmt: skip
        ax.axhline(0.0, color="k", lw=0.6)  # tension above
        if len(profiles) > 1:
            fig.text(0.01, 0.01, "shaded: the thirds of the longest tunnel", fontsize=7,
                     color="grey")  # fmt: skip
        component = next(iter(profiles.values()))["component"].replace("sigma_", "")
        ax.set_xlabel("distance from the wellbore wall (mm)")
        ax.set_ylabel(f"total sigma_{component} (MPa, tension positive)")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout(rect=(0, 0.03, 1, 1))
        fig.savefig(path, dpi=120)
        plt.close(fig)


def plot_first_crack_stress(out: Path, scene: Scene, first: Mapping[str, Any] | None) -> None:
    """Draw ``out``/sigma_xx.png from a summary's first crack (nothing without its profile).

    Not collective: call it on one rank.
    """
    first = first or {}
    profile = first.get("sigma_xx")
    if profile:
        mesh = f"{scene.resolution or 'default'} mesh"
        title = f"{scene.name} ({mesh}): the tunnel at the first crack, {first['time_s']:.3g} s"
        plot_stress_along_tunnels(out / STRESS_FIGURE, {scene.name: profile}, title)


__all__ = [
    "COMPONENTS",
    "PLACES",
    "STRESS_FIGURE",
    "place_counts",
    "place_ratios",
    "plot_first_crack_stress",
    "plot_stress_along_tunnels",
    "stress_along_tunnels",
    "tunnel_length",
    "tunnel_place",
    "turn_past_tips",
    "wall_distances",
    "wellbore_place",
]
