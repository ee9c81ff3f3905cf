"""The KGD series of the HFDDA paper (sec. 4.2, Figs. 8-10): mesh and time-step refinement.

Three studies of ``meshes/scenes/kgd_strip.toml`` run the paper's series: the
path facets dx = 4, 2, 1, 0.5 m without and with a 5 MPa background stress
(Figs. 8 and 9), and dt = 2, 1, 0.5, 0.25 s at dx = 0.5 m (Fig. 10).  Each run
ends at 10 s; its half-length (fluid front), net inlet pressure and inlet
opening are compared with the zero-toughness KGD solution at that time.  The
paper prints these only as curves, so what is judged is the finest run against
the closed form and the direction the paper states for the series:

- no background stress: good agreement at every dx, the length moving in whole
  facets (stair steps);
- 5 MPa: the agreement worsens as dx grows (the pressure and width at the inlet
  rise above the solution);
- a longer time step: a longer fracture, a lower inlet pressure and width.

The figure ``series.png`` draws the three gaps against the swept value.
"""

from __future__ import annotations

import csv
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hfcdem.analytic import kgd_viscosity
from hfcdem.reproduce.compare import CaseResult, Comparison
from hfcdem.workflows.study import case_directory

SOURCE = "KGD zero toughness, self-similar (HFDDA sec. 4.2)"
QUANTITIES = (
    ("half-length (fluid front)", "m", 1.0),
    ("inlet net pressure", "MPa", 1e-6),
    ("inlet opening", "mm", 1e3),
)


@dataclass(frozen=True)
class SeriesRun:
    """One run of a series at its end: swept value (SI), ours and the closed form (SI)."""

    x: float
    label: str
    ours: tuple[float, float, float]  # half-length, net inlet pressure, inlet opening
    exact: tuple[float, float, float]

    @property
    def gaps(self) -> np.ndarray:
        """Ours relative to the closed form, per quantity."""
        return np.asarray(self.ours) / np.asarray(self.exact) - 1.0


def read_series(r: CaseResult) -> list[SeriesRun]:
    """Return the runs of a series study, ordered from the coarsest swept value."""
    runs = []
    for k, (row, scene) in enumerate(zip(r.rows, r.scenes, strict=True)):
        phys = scene.physics
        assert phys.injection is not None
        rate = phys.injection.points[-1][1] * (2.0 if "x" in scene.geometry.symmetry else 1.0)
        t = float(row["simulated_time_s"])
        ref = kgd_viscosity(
            t, rate, phys.rock.youngs_modulus, phys.rock.poisson_ratio, phys.fluid.viscosity
        )
        history = r.directory / case_directory(k, row["value"]) / "history.csv"
        with history.open() as f:
            last = list(csv.DictReader(f))[-1]
        normal = -float(phys.stress.tensor(2)[1, 1])  # compression across the crack (y = 0)
        net = float(last["injection_pressure"]) - normal
        runs.append(
            SeriesRun(
                float(row["x"]),
                str(row["value"]),
                (float(row["fluid_front_m"]), net, float(row["inlet_opening_m"])),
                (ref.half_length, ref.net_pressure, ref.inlet_opening),
            )
        )
    return sorted(runs, key=lambda run: -run.x)


def kgd_series(
    swept: str, trend: Callable[[list[SeriesRun]], tuple[str, bool]] | None, figure: str
) -> Callable[[CaseResult], list[Comparison]]:
    """Compare a series: the finest run per quantity (10 %), and the paper's stated trend.

    ``swept``: what the series varies ("dx", "dt"); ``trend``: returns the paper's
    statement and whether ours follows it (None: nothing stated to judge);
    ``figure``: the paper's figure.
    """

    def compare(r: CaseResult) -> list[Comparison]:
        runs = read_series(r)
        finest = runs[-1]
        values = " / ".join(run.label for run in runs)
        rows = []
        for i, (quantity, unit, scale) in enumerate(QUANTITIES):
            gaps = " / ".join(f"{100 * run.gaps[i]:+.1f}" for run in runs)
            rows.append(
                Comparison(
                    f"{quantity} at {swept} = {finest.label}",
                    finest.ours[i] * scale,
                    finest.exact[i] * scale,
                    unit,
                    SOURCE,
                    0.10,
                    note=f"gaps at {swept} = {values}: {gaps} % "
                    f"(the paper's {figure}: curves only)",
                )
            )
        if trend is not None:
            statement, holds = trend(runs)
            rows.append(
                Comparison(
                    f"the series as {swept} grows",
                    None,
                    ours_text="holds" if holds else "does not hold",
                    reference_text=statement,
                    agrees=holds,
                    source=f"the paper's text on its {figure}",
                )
            )
        if r.directory.exists():
            plot_series(runs, swept, figure, r.directory / "series.png")
        return rows

    return compare


def stress_worsens_coarse(runs: list[SeriesRun]) -> tuple[str, bool]:
    """Judge the paper's statement: with a background stress, a coarser mesh, larger p and w."""
    coarse, fine = runs[0], runs[-1]
    return (
        "with 5 MPa the inlet pressure and width rise above the solution as dx grows",
        bool(coarse.gaps[1] > fine.gaps[1] and coarse.gaps[2] > fine.gaps[2]),
    )


def longer_step_runs_further(runs: list[SeriesRun]) -> tuple[str, bool]:
    """Judge the paper's statement: a longer dt, a longer fracture, lower inlet p and w."""
    long, short = runs[0], runs[-1]
    return (
        "a longer dt gives a longer fracture and a lower inlet pressure and width",
        bool(
            long.ours[0] > short.ours[0]
            and long.ours[1] < short.ours[1]
            and long.ours[2] < short.ours[2]
        ),
    )


def plot_series(runs: list[SeriesRun], swept: str, figure: str, path: Path) -> None:
    """Draw the three gaps against the swept value (log axis)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4))
    x = [run.x for run in runs]
    for i, (quantity, _, _) in enumerate(QUANTITIES):
        ax.plot(x, [100 * run.gaps[i] for run in runs], "os^"[i] + "-", label=quantity)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.axhspan(-10, 10, color="grey", alpha=0.12, label="10 %")
    ax.set_xscale("log", base=2)
    ax.set_xticks(x, [run.label for run in runs])
    ax.invert_xaxis()
    ax.set_xlabel(swept)
    ax.set_ylabel("against the KGD solution at 10 s (%)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"KGD series, the HFDDA paper's {figure}")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


__all__ = [
    "SeriesRun",
    "kgd_series",
    "longer_step_runs_further",
    "plot_series",
    "read_series",
    "stress_worsens_coarse",
]
