"""Colorant selection: toner lines, at most N colorants, amounts on the scale, ranking, determinism."""

from __future__ import annotations

import sys

import colour
import numpy as np
import pytest

from station.formulate.colorants import EFFECT_FAMILIES, default_database, predict_lab
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import formulate
from station.formulate.lines import cost_per_kg, lines_for_design, toner_line
from station.formulate.selection import RANK_DE_RESOLUTION
from tests.processes import Child

A3 = (15.0, 45.0, 110.0)
DB = default_database()
FAMILY = {c.name: c.family for c in DB.colorants}
README_SILVER = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])


def _solid(**fractions: float) -> np.ndarray:
    return predict_lab(DB.vector(fractions), A3)


def test_same_recipe_beside_busy_processes() -> None:
    quiet = formulate(README_SILVER, A3)
    spin = [sys.executable, "-c", "while True: pass"]
    with Child(spin, stdout=None, stderr=None), Child(spin, stdout=None, stderr=None):
        loaded = formulate(README_SILVER, A3)
    assert [o.recipe for o in loaded.recipes] == [o.recipe for o in quiet.recipes]
    assert np.array_equal(loaded.concentrations, quiet.concentrations)
    assert loaded.evaluations == quiet.evaluations


def test_solid_design_gets_only_solid_line_colorants() -> None:
    design = _solid(white_tio2=0.25, red_pr=0.04, yellow_py=0.02)
    assert lines_for_design(design) == ("solid",)
    result = formulate(design, A3)
    assert result.line == "solid" and result.formulable
    for option in result.recipes:
        assert all(FAMILY[n] not in EFFECT_FAMILIES for n in option.recipe)


def test_named_solid_line_refuses_effect_pigments_for_a_silver() -> None:
    result = formulate(README_SILVER, A3, line="solid")
    assert all(FAMILY[n] not in EFFECT_FAMILIES for o in result.recipes for n in o.recipe)
    assert toner_line("metallic").mask(DB)[DB.names.index("alu_bright")]
    assert not toner_line("metallic").mask(DB)[DB.names.index("interference_blue")]


@pytest.mark.parametrize("max_colorants", [2, 3])
def test_recipes_respect_the_colorant_limit(max_colorants: int) -> None:
    result = formulate(README_SILVER, A3, max_colorants=max_colorants, recipes=3)
    assert 1 <= len(result.recipes) <= 3
    for option in result.recipes:
        assert option.colorants == len(option.recipe) <= max_colorants


def test_three_colorant_design_is_recovered_with_three_colorants() -> None:
    # in gamut with exactly these three colorants: a 3-colorant recipe exists that only rounding spoils
    design = _solid(white_tio2=0.2, blue_pb=0.03, yellow_opaque=0.05)
    result = formulate(design, A3, max_colorants=3)
    assert result.formulable and result.mean_de_unrounded < 0.05
    assert len(result.recipe) <= 3


@pytest.mark.parametrize("resolution", [0.1, 0.5])
def test_amounts_are_multiples_of_the_scale_and_delta_e_is_after_rounding(resolution: float) -> None:
    result = formulate(README_SILVER, A3, scale_resolution_g=resolution, batch_g=1000.0)
    for option in result.recipes:
        for grams in option.grams.values():
            assert grams >= resolution - 1e-9
            assert abs(grams / resolution - round(grams / resolution)) < 1e-6
        assert option.binder_g + sum(option.grams.values()) == pytest.approx(1000.0)
        # ΔE after rounding, recomputed by colour-science from the fractions the grams give
        c = DB.vector({k: v / 1000.0 for k, v in option.grams.items()})
        de = colour.delta_E(README_SILVER, predict_lab(c, A3), method="CIE 2000")
        assert option.mean_de == pytest.approx(float(np.mean(de)), abs=1e-6)
        assert option.cost_per_kg == pytest.approx(cost_per_kg(c, DB))


def test_ranking_follows_the_rule() -> None:
    result = formulate(README_SILVER, A3, recipes=3, max_colorants=4)
    keys = [
        (
            not o.formulable,
            round(o.mean_de / RANK_DE_RESOLUTION),
            round(o.worst_mi / RANK_DE_RESOLUTION),
            o.colorants,
            o.cost_per_kg,
        )
        for o in result.recipes
    ]
    assert keys == sorted(keys)
    assert [o.rank for o in result.recipes] == list(range(1, len(keys) + 1))
    assert result.recipe == result.recipes[0].recipe
    for o in result.recipes:
        assert o.metamerism is None or set(o.metamerism) == {"A", "F11"}


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"max_colorants": 0}, "max_colorants"),
        ({"max_colorants": 11}, "max_colorants"),
        ({"scale_resolution_g": 0.0}, "scale_resolution_g"),
        ({"scale_resolution_g": float("nan")}, "scale_resolution_g"),
        ({"recipes": 0}, "recipes"),
        ({"line": "chrome"}, "line"),
        ({"batch_g": 0.5}, "batch_g"),
    ],
)
def test_bad_selection_input_names_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(FormulateInputError) as err:
        formulate(README_SILVER, A3, **kwargs)
    assert err.value.field == field
