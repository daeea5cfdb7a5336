"""Thesis chapter 2: the shared basis exponents and their errors for 1–11 lobes (eq 2.3.4, Figs 2.4–2.5).

The thesis gives no numbers for Figs 2.4–2.5 ("the actual values are omitted, since the error was
measured at only a few angles"), so the regenerated search is compared with two things: the thesis's
qualitative claims (errors fall as lobes are added; exponents spread over decades) and our shipped table
(station/render/data/lobe_basis.json), regenerated from the design database by
:func:`station.render.basis_selection.select_bases`, which is deterministic run to run. The full 1–11
search takes minutes and runs from the command only; the tests run the 1–2 lobe case.

§2.5.3: the anisotropic reconstruction against off-specular samples (Fig. 2.10), against a brute-force
integral of eq 2.5.4 and the product's accuracy bar (:func:`fig210`; ``bench/anisotropy.py`` charts the
same sweep), and the lobe renderer's frame rates at 5 / 9 / 31 / 81 samples as ratios to the 5-sample
rate beside the thesis's 35 / 27 / 7 / 3 Hz (:func:`frame_rates`; absolute rates belong to the machine).
"""

from __future__ import annotations

import itertools
import json
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from station.render import basis_selection as bs
from station.render import lobe_fit as lf
from station.render.design_db import design_database
from station.render.lobes import MAX_LOBES
from station.reproduce.core import ExperimentResult, Figure, Quantity

if TYPE_CHECKING:
    from station.render.anisotropy import SampleSweep, WardLobe

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


# --- §2.5.3: anisotropic reconstruction against samples (Fig. 2.10) and frame rates --------------------

#: The product's accuracy bar against ground truth (mean and 95th-percentile CIEDE2000).
MEAN_BAR, P95_BAR = 1.0, 2.3
#: Sweep cases: (name, environment "booth" | "point", (α_x, α_y)); the last is Fig. 2.10's.
ANISO_CASES: tuple[tuple[str, str, tuple[float, float]], ...] = (
    ("mild, light booth", "booth", (0.05, 0.1)),
    ("strong, light booth", "booth", (0.03, 0.3)),
    ("strong, one point light (Fig. 2.10)", "point", (0.03, 0.3)),
)
#: Image size and truth cube face of the sweep (the bench and ``station reproduce`` use the same).
SWEEP_SIZE, SWEEP_TRUTH_FACE = 40, 48
#: Fig. 2.10's columns: 15, 35 and 81 samples, then the actual (brute-force) reflection.
FIG210_COUNTS = (15, 35, 81)
#: The thesis's frame rates of the lobe renderer (§2.5.3): samples → Hz (5 lobes + SH diffuse).
THESIS_HZ = {5: 35.0, 9: 27.0, 31: 7.0, 81: 3.0}
#: Relative tolerance of a frame-rate ratio (a 30 % miss differs).
RATE_TOLERANCE = 0.3
#: Interleaved timing rounds of the frame-rate experiment.
ROUNDS = 3


def anisotropy_sweeps(
    counts: tuple[int, ...] | None = None, size: int = SWEEP_SIZE, truth_face: int = SWEEP_TRUTH_FACE
) -> list[tuple[str, WardLobe, SampleSweep]]:
    """[(case name, WardLobe, SampleSweep)] for :data:`ANISO_CASES` (P_s = 0.8, direction along +x)."""
    from station.render import anisotropy as an
    from station.render import procedural

    counts = an.SWEEP_COUNTS if counts is None else counts
    out: list[tuple[str, WardLobe, SampleSweep]] = []
    for name, env_name, (ax, ay) in ANISO_CASES:
        env = procedural.light_booth(128) if env_name == "booth" else an.point_light_environment()
        lobe = an.WardLobe((0.8, 0.8, 0.8), ax, ay)
        keep = FIG210_COUNTS if env_name == "point" else ()
        out.append((name, lobe, an.sample_sweep(env, lobe, counts, size, truth_face, keep)))
    return out


def plot_anisotropy_samples(path: Path, sweeps: Sequence[tuple[str, WardLobe, SampleSweep]]) -> Path:
    """Mean and 95th-percentile ΔE00 against samples, the failure regions (above the bars) shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    for ax, attr, bar, label in (
        (axes[0], "mean_de", MEAN_BAR, "mean ΔE00"),
        (axes[1], "p95_de", P95_BAR, "95th-percentile ΔE00"),
    ):
        top = max(max(getattr(s, attr)) for _, _, s in sweeps) * 1.5
        bottom = min(min(getattr(s, attr)) for _, _, s in sweeps) / 1.5
        ax.axhspan(bar, max(top, bar * 1.5), color="C3", alpha=0.12, label=f"fails the bar (> {bar:g})")
        ax.axhline(bar, color="C3", lw=1)
        for k, (name, lobe, s) in enumerate(sweeps):
            ax.plot(
                s.samples,
                getattr(s, attr),
                "o-",
                ms=3.5,
                color=f"C{k}",
                label=f"{name}: α = {lobe.alpha_x:g} / {lobe.alpha_y:g}",
            )
        ax.set_xscale("log")
        ticks = [1, 3, 5, 9, 15, 31, 81]
        ax.set_xticks(ticks, [str(t) for t in ticks])
        ax.set_yscale("log")
        fmt = matplotlib.ticker.FuncFormatter(lambda v, _pos: f"{v:g}")
        ax.yaxis.set_major_formatter(fmt)
        ax.yaxis.set_minor_formatter(fmt)
        ax.tick_params(axis="y", which="minor", labelsize=7)
        ax.set_ylim(min(bottom, bar / 2), max(top, bar * 1.5))
        ax.set_xlabel("off-specular samples J (eq 2.5.7)")
        ax.set_ylabel(f"{label} against brute-force eq 2.5.4")
        ax.set_title(f"Anisotropic Ward: {label} vs samples", fontsize=9)
        ax.legend(fontsize=7)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _plot_fig210(path: Path, sweep: object) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from station.render import tonemap

    imgs = [sweep.images[j] for j in FIG210_COUNTS] + [sweep.truth]  # type: ignore[attr-defined]
    titles = [f"{j} samples" for j in FIG210_COUNTS] + ["actual (brute force)"]
    fig, axes = plt.subplots(1, 4, figsize=(10, 2.9), constrained_layout=True)
    for ax, img, title in zip(axes, imgs, titles, strict=True):
        ax.imshow(tonemap.to_display(img))
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


FLOOR_REASON = (
    "the floor is eq 2.5.5's isotropic fit, not the sampling: the cosine-lobe blend is fitted to Ward's "
    "α_x lobe in plane at 45° incidence only (§2.5.3), and away from that geometry its shape differs from "
    "the lobe's; more samples do not move it (the curves are flat from ~11 samples on)"
)


def _fig210_quantities(sweeps: Sequence[tuple[str, object, object]]) -> list[Quantity]:
    out = []
    mild, strong = sweeps[0][2], sweeps[-1][2]
    out.append(
        Quantity(
            "2.10",
            "samples until the mean ΔE00 settles (within 0.1 of 81), mild anisotropy",
            "samples",
            9,
            mild.converged(),  # type: ignore[attr-defined]
            0,
            mode="at_most",
            source="§2.5.3 'on surfaces exhibiting mild anisotropy nine samples can be sufficient'",
            reason="fewer samples are needed at this anisotropy",
        )
    )
    out.append(
        Quantity(
            "2.10",
            "samples until the mean ΔE00 settles, α_y ≫ α_x, one point light",
            "samples",
            80,
            strong.converged(),  # type: ignore[attr-defined]
            40,
            source="§2.5.3 'on highly anisotropic surfaces with α_y ≫ α_x eighty samples or more may be "
            "necessary to avoid artifacts' (Fig. 2.10: 15, 35, 81 samples)",
            reason="ours settles with far fewer samples: the weighted sum is divided by Σ W_j (the thesis's "
            "eq 2.5.7 is not), so sparse samples leave no dark gaps, and the weights spread α_s = "
            "√(α_y² − α_x²) instead of α_y; the thesis judged 'artifacts' by eye",
        )
    )
    for name, _, s in sweeps:
        out.append(
            Quantity(
                "2.10",
                f"mean ΔE00 at 81 samples, {name}",
                "ΔE00",
                MEAN_BAR,
                s.mean_de[-1],  # type: ignore[attr-defined]
                0.0,
                mode="at_most",
                source="product accuracy bar against ground truth (the thesis shows images only)",
                reference="accuracy bar",
                reason=FLOOR_REASON,
            )
        )
        out.append(
            Quantity(
                "2.10",
                f"95th-percentile ΔE00 at 81 samples, {name}",
                "ΔE00",
                P95_BAR,
                s.p95_de[-1],  # type: ignore[attr-defined]
                0.0,
                mode="at_most",
                source="product accuracy bar against ground truth (the thesis shows images only)",
                reference="accuracy bar",
                reason=FLOOR_REASON,
            )
        )
    return out


def _sweep_notes(sweeps: Sequence[tuple[str, object, object]]) -> str:
    counts = sweeps[0][2].samples  # type: ignore[attr-defined]
    head = "| case | " + " | ".join(str(j) for j in counts) + " |\n|---|" + "---|" * len(counts) + "\n"
    rows = "".join(
        f"| {name} mean / p95 | "
        + " | ".join(f"{m:.2f} / {p:.1f}" for m, p in zip(s.mean_de, s.p95_de, strict=True))  # type: ignore[attr-defined]
        + " |\n"
        for name, _, s in sweeps
    )
    return (
        f"ΔE00 of eq 2.5.7 against brute-force eq 2.5.4 (sphere {SWEEP_SIZE}², truth cube "
        f"{SWEEP_TRUTH_FACE}², tone mapped):\n\n" + head + rows
    )


def fig210(out_dir: Path | None) -> ExperimentResult:
    """Fig. 2.10: the anisotropic reconstruction against sample count, against ground truth."""
    t0 = time.perf_counter()
    sweeps = anisotropy_sweeps()
    figures: tuple[Figure, ...] = ()
    if out_dir is not None:
        figures = (
            Figure(
                "2.10",
                _plot_fig210(out_dir / "ch2-fig2.10.png", sweeps[-1][2]),
                "One point light, α = 0.03 / 0.3: 15, 35, 81 samples and the brute-force reflection.",
            ),
            Figure(
                "2.10",
                plot_anisotropy_samples(out_dir / "ch2-anisotropy-samples.png", sweeps),
                "Mean and p95 ΔE00 against samples; shaded: fails the bar (mean ≤ 1.0, p95 ≤ 2.3).",
            ),
        )
    return ExperimentResult(
        "ch2-fig2.10",
        tuple(_fig210_quantities(sweeps)),
        figures,
        _sweep_notes(sweeps),
        time.perf_counter() - t0,
    )


def fig210_quick(out_dir: Path | None) -> ExperimentResult:
    """Fig. 2.10 on a coarse sweep (1, 5, 9, 15, 35, 81 samples; sphere 24², truth 32²)."""
    t0 = time.perf_counter()
    sweeps = anisotropy_sweeps((1, 5, 9, 15, 35, 81), size=24, truth_face=32)
    return ExperimentResult(
        "ch2-fig2.10-quick",
        tuple(_fig210_quantities(sweeps)),
        (),
        _sweep_notes(sweeps),
        time.perf_counter() - t0,
    )


def _load() -> str:
    import os

    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} / {five:.2f} / {fifteen:.2f} (1 / 5 / 15 min) on {os.cpu_count()} CPUs"


def _timed(frame: Callable[[int, int], None], counts: Sequence[int], min_seconds: float) -> dict[int, float]:
    """{count: best frames per second over ROUNDS interleaved rounds} of ``frame(count, frame index)``."""
    best = dict.fromkeys(counts, 0.0)
    for _ in range(ROUNDS):
        for j in counts:
            frames, t = 0, time.perf_counter()
            while time.perf_counter() - t < min_seconds / ROUNDS or frames < 2:
                frame(j, frames)
                frames += 1
            best[j] = max(best[j], frames / (time.perf_counter() - t))
    return best


def lobe_renderer_rates(
    counts: Sequence[int] = tuple(THESIS_HZ), size: int = 256, min_seconds: float = 1.5
) -> tuple[dict[int, float], str]:
    """({samples: frames per second}, renderer) of the anisotropic lobe renderer: the GL renderer at
    *size*², 5 lobes + SH diffuse as in §2.5.3, the camera orbiting (a new view every frame). The counts
    are timed in ROUNDS interleaved rounds of at least *min_seconds* / ROUNDS each, and each count keeps
    its best round, so a change of machine load during the run does not land on one count only.
    Without a GL context, the NumPy reference at size/4."""
    from station.model.anisotropy import Anisotropy
    from station.render import anisotropy as an
    from station.render import prefilter, procedural, shapes
    from station.render.camera import Camera
    from station.render.errors import GLUnavailableError
    from station.render.lobes import basis_for_count
    from station.render.weights import LobeWeights

    exps = basis_for_count(5).exponents
    env = procedural.light_booth(256)
    a = Anisotropy(0.03, 0.3)
    base = shapes.Scene("sphere").view_camera
    paint = LobeWeights(exps, np.full(3, 0.05), np.full((5, 3), 0.02), np.full(5, 0.5))

    def cam(k: int) -> Camera:
        ang = 0.05 * k
        eye = np.array(base.eye)
        r = np.hypot(eye[0], eye[2])
        return Camera((r * np.sin(ang), eye[1], r * np.cos(ang)), base.target, fov_deg=base.fov_deg)

    try:
        from station.render.gl_renderer import GLRenderer, create_gl_context

        ctx = create_gl_context()
    except GLUnavailableError:
        basis = prefilter.prefilter_basis(env, exps, engine="numpy")
        lobe = an.WardLobe.from_design(a, 0.5)

        def numpy_frame(j: int, k: int) -> None:
            an.render_anisotropic(shapes.Scene("sphere", camera=cam(k)), basis, lobe, j, size // 4, size // 4)

        return _timed(numpy_frame, counts, min_seconds), f"NumPy reference at {size // 4}² (no GL context)"
    try:
        basis = prefilter.prefilter_basis(env, exps, ctx=ctx)
        renderer = ctx.info["GL_RENDERER"]
        with GLRenderer(basis, size, size, ctx=ctx, diffuse="sh") as gl:

            def gl_frame(j: int, k: int) -> None:
                gl.render(shapes.Scene("sphere", camera=cam(k)), [paint], anisotropy=a, anisotropic_samples=j)

            for j in counts:
                gl_frame(j, 0)  # compile
            rates = _timed(gl_frame, counts, min_seconds)
    finally:
        ctx.release()
    return rates, f"GL ({renderer}) at {size}²"


def frame_rates(out_dir: Path | None) -> ExperimentResult:
    """§2.5.3: frame rates for 5 / 9 / 31 / 81 samples as ratios to the 5-sample rate, thesis beside ours."""
    t0 = time.perf_counter()
    load_before = _load()
    rates, renderer = lobe_renderer_rates()
    load = _load()
    quantities = []
    for j, hz in THESIS_HZ.items():
        if j == 5:
            continue
        ratio_t = hz / THESIS_HZ[5]
        quantities.append(
            Quantity(
                "§2.5.3",
                f"frame rate at {j} samples / at 5 samples",
                "ratio",
                ratio_t,
                rates[j] / rates[5],
                RATE_TOLERANCE * ratio_t,
                source=f"§2.5.3: 5 samples 35 Hz, {j} samples {hz:g} Hz (two GeForce 6800 Ultra, SLI)",
                reason="the thesis's GPU pays a fixed cost per frame (its 5 → 9 samples costs 23 %) that a "
                "software rasteriser does not: here the per-sample shading dominates, so the rate falls "
                "closer to 1/J; " + load,
            )
        )
    notes = (
        f"{renderer}; "
        + "; ".join(f"{j} samples {r:.2f} fps" for j, r in rates.items())
        + f" (thesis: {', '.join(f'{j}: {hz:g} Hz' for j, hz in THESIS_HZ.items())}). Before: {load_before}; "
        f"after: {load}. Absolute rates depend on the machine; the verdict compares ratios."
    )
    return ExperimentResult("ch2-frame-rates", tuple(quantities), (), notes, time.perf_counter() - t0)
