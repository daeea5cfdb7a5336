"""QC report of a job: PDF (verdict tables, Lab-vs-angle, ΔE bars, SPC trend), CSV, trend PNG.

:func:`write_pdf` writes one PDF per job (matplotlib's PdfPages), from a
:class:`~station.qc.jobs.JobSummary` (:func:`station.qc.jobs.job_summary`):

1. a cover page: job, time, formula and rule, pass/warn/fail counts per part;
2. per part with a standard:

   * the **verdict table per geometry**: one row per sample (newest :data:`TABLE_ROWS`), ΔE at each
     geometry coloured by its verdict, and the overall verdict with the worst geometry;
   * with illuminant limits (:func:`station.qc.jobs.job_summary` ``illuminant_limits``) the
     **illuminant rows**: per sample and test illuminant, the metamerism index at each geometry against
     its limit ("MI 0.80 <= 1 pass"), coloured pass / fail (:mod:`station.qc.illuminant_rows`);
   * **L\\*, a\\*, b\\* against aspecular angle** of the standard (line) and the samples (points);
   * **ΔE per geometry bars** of the newest samples, with the ΔE limit of each geometry;
   * the **SPC chart** (:mod:`station.qc.spc_chart`): ΔE per geometry, individuals chart with the
     Western Electric and Nelson rule hits ringed and named, the limit and Cpk, drift noted under it.

Trials are named by panel, part and job; the cover names the operators and instruments and leaves
room for the signature.

:func:`write_csv` writes one row per sample and geometry; :func:`write_trend_png` the SPC chart of one
part. *progress* (optional) is called as ``progress(done, total, what)`` after each page.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure

from station.csv_cells import escape_cell
from station.model.display import lab_to_display
from station.model.domain import QC_DE_LIMIT
from station.qc.errors import QcInputError
from station.qc.jobs import JobSummary, PartSummary, SampleResult, StandardInfo
from station.qc.spc_chart import draw_spc
from station.qc.spc_part import part_spc, sample_name

__all__ = [
    "CSV_COLUMNS",
    "Progress",
    "csv_text",
    "part_figures",
    "pdf_bytes",
    "report_figures",
    "write_csv",
    "write_pdf",
    "write_pngs",
    "write_trend_png",
]

Progress = Callable[[int, int, str], None]
#: Samples shown in a part's verdict table and ΔE bars (the newest).
TABLE_ROWS = 25
BAR_SAMPLES = 6
#: Reasons of the newest warned or failed samples printed under a verdict table.
REASON_LINES = 5
_VERDICT_COLOUR = {"pass": "#b7e1b0", "warn": "#ffe08a", "fail": "#f4a09a"}
_A4 = (8.27, 11.69)
_A4_LANDSCAPE = (11.69, 8.27)

CSV_COLUMNS = (
    "job",
    "part",
    "measurement_id",
    "measured_at",
    "instrument",
    "geometry",
    "aspecular_deg",
    "L_standard",
    "a_standard",
    "b_standard",
    "L",
    "a",
    "b",
    "dL",
    "da",
    "db",
    "dC",
    "dH",
    "dE",
    "verdict",
    "overall",
    "formula",
)


def _judged(summary: JobSummary) -> list[PartSummary]:
    return [p for p in summary.parts if p.standard is not None]


def _cover(summary: JobSummary) -> Figure:
    fig = plt.figure(figsize=_A4)
    fig.text(0.08, 0.94, f"QC report — job {summary.job}", fontsize=18, weight="bold")
    tol = summary.tolerance
    rule = (
        f"{tol.aggregation} rule, warn above {tol.warn_fraction:g} × limit ({tol.name or 'tolerance file'})"
        if tol
        else f"product default: ΔE <= {QC_DE_LIMIT:g} at every geometry, max rule"
    )
    lines = [
        f"generated {summary.generated_at.strftime('%Y-%m-%d %H:%M UTC')}",
        f"formula: {summary.formula}",
        f"tolerance: {rule}",
    ]
    if summary.illuminant_limits:
        limits = ", ".join(f"{k} MI <= {v:g}" for k, v in summary.illuminant_limits.items())
        lines.append(f"illuminant rows: {limits} (metamerism index from D65, {summary.formula})")
    samples = [x for p in summary.parts for x in p.samples]
    lines.append(
        "operators: " + (", ".join(sorted({x.row.operator for x in samples if x.row.operator})) or "—")
    )
    lines.append("instruments: " + (", ".join(dict.fromkeys(x.row.instrument for x in samples)) or "—"))
    for i, text in enumerate(lines):
        fig.text(0.08, 0.90 - 0.025 * i, text, fontsize=10)
    fig.text(0.08, 0.06, "checked by ____________________   date __________   signature ____________________")
    rows = []
    for p in summary.parts:
        c = p.counts()
        std = (
            "none"
            if p.standard is None
            else _standard_text(p.standard)
            if p.standard.measurement_id is not None
            else f"design {p.standard.design_id}"
        )
        rows.append([p.part, std, str(len(p.samples)), str(c["pass"]), str(c["warn"]), str(c["fail"])])
    ax = fig.add_axes((0.08, 0.38, 0.84, 0.34))
    ax.axis("off")
    if rows:
        table = ax.table(
            cellText=rows,
            colLabels=["part", "standard", "samples", "pass", "warn", "fail"],
            loc="upper center",
            cellLoc="center",
        )
        table.scale(1, 1.4)
        for i, p in enumerate(summary.parts, start=1):
            c = p.counts()
            for j, k in ((3, "pass"), (4, "warn"), (5, "fail")):
                if c[k]:
                    table[i, j].set_facecolor(_VERDICT_COLOUR[k])
    notes = [f"{p.part}: {p.note}" for p in summary.parts if p.note]
    for i, text in enumerate(notes[:12]):
        fig.text(0.08, 0.34 - 0.022 * i, text[:130], fontsize=8, color="0.3")
    return fig


def _standard_text(std: StandardInfo) -> str:
    avg, n = std.averaged, len(std.averaged.measurement_ids) if std.averaged else 0
    if avg is None:
        return f"measurement {std.measurement_id}"
    return f"mean of {n - len(avg.left_out)}/{n} readings of panel {avg.row.panel_id}"


def _geometries(part: PartSummary) -> list[str]:
    names: list[str] = []
    for s in part.samples:
        for g in s.verdict.per_geometry:
            if g.geometry not in names:
                names.append(g.geometry)
    return names


def _angle_of(part: PartSummary) -> dict[str, float]:
    return {g.geometry: g.aspecular_deg for s in part.samples for g in s.verdict.per_geometry}


def _label(s: SampleResult) -> str:
    """A trial by its panel, part and job (:func:`station.qc.spc_part.sample_name`), not by a row number."""
    return sample_name(s)


def _why(s: SampleResult) -> str:
    """One line on why a sample did not pass: the geometries out of band, or the mean rule's reason,
    then the illuminant rows that failed."""
    v = s.verdict
    tex = s.texture
    if tex is not None and tex.verdict != "pass" and v.verdict == "pass":
        bad = [r for r in tex.rows if r.verdict == tex.verdict]
        rows = "; ".join(
            f"{r.name} {r.geometry or 'sample'} {r.tolerance} {r.delta:+.2f}"
            for r in bad
            if r.delta is not None
        )
        return f"{_label(s)} {s.overall}: texture ({tex.vendor}) {rows}"
    booth = s.illuminants
    if booth is not None and booth.verdict == "fail":
        failed = [r for r in booth.rows if r.verdict == "fail"]
        rows = "; ".join(f"{r.illuminant} {r.geometry} MI {r.index:.2f} > {r.limit:g}" for r in failed)
        d65 = "" if v.verdict == "pass" else f"D65 {v.verdict}; "
        return f"{_label(s)} {s.overall}: {d65}{rows}"
    if v.aggregation == "mean":
        return f"{_label(s)} {v.verdict}: {v.reason}"
    parts = []
    for k in ("fail", "warn"):
        names = [g.geometry for g in v.per_geometry if g.verdict == k]
        if names:
            parts.append(f"{k} at {', '.join(names)}")
    return f"{_label(s)} {v.verdict}: {'; '.join(parts)} (max ΔE {v.max_de:.2f} at {v.worst_geometry})"


def _heads(part: PartSummary, names: Sequence[str]) -> list[str]:
    """ΔE column heads with the limit each geometry was judged with (``ΔE 45as15 ≤ 1``)."""
    lim = {g.geometry: g.limit for s in part.samples for g in s.verdict.per_geometry if g.limit is not None}
    return [f"ΔE {n}" + (f" ≤ {lim[n]:g}" if n in lim else "") for n in names]


def _spc_page(summary: JobSummary, part: PartSummary) -> Figure:
    """The SPC chart of the part with its rule hits (:mod:`station.qc.spc_chart`), drift under it."""
    fig = plt.figure(figsize=_A4, constrained_layout=True)
    try:
        spc = part_spc(summary, part.part)
    except QcInputError as exc:
        fig.text(0.5, 0.5, f"no SPC chart: {exc}", ha="center", fontsize=10)
        return fig
    lines = spc.drift_lines() or ["drift: none flagged"]
    fig.get_layout_engine().set(rect=(0, 0.012 * (len(lines[:6]) + 1), 1, 1 - 0.012 * (len(lines[:6]) + 1)))  # type: ignore[union-attr, call-arg]
    draw_spc(fig, spc)
    fig.text(0.02, 0.003, "\n".join(line[:150] for line in lines[:6]), fontsize=7, color="#8e44ad")
    return fig


def _table_page(summary: JobSummary, part: PartSummary) -> Figure:
    fig = plt.figure(figsize=_A4_LANDSCAPE)
    fig.suptitle(f"{summary.job} / {part.part}: verdict per geometry ({summary.formula})", fontsize=13)
    names = _geometries(part)
    samples = list(part.samples)[-TABLE_ROWS:]
    ax = fig.add_axes((0.03, 0.05, 0.94, 0.85))
    ax.axis("off")
    if not samples:
        ax.text(0.5, 0.5, "no samples judged", ha="center", fontsize=12)
        return fig
    rows, colours = [], []
    for s in samples:
        by = {g.geometry: g for g in s.verdict.per_geometry}
        cells = [_label(s)[:34], f"{s.row.instrument[:18]} / {s.row.operator or '—'}"]
        cols = ["white", "white"]
        for n in names:
            g = by.get(n)
            cells.append("—" if g is None else f"{g.de:.2f}")
            cols.append("white" if g is None else _VERDICT_COLOUR[g.verdict])
        v = s.verdict
        cells += [f"{v.mean_de:.2f}", f"{v.max_de:.2f} @ {v.worst_geometry}", s.overall]
        cols += ["white", "white", _VERDICT_COLOUR[s.overall]]
        rows.append(cells)
        colours.append(cols)
    table = ax.table(
        cellText=rows,
        cellColours=colours,
        colLabels=[
            "trial (panel, part, job)",
            "instrument / operator",
            *_heads(part, names),
            "mean ΔE",
            "max ΔE",
            "verdict",
        ],
        loc="upper center",
        cellLoc="center",
    )
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    table.scale(1, 1.25)
    if len(part.samples) > TABLE_ROWS:
        fig.text(0.03, 0.02, f"newest {TABLE_ROWS} of {len(part.samples)} samples", fontsize=8, color="0.3")
    bad = [s for s in reversed(samples) if s.overall != "pass"][:REASON_LINES]
    for i, s in enumerate(bad):
        fig.text(0.03, 0.05 + 0.022 * (len(bad) - 1 - i), _why(s)[:200], fontsize=7, color="0.25")
    return fig


def _illuminant_page(summary: JobSummary, part: PartSummary) -> Figure:
    """Illuminant rows of the newest samples: per test illuminant and geometry the metamerism index
    against its limit, coloured pass / fail (one table row per sample and illuminant)."""
    fig = plt.figure(figsize=_A4_LANDSCAPE)
    limits = summary.illuminant_limits or {}
    fig.suptitle(
        f"{summary.job} / {part.part}: illuminant rows — metamerism index from D65 ({summary.formula})",
        fontsize=13,
    )
    fig.text(
        0.03,
        0.91,
        "limits: "
        + ", ".join(f"{k}: MI <= {v:g}" for k, v in limits.items())
        + "   (CIE special index: the sample corrected additively for its D65 difference)",
        fontsize=9,
        color="0.25",
    )
    samples = [s for s in part.samples if s.illuminants is not None][-TABLE_ROWS:]
    ax = fig.add_axes((0.03, 0.05, 0.94, 0.83))
    ax.axis("off")
    if not samples:
        ax.text(0.5, 0.5, "no sample with spectra judged under the illuminants", ha="center", fontsize=12)
        return fig
    names = list(dict.fromkeys(r.geometry for s in samples for r in s.illuminants.rows))  # type: ignore[union-attr]
    rows, colours = [], []
    for s in samples:
        check = s.illuminants
        assert check is not None  # noqa: S101 - filtered above
        for ill in check.limits:
            by = {r.geometry: r for r in check.rows if r.illuminant == ill}
            cells, cols = [_label(s), ill], ["white", "white"]
            for n in names:
                r = by.get(n)
                op = "" if r is None else ("<=" if r.verdict == "pass" else ">")
                cells.append("—" if r is None else f"MI {r.index:.2f} {op} {r.limit:g} {r.verdict}")
                cols.append("white" if r is None else _VERDICT_COLOUR[r.verdict])
            worst = max(by.values(), key=lambda r: r.index)
            verdict = "fail" if any(r.verdict == "fail" for r in by.values()) else "pass"
            cells += [f"{worst.index:.2f} @ {worst.geometry}", verdict]
            cols += ["white", _VERDICT_COLOUR[verdict]]
            rows.append(cells)
            colours.append(cols)
    table = ax.table(
        cellText=rows,
        cellColours=colours,
        colLabels=["sample", "illuminant", *names, "max MI", "verdict"],
        loc="upper center",
        cellLoc="center",
    )
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    table.scale(1, 1.25)
    return fig


def _lab_and_bars_page(summary: JobSummary, part: PartSummary) -> Figure:
    assert part.standard is not None  # noqa: S101 - only judged parts get this page
    fig, axes = plt.subplots(2, 2, figsize=_A4_LANDSCAPE, constrained_layout=True)
    fig.suptitle(f"{summary.job} / {part.part}: standard and samples", fontsize=13)
    std = part.standard.reading
    order = np.argsort(std.aspecular_deg)
    ang = np.asarray(std.aspecular_deg)[order]
    lab = std.lab_array()[order]
    mid = int(np.argmin(np.abs(ang - 45.0)))
    swatch = np.clip(lab_to_display(lab[mid]), 0, 1)
    recent = list(part.samples)[-BAR_SAMPLES:]
    cmap = plt.get_cmap("viridis")
    curve = part.standard.curve
    kind = "standard (design)" if curve is not None else "standard"
    line_ang, line_lab = (ang, lab) if curve is None else (np.asarray(curve.aspecular_deg), curve.lab_array())
    for ch, (ax, name) in enumerate(zip(axes.flat[:3], ("L*", "a*", "b*"), strict=True)):
        ax.plot(line_ang, line_lab[:, ch], "-", color="black", lw=1.5, label=kind, zorder=3)
        ax.plot(ang, lab[:, ch], "s", mfc="none", mec="black", mew=1.5, ms=8, zorder=4)
        ax.plot([], [], "s", color=swatch, mec="black", ms=8, label=f"standard colour at {ang[mid]:g}°")
        for i, s in enumerate(part.samples):
            r = s.row.reading
            ax.plot(
                r.aspecular_deg,
                r.lab_array()[:, ch],
                "o",
                ms=3.5,
                alpha=0.8,
                color=cmap(i / max(1, len(part.samples) - 1)),
                label="samples (old → new)" if i == 0 else None,
            )
        ax.set_xlabel("aspecular angle (°)")
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    ax = axes[1, 1]
    names = _geometries(part)
    x = np.arange(len(names))
    width = 0.8 / max(1, len(recent))
    limits = _limits(summary, part, names)
    for i, s in enumerate(recent):
        by = {g.geometry: g for g in s.verdict.per_geometry}
        de = [by[n].de if n in by else 0.0 for n in names]
        edge = ["#c0392b" if n in by and by[n].verdict == "fail" else "none" for n in names]
        ax.bar(
            x + (i - (len(recent) - 1) / 2) * width,
            de,
            width,
            color=cmap(i / max(1, len(recent) - 1)),
            edgecolor=edge,
            linewidth=1.5,
            label=_label(s),
        )
    ax.plot(x, limits, "_", color="#c0392b", ms=30, mew=2, label="ΔE limit")
    ax.set_xticks(x, names)
    ax.set_ylabel(f"ΔE ({summary.formula})")
    ax.set_title(f"ΔE per geometry, newest {len(recent)} samples (red edge: fail)", fontsize=10)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    ax.grid(axis="y", alpha=0.3)
    return fig


def _limits(summary: JobSummary, part: PartSummary, names: Sequence[str]) -> list[float]:
    angles = _angle_of(part)
    tol = summary.tolerance
    out = []
    for n in names:
        if tol is None:
            out.append(QC_DE_LIMIT)
            continue
        try:
            out.append(tol.limits_for(angles[n]).de)
        except QcInputError:
            out.append(float("nan"))
    return out


def part_figures(summary: JobSummary, part: PartSummary) -> list[Figure]:
    """The pages of one judged part: verdict table, (illuminant rows,) Lab vs angle with ΔE bars, SPC trend."""
    return [build() for build in _part_pages(summary, part)]


def _part_pages(summary: JobSummary, part: PartSummary) -> list[Callable[[], Figure]]:
    pages: list[Callable[[], Figure]] = [lambda: _table_page(summary, part)]
    if summary.illuminant_limits:
        pages.append(lambda: _illuminant_page(summary, part))
    pages += [lambda: _lab_and_bars_page(summary, part), lambda: _spc_page(summary, part)]
    return pages


def report_figures(summary: JobSummary) -> list[Callable[[], Figure]]:
    """The report's pages as builders (cover, then three per judged part, four with illuminant rows)."""
    pages: list[Callable[[], Figure]] = [lambda: _cover(summary)]
    for part in _judged(summary):
        pages += _part_pages(summary, part)
    return pages


def _writable(path: str | Path) -> Path:
    out = Path(path)
    if not out.parent.is_dir():
        raise QcInputError("out", "a file in an existing folder", str(out))
    return out


def write_pdf(summary: JobSummary, path: str | Path, progress: Progress | None = None) -> Path:
    """Write the job's QC report as a PDF at *path* (module docstring for the pages); returns the path.

    The file is written next to *path* and moved into place at the end, so a failed run leaves no
    half-written report.
    """
    out = _writable(path)
    tmp = out.with_name(out.name + ".part")
    try:
        _render(summary, tmp, progress)
        tmp.replace(out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def pdf_bytes(summary: JobSummary, progress: Progress | None = None) -> bytes:
    """The job's QC report as PDF bytes (what :func:`write_pdf` writes; for a service response)."""
    buf = io.BytesIO()
    _render(summary, buf, progress)
    return buf.getvalue()


def _render(summary: JobSummary, target: Any, progress: Progress | None) -> None:
    pages = report_figures(summary)
    with PdfPages(target, metadata={"Title": f"QC report {summary.job}", "Creator": "CACAD Station"}) as pdf:
        for i, build in enumerate(pages, start=1):
            fig = build()
            pdf.savefig(fig)
            plt.close(fig)
            if progress is not None:
                progress(i, len(pages), f"page {i} of {len(pages)}")


def write_pngs(summary: JobSummary, folder: str | Path, dpi: int = 80) -> list[Path]:
    """The report's pages as PNG files ``page-01.png`` … in *folder* (to look at or embed)."""
    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True)
    out = []
    for i, build in enumerate(report_figures(summary), start=1):
        fig = build()
        p = d / f"page-{i:02d}.png"
        fig.savefig(p, dpi=dpi)
        plt.close(fig)
        out.append(p)
    return out


def write_trend_png(summary: JobSummary, part: str, path: str | Path, dpi: int = 110) -> Path:
    """The SPC trend chart of one part of the job as a PNG at *path*."""
    match = [p for p in summary.parts if p.part == part]
    if not match:
        raise QcInputError(
            "part", f"a part of job {summary.job} ({', '.join(p.part for p in summary.parts)})", part
        )
    if not match[0].samples:
        raise QcInputError("part", f"a part with judged samples ({match[0].note or 'none judged'})", part)
    out = _writable(path)
    if len(match[0].samples) < 2:  # too few for control limits: the sample's ΔE per geometry alone
        (smp,) = match[0].samples
        fig = plt.figure(figsize=(10, 3), constrained_layout=True)
        ax = fig.subplots()
        ax.bar([g.geometry for g in smp.verdict.per_geometry], [g.de for g in smp.verdict.per_geometry])
        ax.set_title(f"{summary.job} / {part}: one sample, too few for control limits", fontsize=10)
        ax.set_ylabel(f"ΔE ({summary.formula})")
    else:
        spc = part_spc(summary, part)
        n = len(spc.geometries) + len(spc.texture)
        fig = plt.figure(figsize=(10, 2.4 * max(1, n) + 0.8), constrained_layout=True)
        draw_spc(fig, spc)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


def csv_rows(summary: JobSummary) -> list[list[object]]:
    """The CSV's data rows (one per sample and geometry), in :data:`CSV_COLUMNS` order."""
    rows: list[list[object]] = []
    for part in _judged(summary):
        assert part.standard is not None  # noqa: S101
        std = part.standard
        for s in part.samples:
            reading = s.row.reading
            for g in s.verdict.per_geometry:
                i = reading.aspecular_deg.index(g.aspecular_deg)
                ref = (
                    std.reading.lab[std.reading.aspecular_deg.index(g.aspecular_deg)]
                    if (g.aspecular_deg in std.reading.aspecular_deg)
                    else _design_lab(s, g.aspecular_deg)
                )
                rows.append(
                    [
                        escape_cell(summary.job),
                        part.part,
                        s.row.measurement_id,
                        s.row.measured_at.isoformat(),
                        escape_cell(s.row.instrument),
                        g.geometry,
                        g.aspecular_deg,
                        *ref,
                        *reading.lab[i],
                        g.dl,
                        g.da,
                        g.db,
                        g.dc,
                        g.dh,
                        g.de,
                        g.verdict,
                        s.overall,
                        summary.formula,
                    ]
                )
    return rows


def _design_lab(s: SampleResult, angle: float) -> tuple[float, float, float]:
    """Standard Lab at *angle* recovered from the sample and its differences (sample − ΔLab)."""
    g = next(g for g in s.verdict.per_geometry if g.aspecular_deg == angle)
    lab = s.row.reading.lab[s.row.reading.aspecular_deg.index(angle)]
    return (lab[0] - g.dl, lab[1] - g.da, lab[2] - g.db)


def csv_text(summary: JobSummary) -> str:
    """The CSV :func:`write_csv` writes, as text (header and one row per sample and geometry)."""
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(CSV_COLUMNS)
    w.writerows(csv_rows(summary))
    return buf.getvalue()


def write_csv(summary: JobSummary, path: str | Path) -> Path:
    """Write one row per sample and geometry (:data:`CSV_COLUMNS`) as UTF-8 CSV at *path*."""
    out = _writable(path)
    out.write_text(csv_text(summary), encoding="utf-8", newline="")
    return out
