"""What the chemist asks of a recipe: toner line, colorant count, scale, batch, recipes to compare
(:class:`FormulationOptions`), each field checked by :func:`formulation_options`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.formulate.batch import DEFAULT_BATCH_G, MAX_BATCH_G
from station.formulate.errors import FormulateInputError
from station.formulate.lines import toner_line
from station.model.domain import (
    DEFAULT_MAX_COLORANTS,
    DEFAULT_RECIPE_COUNT,
    DEFAULT_SCALE_RESOLUTION_G,
    MAX_COLORANTS_RANGE,
    METAMERISM_TEST_ILLUMINANTS,
    RECIPE_COUNT_RANGE,
    SCALE_RESOLUTION_RANGE_G,
)

__all__ = ["MAX_STARTS", "FormulationOptions", "formulation_options"]

#: Starting recipes fitted at most per toner line (library matches first, then generic starts).
MAX_STARTS = 4


@dataclass(frozen=True)
class FormulationOptions:
    """What the chemist asks of a recipe (validated by :func:`formulation_options`)."""

    line: str | None = None
    paint_type: str | None = None
    max_colorants: int = DEFAULT_MAX_COLORANTS
    scale_resolution_g: float = DEFAULT_SCALE_RESOLUTION_G
    batch_g: float = DEFAULT_BATCH_G
    recipes: int = DEFAULT_RECIPE_COUNT
    illuminants: tuple[str, ...] = METAMERISM_TEST_ILLUMINANTS
    max_starts: int = MAX_STARTS


def _is_integer(value: object) -> bool:
    """True for an int that is not a bool (``True`` is an int to Python, not a count to a chemist)."""
    return isinstance(value, int) and not isinstance(value, bool)


def formulation_options(o: FormulationOptions) -> FormulationOptions:
    """*o*, each field checked (a :class:`FormulateInputError` naming the field and its accepted range)."""
    lo, hi = MAX_COLORANTS_RANGE
    if not _is_integer(o.max_colorants) or not lo <= o.max_colorants <= hi:
        raise FormulateInputError("max_colorants", f"an integer in [{lo}, {hi}]", o.max_colorants)
    lo_r, hi_r = SCALE_RESOLUTION_RANGE_G
    if not (np.isfinite(o.scale_resolution_g) and lo_r <= o.scale_resolution_g <= hi_r):
        raise FormulateInputError(
            "scale_resolution_g", f"{lo_r:g} <= scale_resolution_g <= {hi_r:g} g", o.scale_resolution_g
        )
    if not (
        np.isfinite(o.batch_g) and 0 < o.batch_g <= MAX_BATCH_G and o.batch_g >= 10 * o.scale_resolution_g
    ):
        raise FormulateInputError(
            "batch_g", f"10 × the scale resolution <= batch_g <= {MAX_BATCH_G:g} g", o.batch_g
        )
    lo, hi = RECIPE_COUNT_RANGE
    if not _is_integer(o.recipes) or not lo <= o.recipes <= hi:
        raise FormulateInputError("recipes", f"an integer in [{lo}, {hi}]", o.recipes)
    if not _is_integer(o.max_starts) or not 1 <= o.max_starts <= 50:
        raise FormulateInputError("max_starts", "an integer in [1, 50]", o.max_starts)
    if o.line is not None:
        toner_line(o.line)
    return o
