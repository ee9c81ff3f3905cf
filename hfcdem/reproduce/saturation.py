"""The perforation paper's Fig. 14: the joints around the tunnel filling in time.

No. 2 run with the joints' seepage (the fidelity ladder's seepage rung: water,
no wall film, joints of 1 um filling from dry) writes its interfaces over time
(``joints.pvd``, a saturation per interface).  :func:`plot_saturation` draws
their saturation around the tunnel at a few times, binned by station along the
tunnel and distance from its axis; :func:`saturation_in_time` adds how fast the
zone fills to the peak-pressure rows.  The paper shows pictures only ("over 1
to 60 s" the fluid permeates the rock from the tunnel wall), so the filling is
listed, not judged.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from hfcdem import references
from hfcdem.config.geometry import Scene
from hfcdem.io.series import read_facets, read_pvd
from hfcdem.reproduce.compare import CaseResult, Comparison, peak_against

#: the figure the case draws into its directory
SATURATION_FIGURE = "saturation.png"

#: times shown (s): Fig. 14's span, "over 1 to 60 s"
SHOWN_TIMES = (1.0, 5.0, 10.0, 60.0)

#: a scene's joints made to seep; a seepage run's steps go back to solver.time_step
#: after every break, so it takes no bound on the pressure change (the scene's is dropped)
TO_SEEPAGE: dict[str, Any] = {
    "injection.wall_joints": "seepage",
    "solver.max_pressure_change": None,
}

#: No. 2's scene turned into the seepage rung (benchmarks/fidelity_ladder.py), frames every 1 s
SEEPAGE_RUNG: dict[str, Any] = {
    **TO_SEEPAGE,
    "injection.wall_film": None,
    "fluid.bulk_modulus": "2.2 GPa",
    "output.interval": "1 s",
}

#: shares of the zone's joints holding pressure whose first times are reported
SHARES = (0.5, 0.9, 1.0)

#: bin of the picture (m) and how far from the tunnel axis it looks (the zone's radius)
_BIN = 0.01
_REACH = 0.1


def filling_times(history: Path) -> dict[float, float | None]:
    """First time (s) the share of the zone's joints holding pressure reaches each of SHARES."""
    with history.open() as f:
        rows = [
            (float(r["time_s"]), float(r["joints_holding_pressure"])) for r in csv.DictReader(f)
        ]
    return {s: next((t for t, w in rows if w >= s - 1e-12), None) for s in SHARES}


def _frame(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centroids, areas and saturations of the interfaces of one VTU frame."""
    centroids, areas, data = read_facets(path)
    return centroids, areas, np.asarray(data["saturation"], dtype=float)


def plot_saturation(directory: Path, scene: Scene, path: Path) -> bool:
    """Draw the joints' saturation around the first tunnel at SHOWN_TIMES; False if no frames."""
    from hfcdem.mesh.frames import tunnel_frame

    frames = read_pvd(directory / "joints.pvd")
    if not frames or not getattr(scene.geometry, "perforations", ()):
        return False
    times = np.array([t for t, _ in frames])
    chosen = sorted({int(np.argmin(abs(times - t))) for t in SHOWN_TIMES if t <= times[-1] + 0.5})
    tunnel = tunnel_frame(scene.geometry, 0)  # type: ignore[arg-type]
    length = tunnel.profile.stations[-1]
    s_edges = np.arange(-2 * _BIN, length + 3 * _BIN, _BIN)
    r_edges = np.arange(0.0, _REACH + 0.5 * _BIN, _BIN)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(chosen), 1, figsize=(7.0, 1.9 * len(chosen) + 0.9),
                             sharex=True, squeeze=False)  # fmt: skip
    image = None
    for ax, k in zip(axes[:, 0], chosen, strict=True):
        centroid, area, sat = _frame(directory / frames[k][1])
        station, radius = tunnel.local(centroid)
        grid = np.full((len(r_edges) - 1, len(s_edges) - 1), np.nan)
        i = np.digitize(radius, r_edges) - 1
        j = np.digitize(station, s_edges) - 1
        inside = (i >= 0) & (i < grid.shape[0]) & (j >= 0) & (j < grid.shape[1])
        weight = np.zeros(grid.shape)
        total = np.zeros(grid.shape)
        np.add.at(weight, (i[inside], j[inside]), area[inside])
        np.add.at(total, (i[inside], j[inside]), (area * sat)[inside])
        filled = weight > 0
        grid[filled] = total[filled] / weight[filled]
        image = ax.pcolormesh(1e3 * s_edges, 1e3 * r_edges, grid, cmap="Blues", vmin=0.0, vmax=1.0)
        ax.plot(1e3 * np.asarray(tunnel.profile.stations),
                0.5e3 * np.asarray(tunnel.profile.diameters), color="k", lw=1.0)  # fmt: skip
        ax.set_aspect("equal")
        ax.set_ylabel("from the axis (mm)", fontsize=8)
        box = {"facecolor": "white", "alpha": 0.8, "lw": 0}
        ax.text(0.99, 0.93, f"t = {frames[k][0]:.3g} s", transform=ax.transAxes, ha="right",
                va="top", fontsize=8, bbox=box)  # fmt: skip
    axes[-1, 0].set_xlabel("station along the tunnel from the wellbore wall (mm)", fontsize=8)
    if image is not None:
        fig.colorbar(image, ax=list(axes[:, 0]), label="saturation (joint-area weighted)",
                     shrink=0.8)  # fmt: skip
    res = scene.resolution or "default"
    fig.suptitle(f"No. 2's joints filling in time ({res} mesh, water, joints of 1 um from dry; "
                 "black: the tunnel wall)", fontsize=9)  # fmt: skip
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def saturation_in_time(r: CaseResult) -> list[Comparison]:
    """No. 2 with seepage: its peak and first crack, how fast its zone fills, and the picture."""
    rows = peak_against(
        "breakdown (peak pressure), joints filling in time",
        references.CHARGES["no2"],
        "the paper's CDEM (Fig. 15)",
        0.05,
        "no knob of the joints' fluid (water, 1 um joints from dry, no wall film); "
        "the start pressure is the scene's",
        stress=True,
    )(r)
    history = r.directory / "history.csv"
    if history.exists():
        times = filling_times(history)
        shown = ", ".join(
            f"{100 * s:.0f} % by {t:.3g} s" if t is not None else f"{100 * s:.0f} % not reached"
            for s, t in times.items()
        )
        rows.append(
            Comparison(
                "joints of the fracturable zone holding pressure",
                times[0.9],
                unit="s",
                source="the paper's Fig. 14 (pictures only)",
                ours_text=shown,
                reference_text="the fluid permeates the rock gradually over 1 to 60 s",
                note="not judged: the paper gives pictures, no share or time",
            )
        )
    if r.scenes:
        plot_saturation(r.directory, r.scenes[0], r.directory / SATURATION_FIGURE)
    return rows


__all__ = [
    "SATURATION_FIGURE",
    "SEEPAGE_RUNG",
    "SHOWN_TIMES",
    "TO_SEEPAGE",
    "filling_times",
    "plot_saturation",
    "saturation_in_time",
]
