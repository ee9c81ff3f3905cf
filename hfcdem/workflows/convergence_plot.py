"""The picture of a convergence study: each answer against h, and what each case cost.

One panel per answer that some case found: the answer against the measure (log
x, inverted so the mesh refines from left to right), the extrapolated value
(dashed) and the band of the estimated error around it (around the finest
answer when there is no extrapolation).  A last panel draws the wall time (log)
and, on a twin axis, the peak memory (sum over the ranks and the largest rank).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np


def plot_convergence(path: Path, title: str, axis: tuple[str, float] | None, result: Any) -> None:
    """Draw ``result`` (a ConvergenceResult) into the PNG ``path`` (one process).

    ``axis``: the x label and the factor from SI to its unit; None for named cases.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    rows = list(result.rows)
    categorical = axis is None
    scale = 1.0 if axis is None else axis[1]
    xs = np.array([k if categorical else _num(r.get("x")) * scale for k, r in enumerate(rows)])
    shown = [
        (key, label)
        for key, label in result.answers
        if any(math.isfinite(_num(r.get(key))) for r in rows)
    ]
    panels = len(shown) + 1
    ncols = min(3, panels)
    nrows = math.ceil(panels / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.6 * ncols, 3.6 * nrows), squeeze=False)
    flat = list(axes.ravel())
    for ax, (key, label) in zip(flat, shown, strict=False):
        ys = np.array([_num(r.get(key)) for r in rows])
        _answer_panel(ax, xs, ys, label, result.estimates[key])
    _cost_panel(flat[len(shown)], xs, rows)
    for ax in flat[panels:]:
        ax.set_visible(False)
    for ax in flat[:panels]:
        if axis is None:
            ax.set_xticks(xs, [str(r["value"]) for r in rows])
        else:
            ax.set_xscale("log")
            ax.invert_xaxis()  # finer meshes to the right
            ax.xaxis.set_minor_formatter(NullFormatter())
            ticks = xs[np.isfinite(xs)]
            ax.set_xticks(ticks, [f"{t:.3g}" for t in ticks])
            ax.set_xlabel(axis[0])
        ax.grid(alpha=0.3, which="both")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=110)
    plt.close(fig)


def _answer_panel(ax: Any, xs: np.ndarray, ys: np.ndarray, label: str, est: Any) -> None:
    """One answer against the measure, with its extrapolation and error band."""
    ok = np.isfinite(xs) & np.isfinite(ys)
    ax.plot(xs[ok], ys[ok], "o-", label="cases")
    if est.limit is not None and math.isfinite(est.limit):
        ax.axhline(est.limit, color="k", ls="--", lw=1.0, label=f"extrapolated {est.limit:.5g}")
        ax.axhspan(
            est.limit - est.error,
            est.limit + est.error,
            color="C1",
            alpha=0.2,
            label="± estimated error",
        )
    elif math.isfinite(est.error) and math.isfinite(est.finest):
        ax.axhspan(
            est.finest - est.error,
            est.finest + est.error,
            color="C3",
            alpha=0.15,
            label="± two finest differ",
        )
    order = f", p = {est.order:.2f}" if est.order is not None else ""
    ax.set_title(f"{label}\n{est.method}{order}", fontsize=9)
    ax.legend(fontsize=7)


def _cost_panel(ax: Any, xs: np.ndarray, rows: list[dict[str, Any]]) -> None:
    """Wall time (log) and peak memory (twin axis) of each case."""
    wall = np.array([_num(r.get("wall_time_s")) for r in rows])
    total = np.array([_num(r.get("peak_memory_MB")) for r in rows])
    largest = np.array([_num(r.get("peak_memory_rank_max_MB")) for r in rows])
    ax.plot(xs, wall, "o-", color="C0", label="wall time")
    if np.any(np.isfinite(wall) & (wall > 0)):
        ax.set_yscale("log")
    ax.set_ylabel("wall time (s)", color="C0")
    twin = ax.twinx()
    twin.plot(xs, total, "s--", color="C2", label="peak memory, ranks summed")
    twin.plot(xs, largest, "^:", color="C4", label="peak memory, largest rank")
    twin.set_ylabel("peak memory (MB)", color="C2")
    lines = ax.get_lines() + twin.get_lines()
    twin.legend(lines, [line.get_label() for line in lines], fontsize=7, loc="upper left")
    ax.set_title("cost of each case", fontsize=9)


def _num(v: Any) -> float:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else math.nan


__all__ = ["plot_convergence"]
