"""The SPC chart of a part as a figure: ΔE per geometry with centre, control limits, tolerance and rule hits.

One panel per geometry, then one per texture quantity of one vendor (|ΔS|, |ΔG| against their limits) (:class:`station.qc.spc_part.PartSpc`): the points in time order, the centre line
and the control limits from the baseline (shaded), the ΔE limit the samples were judged with, every
point a run rule names ringed red and labelled with the rule (WE1…4, N1…8), and a drift marked with an
arrow at the point that flagged it. Used by ``station qc spc --out`` and the report's SPC page.
"""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from station.qc.errors import QcInputError
from station.qc.spc_part import GeometrySpc, PartSpc

__all__ = ["draw_spc", "spc_png_bytes", "write_spc_png"]


def _panel(ax: Axes, g: GeometrySpc, subgroup: int) -> None:
    ch = g.chart
    xs = list(range(1, len(ch.points) + 1))
    ax.plot(xs, ch.points, "o-", ms=3.5, lw=1, color="#2c5aa0")
    ax.axhline(ch.centre, color="0.2", lw=1, label=f"centre {ch.centre:.3f}")
    ax.axhline(ch.ucl, color="#e67e22", ls="--", lw=1, label=f"UCL {ch.ucl:.3f}")
    if ch.lcl > 0:
        ax.axhline(ch.lcl, color="#e67e22", ls="--", lw=1, label=f"LCL {ch.lcl:.3f}")
    ax.axvspan(0.5, ch.baseline + 0.5, color="0.85", alpha=0.5, label=f"baseline ({ch.baseline})")
    tops = [*ch.points, ch.ucl]
    if g.capability is not None:
        usl = g.capability.usl
        cpk = g.capability.cpk
        ax.axhline(
            usl, color="#c0392b", lw=1.2, label=f"limit {usl:g}" + ("" if cpk is None else f", Cpk {cpk:.2f}")
        )
        tops.append(usl)
    rules: dict[int, list[str]] = {}
    for h in ch.hits:
        for p in h.points:
            # label a rule where its run of hits starts; later points of the run are only ringed
            rules.setdefault(p, []).extend([] if p - 1 in h.points else [h.rule])
    for p, names in rules.items():
        ax.plot(xs[p], ch.points[p], "o", ms=9, mfc="none", mec="#c0392b", mew=1.5)
        if not names:
            continue
        ax.annotate(
            ",".join(names),
            (xs[p], ch.points[p]),
            textcoords="offset points",
            xytext=(0, 8),
            ha="center",
            fontsize=6,
            color="#c0392b",
        )
    for h in g.drift[:1]:
        p = h.points[0]
        ax.annotate(
            f"drift ({h.rule})",
            (xs[p], ch.points[p]),
            xytext=(xs[p] - 0.5, max(tops) * 1.05),
            arrowprops={"arrowstyle": "->", "color": "#8e44ad"},
            fontsize=7,
            color="#8e44ad",
            ha="right",
        )
    what = "|Δ|" if g.quantity != "ΔE" else "ΔE"
    what = what if subgroup == 1 else f"mean {what} of {subgroup}"
    name = g.geometry if g.quantity == "ΔE" else f"{g.label} ({g.vendor})"
    ax.set_ylabel(f"{what} {name}", fontsize=8)
    ax.set_ylim(0, 1.2 * max(tops) or 1.0)
    ax.tick_params(labelsize=7)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, loc="upper left", ncol=5)


def draw_spc(fig: Figure, spc: PartSpc) -> None:
    """Draw *spc* on *fig*, one panel per geometry, then one per texture quantity (module docstring)."""
    charts = (*spc.geometries, *spc.texture)
    axes = fig.subplots(len(charts), 1, sharex=True, squeeze=False)[:, 0]
    for ax, g in zip(axes, charts, strict=True):
        _panel(ax, g, spc.subgroup)
    axes[-1].set_xlabel("sample (oldest first)" if spc.subgroup == 1 else "subgroup (oldest first)")
    chart = "individuals chart, σ = MR̄/d₂" if spc.subgroup == 1 else f"X̄/R chart, subgroups of {spc.subgroup}"
    fig.suptitle(
        f"{spc.job} / {spc.part}: SPC of ΔE{' and texture' if spc.texture else ''} ({chart}; Western Electric "
        "and Nelson rules)",
        fontsize=10,
    )


def spc_png_bytes(spc: PartSpc, dpi: int = 110) -> bytes:
    """The SPC chart of *spc* as PNG bytes (module docstring): 10 in wide, 2.4 in per chart, *dpi* dots per inch."""
    n = len(spc.geometries) + len(spc.texture)
    fig = plt.figure(figsize=(10, 2.4 * max(1, n) + 0.8), constrained_layout=True)
    try:
        draw_spc(fig, spc)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi)
    finally:
        plt.close(fig)
    return buf.getvalue()


def write_spc_png(spc: PartSpc, path: str | Path, dpi: int = 110) -> Path:
    """The SPC chart of *spc* (:func:`spc_png_bytes`) as a PNG at *path* (a file in an existing folder)."""
    out = Path(path)
    if out.suffix.lower() != ".png" or not out.parent.is_dir():
        raise QcInputError("out", "a .png file in an existing folder", str(out))
    out.write_bytes(spc_png_bytes(spc, dpi))
    return out
