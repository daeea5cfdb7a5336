"""Thesis chapter 2, §2.5.3: the anisotropic reconstruction against off-specular samples (Fig. 2.10) and
the lobe renderer's frame rates.

:func:`fig210` compares the reconstruction with a brute-force integral of eq 2.5.4 and the product's
accuracy bar (``bench/anisotropy.py`` charts the same sweep); :func:`frame_rates` times the lobe
renderer at 5 / 9 / 31 / 81 samples as ratios to the 5-sample rate beside the thesis's 35 / 27 / 7 / 3 Hz
(absolute rates belong to the machine). The basis and fit experiments of the chapter: :mod:`station.reproduce.ch2`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from station.reproduce.core import ExperimentResult, Figure, Quantity

if TYPE_CHECKING:
    from station.render.anisotropy import SampleSweep, WardLobe

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
