"""Thesis chapter 2: the shared basis exponents and their errors for 1–11 lobes (eq 2.3.4, Figs 2.4–2.5).

The thesis gives no numbers for Figs 2.4–2.5 ("the actual values are omitted, since the error was
measured at only a few angles"), so the regenerated search is compared with two things: the thesis's
qualitative claims (errors fall as lobes are added; exponents spread over decades) and our shipped table
(station/render/data/lobe_basis.json), regenerated from the design database by
:func:`station.render.basis_selection.select_bases`, which is deterministic run to run. The full 1–11
search takes minutes and runs from the command only; the tests run the 1–2 lobe case.

§2.4: the lobe-weight fit methods (:func:`fit_methods`). §2.5.3, the anisotropic reconstruction
(Fig. 2.10) and the frame rates: :mod:`station.reproduce.ch2_aniso`.
"""

from __future__ import annotations

import itertools
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from station.render import basis_selection as bs
from station.render import lobe_fit as lf
from station.render.design_db import design_database
from station.render.lobes import MAX_LOBES
from station.reproduce.core import ExperimentResult, Figure, Quantity

if TYPE_CHECKING:
    pass

SHIPPED = "shipped table (station/render/data/lobe_basis.json)"
#: Relative tolerance between a regenerated objective f(E) and the shipped one.
F_TOLERANCE = 0.01


def shipped_rows() -> list[dict[str, object]]:
    """The shipped table's rows (lobes, exponents, max/mean error, objective)."""
    doc = json.loads(bs.SHIPPED_TABLE.read_text())
    rows: list[dict[str, object]] = doc["bases"]
    return rows


def regenerate(max_lobes: int, max_evals: int = bs.MAX_EVALS) -> list[bs.BasisRow]:
    """Run the basis search of eq 2.3.4 on the design database for 1..*max_lobes* lobes (converged:
    independent of *max_evals* unless a row reports ``converged`` False)."""
    brdfs = [lf.designed_brdf(d) for d in design_database()]
    return bs.select_bases(brdfs, max_lobes, max_evals)


def _compare(rows: Sequence[bs.BasisRow], divergence_note: str) -> list[Quantity]:
    shipped = {int(str(r["lobes"])): r for r in shipped_rows()}
    out = []
    for r in rows:
        ref = float(str(shipped[r.lobes]["objective"]))
        note = divergence_note if r.converged else divergence_note + "; this row's search was CUT OFF"
        out.append(
            Quantity(
                "2.5",
                f"f(E) = max + mean error, {r.lobes} lobe{'s' if r.lobes > 1 else ''}",
                "ΔE00",
                ref,
                r.objective,
                F_TOLERANCE * ref,
                reason=note,
                source=SHIPPED + "; the thesis omits its values",
                reference="shipped",
            )
        )
    return out


def _plot(out_dir: Path, rows: Sequence[bs.BasisRow]) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shipped = shipped_rows()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    for r in rows:
        axes[0].semilogy([r.lobes] * r.lobes, r.exponents, "o", color="C0", ms=5)
    for s in shipped:
        ex = [float(e) for e in s["exponents"]]  # type: ignore[attr-defined]
        axes[0].semilogy([int(str(s["lobes"])) + 0.25] * len(ex), ex, "x", color="C3", ms=5)
    axes[0].plot([], [], "o", color="C0", label="regenerated")
    axes[0].plot([], [], "x", color="C3", label="shipped")
    axes[0].set_xlabel("number of lobes")
    axes[0].set_ylabel("Phong exponent")
    axes[0].set_title("Fig. 2.4: basis exponents", fontsize=9)
    axes[0].legend(fontsize=8)
    m = [r.lobes for r in rows]
    axes[1].plot(m, [r.max_error for r in rows], "o-", label="max (regenerated)")
    axes[1].plot(m, [r.mean_error for r in rows], "s-", label="mean (regenerated)")
    sm = [int(str(s["lobes"])) for s in shipped]
    axes[1].plot(
        sm, [float(str(s["max_error_de"])) for s in shipped], "x--", color="C3", label="max (shipped)"
    )
    axes[1].plot(
        sm, [float(str(s["mean_error_de"])) for s in shipped], "+--", color="C3", label="mean (shipped)"
    )
    axes[1].set_xlabel("number of lobes")
    axes[1].set_ylabel("RMS CIEDE2000 at the sample geometries")
    axes[1].set_title("Fig. 2.5: basis error (eq 2.3.4)", fontsize=9)
    axes[1].legend(fontsize=8)
    path = out_dir / "ch2-basis.png"
    fig.savefig(path, dpi=85)
    plt.close(fig)
    return Figure("2.4–2.5", path, "Exponents per lobe count (log scale) and the max / mean fit error.")


DIVERGENCE = (
    "the search is local (greedy forward selection, each start polished by Nelder–Mead run to convergence "
    "and restarted until a restart gains nothing, so its answer no longer depends on the evaluation "
    "cap); the shipped table was made by a search capped at a fixed number of evaluations per start "
    "(docs/render-fit.md), so from 5 lobes on its bases are where that budget ran out: converged, the "
    "search reproduces the shipped f for 1–4 lobes and finds lower ones for 5 (9.061 against 9.803) and "
    "6 lobes (7.040 against 7.294), identical with caps of 4000 and 10000 evaluations per start"
)


def _monotone(rows: Sequence[bs.BasisRow]) -> list[Quantity]:
    rises_max = sum(1 for a, b in itertools.pairwise(rows) if b.max_error > a.max_error + 0.01)
    rises_mean = sum(1 for a, b in itertools.pairwise(rows) if b.mean_error > a.mean_error + 0.01)
    span = float(np.log10(max(rows[-1].exponents) / min(rows[-1].exponents)))
    out = [
        Quantity(
            "2.5",
            "lobe counts where the max error rises (> 0.01)",
            "count",
            0,
            rises_max,
            0,
            source="§2.3.2 'as more basis functions are added, the max error should decrease'",
            reason="with a max in f(E) the search may trade the max for the mean",
        ),
        Quantity(
            "2.5",
            "lobe counts where the mean error rises (> 0.01)",
            "count",
            0,
            rises_mean,
            0,
            source="§2.3.2 'along with the average error'",
            reason="with a max in f(E) the search may trade the mean for the max",
        ),
    ]
    if len(rows) >= 5:
        out.append(
            Quantity(
                "2.4",
                f"decades spanned by the {rows[-1].lobes}-lobe exponents",
                "decades",
                3.0,
                span,
                1.0,
                mode="at_least",
                source="Fig. 2.4: exponents 'distributed somewhat regularly in log space' "
                "from diffuse-like to glossy (read as ≥ 2 decades)",
                reason="the design database's gloss range sets the top exponent",
            )
        )
    return out


def basis_quick(out_dir: Path | None) -> ExperimentResult:
    """1–2 lobes regenerated against the shipped table (the fast case the tests run)."""
    t0 = time.perf_counter()
    rows = regenerate(2)
    quantities = tuple(_compare(rows, DIVERGENCE) + _monotone(rows))
    notes = "; ".join(
        f"{r.lobes}: E = {', '.join(f'{e:.4g}' for e in r.exponents)} (f {r.objective:.3f})" for r in rows
    )
    return ExperimentResult("ch2-basis-quick", quantities, (), notes, time.perf_counter() - t0)


def basis_table(out_dir: Path | None) -> ExperimentResult:
    """The full 1–11 lobe search (minutes), against the shipped table and the thesis's claims."""
    t0 = time.perf_counter()
    rows = regenerate(MAX_LOBES)
    quantities = tuple(_compare(rows, DIVERGENCE) + _monotone(rows))
    figures = (_plot(out_dir, rows),) if out_dir is not None else ()
    table = "\n".join(
        f"| {r.lobes} | {', '.join(f'{e:.4g}' for e in r.exponents)} | {r.max_error:.3f} | {r.mean_error:.3f} "
        f"| {r.objective:.3f} |"
        for r in rows
    )
    notes = (
        "Regenerated (deterministic; BLAS held to one thread):\n\n| lobes | exponents | max | mean | f |\n"
        "|---|---|---|---|---|\n" + table
    )
    return ExperimentResult("ch2-basis", quantities, figures, notes, time.perf_counter() - t0)


#: "Real-time rates" for one fit: one 30 Hz frame, in ms.
REAL_TIME_MS = 1000.0 / 30.0


def fit_comparison(designs: int | None = None) -> dict[str, tuple[float, float, float]]:
    """{method: (mean error, max error, ms per design)} over the design database (first *designs*)."""
    ds = design_database()[:designs]
    brdfs = [lf.designed_brdf(d) for d in ds]
    out = {}
    for method in ("nnls", "lp-l1", "clamped-lsq"):
        t = time.perf_counter()
        rep = lf.fit_designs(ds, None, method)
        ms = 1e3 * (time.perf_counter() - t) / len(ds)
        err = lf.fit_error_de(brdfs, rep)
        out[method] = (float(np.mean(err)), float(np.max(err)), ms)
    return out


def fit_methods(out_dir: Path | None) -> ExperimentResult:
    """§2.4: the thesis's LP, our NNLS and the clamped least squares it rejected, on the design database."""
    t0 = time.perf_counter()
    r = fit_comparison()
    nnls, lp, clamped = r["nnls"], r["lp-l1"], r["clamped-lsq"]
    quantities = (
        Quantity(
            "§2.4",
            "clamped LSQ / NNLS mean error",
            "ratio",
            1.0,
            clamped[0] / nnls[0],
            0.0,
            mode="at_least",
            source="§2.4: clamping least-squares weights at zero is rejected for poor fits",
        ),
        Quantity(
            "§2.4",
            "NNLS (ours) mean error against the thesis's LP",
            "ΔE00",
            lp[0],
            nnls[0],
            0.0,
            mode="at_most",
            source="the LP (L1) fit of §2.4, run on our code",
            reference="LP on our code",
        ),
        Quantity(
            "§2.4",
            "LP fit time per design",
            "ms",
            REAL_TIME_MS,
            lp[2],
            0.0,
            mode="at_most",
            source="§2.4 'solved at real-time rates' (one 30 Hz frame)",
            reason="HiGHS on the full sample matrix takes longer than a frame here; the product fits with "
            "NNLS, the same non-negative weights under the L2 norm",
        ),
        Quantity(
            "§2.4",
            "NNLS fit time per design",
            "ms",
            REAL_TIME_MS,
            nnls[2],
            0.0,
            mode="at_most",
            source="§2.4 'real-time rates'",
        ),
    )
    notes = "Mean / max RMS CIEDE2000 over the design database, ms per design: " + "; ".join(
        f"{m} {v[0]:.2f} / {v[1]:.2f}, {v[2]:.2f} ms" for m, v in r.items()
    )
    return ExperimentResult("ch2-fit-methods", quantities, (), notes, time.perf_counter() - t0)
