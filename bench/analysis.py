"""Benchmarks of the misalignment analysis (issue 6 bars) and the docs figures.

Run: ``.venv/bin/python -m bench.analysis``. Bars: one index evaluation ≤ 1 ms; the Fig. 4.3 sweep ≤ 1 s;
one inverse trompe l'oeil solve ≤ 1 s. Baseline in the same run: a plain 1e-3° scan for the first
crossing (what the bracket + Brent replaces). Writes docs/misalignment-index.png (Fig. 4.3),
docs/misalignment-fig44.png (Fig. 4.4 grid), docs/misalignment-fig45.png (Fig. 4.5 contour) and
docs/misalignment-qa.png (QA report example).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bench._report import Case, write_section
from station.analysis import Environment, goniogeometric_index
from station.analysis.picture import SOLID_GRID_COLUMNS, draw_solid_grid, plot_seam_report
from station.analysis.qa import seam_qa
from station.analysis.scenarios import BUMPER_PAINT, SILVER_PAINT, SOLID_LIGHTS_DEG, SOLID_PAINT, solid_panels
from station.analysis.seam_model import SeamModel
from station.analysis.sweep import SweepResult, plot_sweep, seam_sweep
from station.analysis.trompe import inverse_trompe_loeil
from station.model import FaceFlopTravelGloss

DOCS = Path(__file__).resolve().parents[1] / "docs"


def timeit(fn: Callable[[], object], repeat: int = 30, warm: int = 2) -> float:
    """Median wall time of *fn* in seconds."""
    for _ in range(warm):
        fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def plain_scan(
    paint: FaceFlopTravelGloss, light: float, view: float, sign: float, eps: float = 2.3
) -> float | None:
    """Baseline: first crossing on a 1e-3° grid (0 … 30°)."""
    m = SeamModel([light], [view])
    betas = np.arange(0.0, 30.0005, 1e-3)
    de = m.delta_e(paint, paint, sign * betas)[0]
    hit = np.nonzero(de >= eps)[0]
    return float(betas[hit[0]]) if hit.size else None


def fig44_grid(path: Path) -> Path:
    """Fig. 4.4 style grid: rows = light angles, columns = identical / 45°-opt / RMS / per-row paint."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(SOLID_LIGHTS_DEG), len(SOLID_GRID_COLUMNS), figsize=(9, 9))
    draw_solid_grid(axes, SOLID_PAINT, solid_panels(), SOLID_LIGHTS_DEG, -3.0, (40, 80))
    fig.suptitle("Fig. 4.4 reproduced: solid, panels misaligned 3°, seam ΔE*ab under each")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def fig45_contour(path: Path) -> Path:
    """Fig. 4.5 style: RMS seam ΔE against Δ face L* and Δ travel for the silver, minimum marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from station.analysis.scenarios import INSTRUMENT_ASPECULAR, SILVER_BETA_DEG, silver_black_flop

    ls, vs = [45.0] * len(INSTRUMENT_ASPECULAR), [a - 45.0 for a in INSTRUMENT_ASPECULAR]
    m = SeamModel(ls, vs)
    dls = np.linspace(-5.0, 30.0, 57)
    dts = np.linspace(-3.0, 8.0, 45)
    z = np.empty((len(dts), len(dls)))
    for i, dt in enumerate(dts):
        for j, dl in enumerate(dls):
            p = SILVER_PAINT.replace(
                face=(SILVER_PAINT.face[0] + dl, 0.0, 0.0), travel_deg=SILVER_PAINT.travel_deg + dt
            )
            z[i, j] = np.sqrt(np.mean(m.delta_e(SILVER_PAINT, p, np.array([SILVER_BETA_DEG]))[:, 0] ** 2))
    r = silver_black_flop()
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    cs = ax.contourf(dls, dts, z, levels=np.linspace(0.0, z.max(), 25), cmap="viridis")
    fig.colorbar(cs, label="RMS seam ΔE*ab")
    ax.plot([0.0], [0.0], "wo", label=f"A: identical paint, ΔE {r.rms_before:.2f}")
    ax.plot(
        [r.changes["face_L"]],
        [r.changes["travel_deg"]],
        "r*",
        ms=12,
        label=f"B: Δface L {r.changes['face_L']:+.1f}, Δtravel {r.changes['travel_deg']:+.1f}°, "
        f"ΔE {r.rms_after:.2f}",
    )
    ax.plot([3.4], [2.0], "w^", label="thesis minimum: +3.4, +2.0°")
    ax.set_xlabel("Δ face L*")
    ax.set_ylabel("Δ travel (degrees)")
    ax.set_title("Fig. 4.5 reproduced: silver, black flop, 2° in-plane misalignment", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def main() -> None:
    cases = [*_index_cases(), _sweep_case(), *_trompe_cases()]
    t = timeit(lambda: seam_qa(BUMPER_PAINT, BUMPER_PAINT.replace(face=(61.0, -4.0, -41.0)), -3.0), repeat=3)
    cases.append(Case("QA workflow (seam_qa, no PNG)", "3 lights × 4 aspecular", t * 1e3, "ms"))

    report = seam_qa(BUMPER_PAINT, BUMPER_PAINT.replace(face=(61.0, -4.0, -41.0)), -3.0)
    plot_seam_report(report, DOCS / "misalignment-qa.png")
    fig44_grid(DOCS / "misalignment-fig44.png")
    fig45_contour(DOCS / "misalignment-fig45.png")
    write_section(
        "analysis",
        "Misalignment analysis (goniogeometric index, inverse trompe l'oeil)",
        cases,
        "Figures: docs/misalignment-index.png, docs/misalignment-fig44.png, docs/misalignment-fig45.png, "
        "docs/misalignment-qa.png.",
    )


def _index_cases() -> list[Case]:
    """The goniogeometric index against the plain 1e-3° scan (the baseline, timed first)."""
    grey = FaceFlopTravelGloss((60.0, 0.0, 0.0), (60.0, 0.0, 0.0), None)
    cases: list[Case] = []
    base = timeit(lambda: plain_scan(grey, 45.0, 0.0, 1.0), repeat=10)
    cases.append(Case("baseline: plain 1e-3° scan, solid", "30001 β", base * 1e3, "ms"))
    t = timeit(lambda: goniogeometric_index(grey, 45.0, 0.0, direction="+"))
    cases.append(
        Case(
            "index: solid, point light, one direction",
            "1 geometry",
            t * 1e3,
            "ms",
            f"bar ≤ 1 ms; {base / t:.0f}× faster than the scan",
        )
    )
    t = timeit(lambda: goniogeometric_index(BUMPER_PAINT, 45.0, -30.0))
    cases.append(Case("index: effect paint, either direction", "1 geometry", t * 1e3, "ms", "bar ≤ 1 ms"))
    t = timeit(lambda: goniogeometric_index(BUMPER_PAINT, 45.0, -30.0, method="cie2000"), repeat=10)
    cases.append(Case("index: effect paint, CIEDE2000", "1 geometry", t * 1e3, "ms"))
    t = timeit(lambda: goniogeometric_index(BUMPER_PAINT, 45.0, -30.0, hinge="out-of-plane"))
    cases.append(Case("index: effect paint, out-of-plane hinge", "1 geometry", t * 1e3, "ms"))
    t = timeit(lambda: goniogeometric_index(BUMPER_PAINT, list(SOLID_LIGHTS_DEG)), repeat=5)
    cases.append(Case("index over a range (6 lights × aspecular 15–110°)", "≈110 geometries", t * 1e3, "ms"))
    env = Environment.from_equirect(np.random.default_rng(0).uniform(0.2, 1.0, (16, 32, 3)))
    t = timeit(lambda: goniogeometric_index(BUMPER_PAINT, env, -10.0), repeat=5)
    cases.append(Case("index: environment (16×32 equirect)", "512 samples", t * 1e3, "ms"))
    return cases


def _sweep_case() -> Case:
    """The Fig. 4.3 sweep, timed, then drawn to docs/misalignment-index.png."""

    def fig_4_3_sweep() -> SweepResult:
        return seam_sweep(
            BUMPER_PAINT,
            betas_deg=(0.25, 0.5, 1.0, 2.0, 3.0, 5.0),
            lights_deg=tuple(range(15, 86, 5)),
            views_deg=tuple(np.arange(-30.0, 66.0, 1.0)),
        )

    t = timeit(fig_4_3_sweep, repeat=10)
    case = Case("Fig. 4.3 sweep", "6 β × 15 lights × 96 views", t * 1e3, "ms", "bar ≤ 1 s")
    plot_sweep(
        fig_4_3_sweep(),
        DOCS / "misalignment-index.png",
        view_for_lights=0.0,
        title="Seam ΔE*ab against view, light and misalignment, blue metallic (thesis Fig. 4.3)",
    )
    return case


def _trompe_cases() -> list[Case]:
    """Inverse trompe l'oeil solves: the solid, the silver and the metallic."""
    cases: list[Case] = []
    lights = list(SOLID_LIGHTS_DEG)
    t = timeit(lambda: inverse_trompe_loeil(SOLID_PAINT, lights, beta_deg=-3.0, objective="rms"), repeat=5)
    cases.append(Case("trompe l'oeil: solid, RMS", "6 geometries, 3 params", t * 1e3, "ms", "bar ≤ 1 s"))
    t = timeit(
        lambda: inverse_trompe_loeil(SOLID_PAINT, lights, beta_deg=-3.0, objective="minimax"), repeat=5
    )
    cases.append(Case("trompe l'oeil: solid, minimax", "6 geometries, 3 params", t * 1e3, "ms", "bar ≤ 1 s"))
    asp = (15.0, 25.0, 45.0, 75.0, 110.0)
    ls, vs = [45.0] * 5, [a - 45.0 for a in asp]
    t = timeit(
        lambda: inverse_trompe_loeil(SILVER_PAINT, ls, vs, beta_deg=-2.0, subset="face_L+travel"), repeat=5
    )
    cases.append(
        Case(
            "trompe l'oeil: silver, face L + travel, RMS",
            "5 geometries, 2 params",
            t * 1e3,
            "ms",
            "bar ≤ 1 s",
        )
    )
    t = timeit(lambda: inverse_trompe_loeil(BUMPER_PAINT, ls, vs, beta_deg=-8.0, subset="full"), repeat=5)
    cases.append(
        Case("trompe l'oeil: metallic, full FFTG, RMS", "5 geometries, 7 params", t * 1e3, "ms", "bar ≤ 1 s")
    )
    t = timeit(
        lambda: inverse_trompe_loeil(BUMPER_PAINT, ls, vs, beta_deg=-8.0, subset="full", objective="minimax"),
        repeat=5,
    )
    cases.append(
        Case(
            "trompe l'oeil: metallic, full FFTG, minimax",
            "5 geometries, 7 params",
            t * 1e3,
            "ms",
            "bar ≤ 1 s",
        )
    )
    return cases


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "analysis")
    main()
