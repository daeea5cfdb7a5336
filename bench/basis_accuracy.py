"""Lobe basis against ground truth: CIEDE2000 over the design database in two environments (issue 3 bar).

Run: ``.venv/bin/python -m bench.basis_accuracy``. For the shipped bases with 1..11 lobes:

* every design of :mod:`station.render.design_db` is fitted (default method) and shaded on a sphere
  (orthographic, 32×32 pixels, rim excluded) in the procedural booth and sunny-sky environments;
* ground truth: :class:`station.render.truth.TruthScene` integrates the designed BRDF itself;
* "exact": the lobe model of eqs 2.3.1–2.3.3 integrated the same way (the cost of the lobe fit);
* "prefiltered": the lobe model as the renderers evaluate it (eqs 2.5.1–2.5.3: (R·N) for (L·N),
  lobes not clipped at the horizon), i.e. what a perfect GL/NumPy renderer shows;
* "prefiltered-lut": the same single lookups per lobe, (R·N) replaced by the horizon factors
  g(E, R·N), h(E, R·N) of :func:`station.render.lobes.horizon_factors` (exact for constant light);
* ΔE: CIEDE2000 per pixel, Lab relative to one white per scene: the brightest white-Lambertian pixel
  (a viewer adapts to the scene, not pixel by pixel);
* frame-time proxy: blending cached per-lobe basis images at 1024×1024 (2m + 1 RGB float32 images;
  a paint edit's cost grows with the lobe count the same way a full render's texture lookups do).

Bars: default basis, mean ΔE ≤ 1.0 and 95th percentile ≤ 2.3 in both environments.
"""

from __future__ import annotations

import json
import time

import numpy as np

from bench._report import ROOT, Case, write_section
from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.render import lobe_fit as lf
from station.render import truth as tr
from station.render.design_db import design_database
from station.render.lobes import LobeBasis, basis_table, default_basis

SPHERE = 32
ENVIRONMENTS = ("booth", "sky")
MEAN_BAR, P95_BAR = 1.0, 2.3
MODES = tr.LOBE_MODES


def environment(name: str):
    """The renderer's procedural environment at 512×256."""
    from station.render.procedural import procedural_environment

    return procedural_environment(name, 512)


def scene_errors(
    scene: tr.TruthScene, brdfs: list[lf.DesignedBRDF], basis: LobeBasis
) -> dict[str, np.ndarray]:
    """ΔE00 per design and pixel, (d, P), for the exact and prefiltered lobe models against truth."""
    white = float(scene.white()[..., 1].max())
    rep = lf.fit_targets(lf.targets_from_brdfs(brdfs), basis)
    out: dict[str, list[np.ndarray]] = {mode: [] for mode in MODES}
    for i, brdf in enumerate(brdfs):
        ref = linear_srgb_to_lab(scene.truth(brdf) / white)
        w = rep.weights(i)
        for mode in out:
            out[mode].append(delta_e(ref, linear_srgb_to_lab(scene.lobes(w, mode) / white), "cie2000"))
    return {k: np.stack(v) for k, v in out.items()}


def blend_seconds(m: int, size: int = 1024, repeats: int = 9) -> float:
    """Fastest of *repeats* blends of 2m + 1 cached RGB float32 basis images at size² (paint-edit proxy).

    The minimum, not the median: the machine is shared and the blend is memory-bound, so the fastest
    run is the one least disturbed by other jobs.
    """
    rng = np.random.default_rng(0)
    imgs = rng.random((2 * m + 1, size * size * 3), dtype=np.float32)
    w = rng.random(2 * m + 1).astype(np.float32)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        w @ imgs
        times.append(time.perf_counter() - t0)
    return float(np.min(times))


def blend_table(counts: list[int], size: int = 1024, rounds: int = 15) -> dict[int, float]:
    """Blend seconds per lobe count, rounds interleaved over the counts, fastest round of each.

    Interleaving spreads other jobs' memory traffic over every count alike, so the trend survives it.
    """
    rng = np.random.default_rng(0)
    imgs = rng.random((2 * max(counts) + 1, size * size * 3), dtype=np.float32)
    best = {m: np.inf for m in counts}
    for _ in range(rounds):
        for m in counts:
            w = np.ones(2 * m + 1, dtype=np.float32)
            t0 = time.perf_counter()
            w @ imgs[: 2 * m + 1]
            best[m] = min(best[m], time.perf_counter() - t0)
    return best


def chart(rows: list[dict[str, float]], path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), dpi=110)
    m = [r["lobes"] for r in rows]
    ms = [r["frame_ms"] for r in rows]
    for env, colour in zip(ENVIRONMENTS, ("tab:blue", "tab:orange"), strict=True):
        for mode, ls in zip(MODES, ("-", "--", ":", "-.", (0, (1, 1))), strict=True):
            mean = [r[f"{env}/{mode}/mean"] for r in rows]
            p95 = [r[f"{env}/{mode}/p95"] for r in rows]
            axes[0].plot(m, mean, linestyle=ls, color=colour, marker="o", ms=3, label=f"{env} {mode} mean")
            axes[0].plot(
                m, p95, linestyle=ls, color=colour, marker="^", ms=3, alpha=0.5, label=f"{env} {mode} p95"
            )
            axes[1].plot(ms, mean, linestyle=ls, color=colour, marker="o", ms=3)
    for ax in axes:
        ax.axhline(MEAN_BAR, color="grey", lw=0.8)
        ax.axhline(P95_BAR, color="grey", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylabel("CIEDE2000 against ground truth")
    axes[0].set_xlabel("lobes m")
    axes[1].set_xlabel("paint-edit frame time proxy at 1024² (ms, blend of 2m+1 basis images)")
    axes[0].legend(fontsize=6, ncol=2)
    axes[0].set_title("error against lobe count")
    axes[1].set_title("mean error against frame time")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def replot() -> None:
    """Re-measure the frame proxy and redraw the chart from docs/render-basis-accuracy.json (no truth)."""
    path = ROOT / "docs" / "render-basis-accuracy.json"
    rows = json.loads(path.read_text())
    frames = blend_table([int(r["lobes"]) for r in rows])
    for r in rows:
        r["frame_ms"] = frames[int(r["lobes"])] * 1e3
    path.write_text(json.dumps(rows, indent=1) + "\n")
    chart(rows, ROOT / "docs" / "render-basis-accuracy.png")
    print("\n".join(f"{int(r['lobes']):2d} lobes  frame proxy {r['frame_ms']:.2f} ms" for r in rows))


def main() -> None:
    import sys

    if "--replot" in sys.argv:
        replot()
        return
    designs = design_database()
    brdfs = [lf.designed_brdf(d) for d in designs]
    normals, views = tr.sphere_pixels(SPHERE)
    table = basis_table()
    bases = [(int(r["lobes"]), LobeBasis(tuple(r["exponents"]))) for r in table["bases"]]
    scenes = {}
    cases: list[Case] = []
    for env in ENVIRONMENTS:
        t0 = time.perf_counter()
        scenes[env] = tr.TruthScene(environment(env), normals, views)
        cases.append(
            Case(f"truth scene {env}: integrals", f"{normals.shape[0]} px", time.perf_counter() - t0, "s")
        )
    rows: list[dict[str, float]] = []
    default_m = default_basis().size
    frames = blend_table([m for m, _ in bases])
    for m, basis in bases:
        row: dict[str, float] = {"lobes": m, "frame_ms": frames[m] * 1e3}
        for env, scene in scenes.items():
            errs = scene_errors(scene, brdfs, basis)
            for mode, e in errs.items():
                row[f"{env}/{mode}/mean"] = float(e.mean())
                row[f"{env}/{mode}/p95"] = float(np.percentile(e, 95))
                row[f"{env}/{mode}/worst_design"] = float(e.mean(axis=1).max())
        rows.append(row)
        print(
            f"{m:2d} lobes  "
            + "  ".join(f"{k} {v:.3f}" for k, v in row.items() if k.endswith(("mean", "p95")))
        )
    for row in rows:
        if row["lobes"] != default_m:
            continue
        for env in ENVIRONMENTS:
            for mode in MODES:
                mean, p95 = row[f"{env}/{mode}/mean"], row[f"{env}/{mode}/p95"]
                ok = "meets" if mean <= MEAN_BAR and p95 <= P95_BAR else "MISSES"
                cases += [
                    Case(
                        f"default {m_str(default_m)} {env} {mode}: mean",
                        f"{len(designs)} designs",
                        mean,
                        "ΔE00",
                        f"{ok} bar (≤ {MEAN_BAR}, p95 ≤ {P95_BAR})",
                    ),
                    Case(
                        f"default {m_str(default_m)} {env} {mode}: p95", f"{normals.shape[0]} px", p95, "ΔE00"
                    ),
                ]
    (ROOT / "docs" / "render-basis-accuracy.json").write_text(json.dumps(rows, indent=1) + "\n")
    png = ROOT / "docs" / "render-basis-accuracy.png"
    chart(rows, png)
    header = (
        "| lobes | frame proxy ms | "
        + " | ".join(f"{env} {mode} mean / p95" for env in ENVIRONMENTS for mode in MODES)
        + " |"
    )
    lines = [header, "|" + "---|" * (2 + len(MODES) * len(ENVIRONMENTS))]
    for r in rows:
        cells = " | ".join(
            f"{r[f'{env}/{mode}/mean']:.2f} / {r[f'{env}/{mode}/p95']:.2f}"
            for env in ENVIRONMENTS
            for mode in MODES
        )
        lines.append(f"| {r['lobes']} | {r['frame_ms']:.2f} | {cells} |")
    extra = (
        "Error against lobe count and frame time: `docs/render-basis-accuracy.png`.\n\n"
        + "\n".join(lines)
        + "\n\n*exact*: lobe model integrated like the truth (cost of the fit alone); *prefiltered*: the "
        "renderers' evaluation (eqs 2.5.1–2.5.3); *prefiltered-lut*: the same lookups with the "
        "per-lobe horizon factors of `station.render.lobes.horizon_factors` instead of R·N."
    )
    write_section("basis_accuracy", "Lobe basis against ground truth (booth, sky)", cases, extra)


def m_str(m: int) -> str:
    return f"{m} lobes"


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "basis_accuracy")
    main()
