"""Write the reproduction report: results.csv, report.md, report.html and figures/.

Everything the report shows is in its directory (the case figures are copied
into ``figures/``), so ``report.html`` reads offline and the directory can be
committed or mailed as it is.  ``results.csv`` has one row per comparison, for
diffing two versions of the code.
"""

from __future__ import annotations

import csv
import html
import io
import math
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from hfcdem.io.files import write_atomic
from hfcdem.reproduce.cases import PAPERS
from hfcdem.reproduce.compare import Comparison
from hfcdem.reproduce.runner import CaseRecord

COLUMNS = (
    "paper",
    "case",
    "quantity",
    "reference",
    "ours",
    "unit",
    "gap",
    "target",
    "met",
    "estimated_error",
    "source",
    "resolution",
    "wall_time_s",
    "status",
    "note",
)


def _num(v: float | None, digits: int = 4) -> str:
    if v is None or not math.isfinite(v):
        return ""
    return f"{v:.{digits}g}"


def _met(c: Comparison) -> str:
    return {True: "met", False: "NOT met", None: ""}[c.met]


def _rows(records: Sequence[CaseRecord]) -> list[dict[str, str]]:
    rows = []
    for r in records:
        comparisons = r.comparisons or (None,)
        for c in comparisons:
            row = {
                "paper": r.paper,
                "case": r.name,
                "resolution": r.resolution,
                "wall_time_s": f"{r.wall_time_s:.1f}",
                "status": r.status,
                "note": "; ".join(x for x in (r.message, r.note) if x),
            }
            if c is not None:
                row |= {
                    "quantity": c.quantity,
                    "reference": c.reference_text or _num(c.reference),
                    "ours": c.ours_text or _num(c.ours),
                    "unit": c.unit,
                    "gap": f"{c.gap:+.1%}" if c.gap is not None else "",
                    "target": c.target,
                    "met": _met(c),
                    "estimated_error": _num(c.error, 3),
                    "source": c.source,
                    "note": "; ".join(x for x in (c.note, row["note"]) if x),
                }
            rows.append({k: row.get(k, "") for k in COLUMNS})
    return rows


def _counts(records: Sequence[CaseRecord]) -> dict[str, int]:
    every = [c for r in records for c in r.comparisons]
    return {
        "met": sum(1 for c in every if c.met is True),
        "not met": sum(1 for c in every if c.met is False),
        "not judged": sum(1 for c in every if c.met is None),
        "cases failed": sum(1 for r in records if r.status in ("failed", "stopped")),
        "not modelled": sum(1 for r in records if r.status == "not modelled"),
    }


def write_report(out: Path, records: Sequence[CaseRecord], meta: Mapping[str, Any]) -> None:
    """Write the report files into ``out`` (call on one rank)."""
    figures = out / "figures"
    figures.mkdir(exist_ok=True)
    shown: dict[str, list[str]] = {}
    for r in records:
        for f in r.figures:
            name = f"{r.name}_{Path(f).name}"
            shutil.copyfile(out / f, figures / name)
            shown.setdefault(r.name, []).append(f"figures/{name}")
    rows = _rows(records)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_atomic(out / "results.csv", buf.getvalue())
    _plot_gaps(figures / "gaps.png", records)
    write_atomic(out / "report.md", _markdown(records, rows, meta, shown))
    write_atomic(out / "report.html", _html(records, rows, meta, shown))


def _header(meta: Mapping[str, Any], records: Sequence[CaseRecord]) -> list[str]:
    counts = _counts(records)
    total = sum(r.wall_time_s for r in records)
    return [
        f"Made {meta['date']} at commit {meta['commit']} on {meta['machine']}, "
        f"{meta['ranks']} rank(s); tier {meta['tier']}, fidelity {meta['fidelity']}"
        + (f", every case at resolution {meta['resolution']}" if meta.get("resolution") else "")
        + f"; {total / 60:.1f} min of case wall time.",
        "Rows: " + ", ".join(f"{v} {k}" for k, v in counts.items()) + ".",
        "A gap is ours relative to the reference. A row with a target is judged; a "
        "trend or ordering row is met when ours goes the paper's way. The resolution is "
        "the element size at the cavity or crack; the estimated error is the case's own "
        "(convergence cases) or what the project measured elsewhere (the case's note).",
    ]


def _markdown(
    records: Sequence[CaseRecord],
    rows: Sequence[Mapping[str, str]],
    meta: Mapping[str, Any],
    shown: Mapping[str, list[str]],
) -> str:
    lines = ["# hfcdem: the four papers reproduced", ""]
    lines += [*_header(meta, records), "", "![gaps](figures/gaps.png)", ""]
    cols = ("quantity", "reference", "ours", "unit", "gap", "target", "met", "estimated_error")
    for paper, title in PAPERS.items():
        mine = [r for r in records if r.paper == paper]
        if not mine:
            continue
        lines += [f"## {title}", ""]
        for r in mine:
            lines += [f"### {r.name}: {r.title}", ""]
            facts = [f"status: {r.status}"]
            if r.resolution:
                facts.append(f"resolution: {r.resolution}")
            if r.wall_time_s:
                facts.append(f"wall time: {r.wall_time_s:.0f} s")
            lines += ["; ".join(facts) + ".", ""]
            for text in (r.message, r.note, r.discretisation):
                if text:
                    lines += [f"- {text}"]
            if r.message or r.note or r.discretisation:
                lines.append("")
            mine_rows = [row for row in rows if row["case"] == r.name and row["quantity"]]
            if mine_rows:
                lines += ["| " + " | ".join(cols) + " | source / note |"]
                lines += ["|" + "---|" * (len(cols) + 1)]
                for row in mine_rows:
                    extra = "; ".join(x for x in (row["source"], row["note"]) if x)
                    cells = [row[c].replace("|", "/") for c in cols]
                    lines += ["| " + " | ".join(cells) + f" | {extra.replace('|', '/')} |"]
                lines.append("")
            for f in shown.get(r.name, []):
                lines += [f"![{r.name}]({f})", ""]
    return "\n".join(lines) + "\n"


def _html(
    records: Sequence[CaseRecord],
    rows: Sequence[Mapping[str, str]],
    meta: Mapping[str, Any],
    shown: Mapping[str, list[str]],
) -> str:
    e = html.escape
    cols = ("quantity", "reference", "ours", "unit", "gap", "target", "met", "estimated_error")
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        "<title>hfcdem: the four papers reproduced</title><style>",
        "body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}",
        "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;",
        "padding:2px 6px;font-size:90%}.met{background:#dfd}.no{background:#fdd}",
        "img{max-width:100%}</style></head><body>",
        "<h1>hfcdem: the four papers reproduced</h1>",
    ]
    parts += [f"<p>{e(p)}</p>" for p in _header(meta, records)]
    parts.append("<img src='figures/gaps.png' alt='gaps'>")
    for paper, title in PAPERS.items():
        mine = [r for r in records if r.paper == paper]
        if not mine:
            continue
        parts.append(f"<h2>{e(title)}</h2>")
        for r in mine:
            parts.append(f"<h3>{e(r.name)}: {e(r.title)}</h3><p>status: {e(r.status)}")
            if r.resolution:
                parts.append(f"; resolution: {e(r.resolution)}")
            if r.wall_time_s:
                parts.append(f"; wall time: {r.wall_time_s:.0f} s")
            parts.append("</p><ul>")
            parts += [f"<li>{e(t)}</li>" for t in (r.message, r.note, r.discretisation) if t]
            parts.append("</ul>")
            mine_rows = [row for row in rows if row["case"] == r.name and row["quantity"]]
            if mine_rows:
                head = "".join(f"<th>{c}</th>" for c in cols)
                parts.append(f"<table><tr>{head}<th>source / note</th></tr>")
                for row in mine_rows:
                    cls = {"met": "met", "NOT met": "no"}.get(row["met"], "")
                    cells = "".join(f"<td>{e(row[c])}</td>" for c in cols)
                    extra = "; ".join(x for x in (row["source"], row["note"]) if x)
                    parts.append(f"<tr class='{cls}'>{cells}<td>{e(extra)}</td></tr>")
                parts.append("</table>")
            parts += [f"<p><img src='{e(f)}' alt='{e(r.name)}'></p>" for f in shown.get(r.name, [])]
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _plot_gaps(path: Path, records: Sequence[CaseRecord]) -> None:
    """One bar per judged value row: the gap, coloured by met, with its target band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    bars = [
        (f"{r.name}: {c.quantity}", 100.0 * c.gap, c.tolerance, c.met)
        for r in records
        for c in r.comparisons
        if c.gap is not None and c.tolerance is not None
    ]
    fig, ax = plt.subplots(figsize=(9, 0.8 + 0.32 * max(len(bars), 1)))
    for i, (_, gap, tol, met) in enumerate(bars):
        ax.barh(i, gap, color="tab:green" if met else "tab:red")
        ax.plot([-100 * tol, 100 * tol], [i, i], "|", color="k", ms=9)
    ax.set_yticks(range(len(bars)), [b[0] for b in bars], fontsize=8)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.invert_yaxis()
    ax.set_xlabel("ours against the reference (%); ticks: the target")
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


__all__ = ["COLUMNS", "write_report"]
