"""What the QC screen shows beyond the verdict table (Qt-free): how the samples are judged, the readings
left out of a panel's mean, the texture rows, the SPC chart and the report's first page as PNG.

Every number comes from ``station.qc``: the averaging and its outliers from :mod:`station.qc.panels`
(robust z of :mod:`station.qc.repeats`), texture from :mod:`station.qc.texture`, the charts, run rules,
capability and drift from :mod:`station.qc.spc_part` and :mod:`station.qc.spc_chart`, the report's
pages from :mod:`station.qc.report`. This module only picks what to show and formats it.
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.errors import InputError
from station.model.domain import QC_OUTLIER_Z

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from station.qc.jobs import JobSummary
    from station.qc.spc_part import PartSpc
    from station.qc.texture import TextureTolerance
    from station.qc.tolerance import ToleranceSet

__all__ = [
    "PLAIN",
    "Judging",
    "SpcRow",
    "TextureLine",
    "figure_png",
    "outlier_lines",
    "report_first_page_png",
    "spc_hit_lines",
    "spc_png",
    "spc_rows",
    "texture_lines",
]

#: Subgroup sizes the SPC picker offers: 1 (individuals chart) and 2 … 10 (X̄/R chart).
SUBGROUPS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10)


@dataclass(frozen=True)
class Judging:
    """How a job is judged besides the formula, as ``station qc summary`` takes it.

    *average_panels*: each panel's repeat readings averaged and judged once (``--average-panels``),
    flagged outliers left out unless *keep_outliers* (``--keep-outliers``). *tolerance*: a tolerance
    set JSON file (``station qc tolerance --json``; blank: the product default). *texture_limits*:
    ``"ds=1,dg=0.5"`` (``--texture-limits``; blank: texture not judged).
    """

    average_panels: bool = False
    keep_outliers: bool = False
    tolerance: str = ""
    texture_limits: str = ""

    @property
    def is_default(self) -> bool:
        """True when nothing beyond the formula is asked (what every source can answer)."""
        return self == PLAIN

    def tolerance_set(self) -> ToleranceSet | None:
        """The tolerance set of the file named (``None`` when blank); :class:`InputError` naming
        ``tolerance`` for a file that cannot be read or is not a tolerance set."""
        from station.errors import StationError
        from station.qc.tolerance import ToleranceSet

        name = self.tolerance.strip()
        if not name:
            return None
        try:
            data = json.loads(Path(name).read_text(encoding="utf-8"))
            return ToleranceSet.from_dict(data)
        except (OSError, ValueError, StationError) as exc:
            raise InputError(
                "tolerance", "a readable tolerance set JSON file (station qc tolerance --json)", name
            ) from exc

    def texture_tolerance(self) -> TextureTolerance | None:
        """The texture limits typed (``None`` when blank); :class:`InputError` naming the field."""
        from station.qc.texture import parse_texture_limits

        text = self.texture_limits.strip()
        return None if not text else parse_texture_limits(text)

    def checked(self) -> Judging:
        """This judging once its tolerance file and texture limits parse (raises naming the field)."""
        self.tolerance_set()
        self.texture_tolerance()
        return self


#: Nothing beyond the formula: each reading judged alone, the product's default tolerance, no texture.
PLAIN = Judging()


def _panel_name(s: dict[str, Any]) -> str:
    return f"panel {s['panel_id']}" if s.get("panel_id") is not None else f"measurement {s['measurement_id']}"


def outlier_lines(part: dict[str, Any]) -> list[str]:
    """One line per flagged repeat reading of the part's panels (a summary's part, panels averaged):
    left out of the mean, or averaged in when outliers are kept, with its robust z (
    :mod:`station.qc.repeats`: z > ``QC_OUTLIER_Z``). The standard's left-out readings too."""
    out = []
    std = part.get("standard") or {}
    for mid in std.get("left_out") or []:
        out.append(f"standard: measurement {mid} left out of the standard's mean")
    for s in part.get("samples", []):
        rep = s.get("repeats")
        if not rep:
            continue
        ids = s.get("measurement_ids") or []
        left = set(s.get("left_out") or [])
        n = rep["n"]
        for r in rep["readings"]:
            if not r["outlier"]:
                continue
            mid = ids[r["index"]]
            z = "—" if r["robust_z"] is None else f"{r['robust_z']:.1f}"
            why = f"robust z {z} > {QC_OUTLIER_Z:g}"
            if mid in left:
                out.append(
                    f"{_panel_name(s)}: measurement {mid} left out ({why}); mean of {n - len(left)} of {n}"
                )
            else:
                out.append(f"{_panel_name(s)}: measurement {mid} kept although flagged ({why}); mean of {n}")
    return out


@dataclass(frozen=True)
class TextureLine:
    """One texture quantity of one sample against the standard (``station.qc.texture.TextureRow``)."""

    measurement_id: int
    sample: str
    vendor: str
    name: str
    geometry: str
    standard: float | None
    value: float | None
    delta: float | None
    tolerance: str
    limit: float | None
    verdict: str

    def cells(self) -> tuple[str, ...]:
        """The row as the screen's texture table shows it."""

        def num(v: float | None) -> str:
            return "—" if v is None else f"{v:.2f}"

        tol = f"{self.tolerance} ≤ {self.limit:g}" if self.limit is not None else "—"
        return (
            str(self.measurement_id),
            self.sample,
            self.vendor,
            self.name,
            self.geometry or "sample",
            num(self.standard),
            num(self.value),
            num(self.delta),
            tol,
            self.verdict,
        )


def texture_lines(part: dict[str, Any]) -> list[TextureLine]:
    """The texture rows of every sample of the part that has texture values of its own."""
    out = []
    for s in part.get("samples", []):
        tex = s.get("texture")
        if not tex or not any(r["sample"] is not None for r in tex["rows"]):
            continue
        for r in tex["rows"]:
            out.append(
                TextureLine(
                    int(s["measurement_id"]),
                    _panel_name(s),
                    str(tex["vendor"]),
                    str(r["name"]),
                    str(r["geometry"]),
                    r["standard"],
                    r["sample"],
                    r["delta"],
                    str(r["tolerance"]),
                    r["limit"],
                    r["verdict"] or "unjudged",
                )
            )
    return out


@dataclass(frozen=True)
class SpcRow:
    """One geometry of a part's SPC: the chart's limits, the ΔE limit, capability and the rule hits."""

    geometry: str
    centre: float
    lcl: float
    ucl: float
    limit: float | None
    cp: float | None
    cpk: float | None
    ppk: float | None
    r_bar: float | None
    r_ucl: float | None
    hits: str

    def cells(self) -> tuple[str, ...]:
        def num(v: float | None, fmt: str = ".3f") -> str:
            return "—" if v is None else format(v, fmt)

        r = "—" if self.r_bar is None else f"{self.r_bar:.3f} / {num(self.r_ucl)}"
        return (
            self.geometry,
            num(self.centre),
            num(self.lcl),
            num(self.ucl),
            num(self.limit, "g"),
            num(self.cp, ".2f"),
            num(self.cpk, ".2f"),
            num(self.ppk, ".2f"),
            r,
            self.hits,
        )


def _samples(points: tuple[int, ...], step: int) -> str:
    """Chart points (0-based) as sample numbers from 1 (a subgroup by its last sample)."""
    return ", ".join(f"#{p * step + step}" for p in points)


def spc_rows(spc: PartSpc) -> list[SpcRow]:
    """Per geometry of *spc* its row (:class:`SpcRow`); hits as ``RULE @ #samples``."""
    out = []
    for g in spc.geometries:
        ch, cap = g.chart, g.capability
        hits = "; ".join(f"{h.rule} @ {_samples(h.points, spc.subgroup)}" for h in ch.hits) or "none"
        out.append(
            SpcRow(
                g.geometry,
                ch.centre,
                ch.lcl,
                ch.ucl,
                None if cap is None else cap.usl,
                None if cap is None else cap.cp,
                None if cap is None else cap.cpk,
                None if cap is None else cap.ppk,
                ch.r_bar,
                ch.r_ucl,
                hits,
            )
        )
    return out


def spc_hit_lines(spc: PartSpc) -> list[str]:
    """What the chart says in words: the chart used, the drift (
    :meth:`station.qc.spc_part.PartSpc.drift_lines`: where, by which rules, before or after the first
    fail) or that none was flagged, then each rule hit with its meaning."""
    chart = "individuals chart" if spc.subgroup == 1 else f"X̄/R chart, subgroups of {spc.subgroup}"
    base = "all points" if spc.baseline is None else f"the first {spc.baseline}"
    out = [f"{spc.job} / {spc.part}: {len(spc.samples)} samples, {chart}, limits from {base}"]
    out += [f"DRIFT {line}" for line in spc.drift_lines()] or ["drift: none flagged"]
    for g in spc.geometries:
        for h in g.chart.hits:
            out.append(f"{g.geometry} {h.rule} ({h.meaning}) at {_samples(h.points, spc.subgroup)}")
    return out


def figure_png(draw: Callable[[Figure], None], size_in: tuple[float, float], dpi: int = 80) -> bytes:
    """PNG bytes of a figure of *size_in* (inches) drawn by *draw* (Agg, no window, no pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size_in, constrained_layout=True)
    FigureCanvasAgg(fig)
    draw(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def spc_png(spc: PartSpc, dpi: int = 80) -> bytes:
    """The SPC chart of *spc* as ``station qc spc --out`` draws it (:func:`station.qc.spc_chart.draw_spc`)."""
    from station.qc.spc_chart import draw_spc

    return figure_png(lambda fig: draw_spc(fig, spc), (10, 2.4 * max(1, len(spc.geometries)) + 0.8), dpi)


def report_first_page_png(summary: JobSummary, dpi: int = 90) -> bytes:
    """The PDF report's first page (its cover, :func:`station.qc.report.report_figures`) as PNG bytes."""
    import matplotlib.pyplot as plt

    from station.qc.report import report_figures

    fig = report_figures(summary)[0]()
    try:
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi)
    finally:
        plt.close(fig)
    return buf.getvalue()
