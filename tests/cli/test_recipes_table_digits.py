"""``station formulate``'s side-by-side recipes show every amount the scale can weigh."""

from __future__ import annotations

from typing import Any

import pytest

from station.cli.formulate import recipes_table
from tests.recipe_option import recipe_option


def _recipe(resolution_g: float, grams: dict[str, float]) -> dict[str, Any]:
    return recipe_option(1000.0, resolution_g, grams)


@pytest.mark.parametrize(
    ("resolution_g", "grams", "shown"),
    [
        (0.25, {"red": 0.75}, "0.75"),  # a quarter-gram scale: 0.75 g, not 0.8
        (2.5, {"red": 7.5}, "7.5"),  # a 2.5 g step: 7.5 g, not 8
        (0.1, {"red": 12.3}, "12.3"),
    ],
)
def test_amounts_keep_the_scale_step(resolution_g: float, grams: dict[str, float], shown: str) -> None:
    lines = recipes_table([_recipe(resolution_g, grams)]).splitlines()
    (row,) = [line for line in lines if line.startswith("red (g)")]
    assert row.split()[-1] == shown
