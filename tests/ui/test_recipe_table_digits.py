"""The side-by-side recipe table shows grams per kg to the scale's resolution expressed per kg."""

from __future__ import annotations

from typing import Any

import pytest

from tests.recipe_option import recipe_option
from ui.models.formulation_tables import column_from_option, recipe_table


def _option(batch_g: float, resolution_g: float, grams: dict[str, float]) -> dict[str, Any]:
    return recipe_option(batch_g, resolution_g, grams)


@pytest.mark.parametrize(
    ("batch_g", "resolution_g", "grams", "shown"),
    [
        # 0.1 g in a 2 kg batch is 0.05 g/kg: one decimal would show 0.1 (twice the amount)
        (2000.0, 0.1, {"red": 0.1, "white": 40.3}, ["0.05", "20.15"]),
        # 0.1 g in a 500 g batch is 0.2 g/kg: one decimal is exact
        (500.0, 0.1, {"red": 0.1, "white": 40.3}, ["0.2", "80.6"]),
        # 1 g in a 4 kg batch is 0.25 g/kg
        (4000.0, 1.0, {"red": 1.0}, ["0.25"]),
    ],
)
def test_amounts_per_kg_keep_every_weighed_step(
    batch_g: float, resolution_g: float, grams: dict[str, float], shown: list[str]
) -> None:
    labels, cells = recipe_table([column_from_option(_option(batch_g, resolution_g, grams))])
    by_label = dict(zip(labels, (row[0] for row in cells), strict=True))
    assert sorted(by_label[f"{n} (g/kg)"] for n in grams) == sorted(shown)
