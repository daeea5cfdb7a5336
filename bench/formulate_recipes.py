"""Figure of docs/formulate.md: the recipes a chemist is offered for the README silver, side by side.

Formulates the README silver (15/45/110°: 90,2,-5; 50,1,-3; 30,0.5,-1) with the default limits (toner
line from the design, at most 5 colorants, 0.1 g in a 1000 g batch, 3 recipes) and draws the grams of
each colorant per recipe with its ΔE00 after rounding, worst metamerism index (A, F11), colorants and
cost; writes docs/formulate-recipes.png and one line per recipe in docs/benchmarks.md.

Run: ``python -m bench.formulate_recipes`` (seconds).
"""

from __future__ import annotations

import time

import numpy as np

from bench._report import ROOT, Case, write_section
from station.formulate.formulation import formulate

A3 = (15.0, 45.0, 110.0)
README_SILVER = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])
FIGURE = ROOT / "docs" / "formulate-recipes.png"


def draw(result: object) -> None:
    """Grouped bars: grams per colorant, one group per recipe."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    recipes = result.recipes  # type: ignore[attr-defined]
    names = sorted({n for r in recipes for n in r.grams})
    fig, ax = plt.subplots(figsize=(7.2, 3.6), dpi=110)
    width = 0.8 / len(recipes)
    x = np.arange(len(names))
    for k, r in enumerate(recipes):
        mi = f"{r.worst_mi:.2f}" if r.metamerism else "n/a"
        label = f"#{r.rank}: ΔE00 {r.mean_de:.2f}, MI {mi}, {r.colorants} colorants, {r.cost_per_kg:.1f}/kg"
        ax.bar(
            x + (k - (len(recipes) - 1) / 2) * width, [r.grams.get(n, 0.0) for n in names], width, label=label
        )
    ax.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("g per 1000 g batch")
    ax.set_title("README silver: recipes side by side (SYNTHETIC colorants, 0.1 g scale)", fontsize=9)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    fig.savefig(FIGURE)
    plt.close(fig)


def run() -> None:
    t = time.perf_counter()
    result = formulate(README_SILVER, A3)
    elapsed = time.perf_counter() - t
    draw(result)
    cases = [
        Case(
            f"README silver recipe #{r.rank}",
            f"{r.colorants} colorants",
            r.mean_de,
            "ΔE00 rounded",
            f"unrounded {r.mean_de_unrounded:.2f}; MI A/F11 "
            + ("/".join(f"{v:.2f}" for v in r.metamerism.values()) if r.metamerism else "n/a")
            + f"; {r.cost_per_kg:.2f}/kg; line {r.line}",
        )
        for r in result.recipes
    ]
    cases.append(Case("README silver formulation time", "3 recipes", elapsed, "s"))
    write_section(
        "formulate-recipes",
        "Formulation: the README silver's recipes",
        cases,
        "![README silver recipes](formulate-recipes.png)\n",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "formulate_recipes")
    run()
