"""A ranked recipe option as ``RecipeOption.to_dict`` gives it to the fronts, for the recipe-table tests
of the CLI and the viewer: *grams* of the colorants in a *batch_g* batch on a *resolution_g* scale."""

from __future__ import annotations

from typing import Any


def recipe_option(batch_g: float, resolution_g: float, grams: dict[str, float]) -> dict[str, Any]:
    """One formulable option, rank 1, of the solid line (ΔE00 0.4 after rounding, 0.3 before)."""
    return {
        "rank": 1,
        "line": "solid",
        "grams": grams,
        "binder_g": batch_g - sum(grams.values()),
        "batch_g": batch_g,
        "scale_resolution_g": resolution_g,
        "mean_de": 0.4,
        "mean_de_unrounded": 0.3,
        "metamerism_index": None,
        "colorants": len(grams),
        "cost_per_kg": 12.0,
        "formulable": True,
    }
