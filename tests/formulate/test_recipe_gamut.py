"""The N-colorant gamut (:func:`station.formulate.gamut.recipe_gamut`) against brute force: every N-subset
of a small toner line (the solid line, 10 colorants) refitted from several starts."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from station.cli import main
from station.formulate.colorants import predict_lab
from station.formulate.errors import FormulateInputError
from station.formulate.gamut import line_gamut, recipe_gamut
from tests.formulate._brute import A3, DB, SOLID, best_fit

TOL = 1.0
#: Verdicts closer to the tolerance than this may differ between two optimisers of the same subset.
BORDER = 0.05


def _brute_force(design: np.ndarray, n: int) -> float:
    """Best mean ΔE00 over every subset of *n* colorants of the solid line."""
    return min(best_fit(design, sub) for sub in itertools.combinations(SOLID.tolist(), n))


def _designs() -> list[np.ndarray]:
    """Seeded solid designs: four-colorant recipes of the solid line (a white base, three tints or black)
    with a stylist's move of up to 3 in L*, a*, b* — some a pair of colorants makes, some it cannot."""
    rng = np.random.default_rng(25)
    white = DB.names.index("white_tio2")
    others = [int(i) for i in SOLID if i != white]
    out = []
    for _ in range(6):
        c = np.zeros(len(DB.names))
        c[white] = rng.uniform(0.02, 0.2)
        for i in rng.choice(others, 3, replace=False):
            c[i] = rng.uniform(0.002, 0.04)
        out.append(predict_lab(c, A3) + rng.uniform(-3.0, 3.0, size=3))
    return out


@pytest.fixture(scope="module")
def verdicts() -> list[tuple[float, float, bool, bool]]:
    """(brute force 2-colorant best, screen best, inside, line inside) per design."""
    out = []
    for d in _designs():
        r = recipe_gamut(d, A3, line="solid", max_colorants=2)
        out.append((_brute_force(d, 2), r.mean_de, r.inside, r.line_inside))
    return out


def test_two_colorant_gamut_agrees_with_brute_force(verdicts: list) -> None:
    inside = [v for v in verdicts if v[0] <= TOL - BORDER]
    outside = [v for v in verdicts if v[0] > TOL + BORDER and v[3]]
    assert inside and outside  # the sample holds both kinds, inside the line's gamut
    false_accepts = [v for v in verdicts if v[2] and v[0] > TOL + BORDER]
    false_refusals = [v for v in verdicts if not v[2] and v[0] <= TOL - BORDER]
    assert not false_accepts and not false_refusals
    for brute2, screened, _, _ in verdicts:
        # the screen's refit is a recipe of at most 2 colorants: never better than the brute force
        # (up to the optimisers' noise), and it finds about the best
        assert brute2 - 0.02 <= screened <= brute2 + 0.1


def test_refusal_by_the_colorant_limit_names_the_count_that_reaches() -> None:
    for d in _designs():
        r = recipe_gamut(d, A3, line="solid", max_colorants=2)
        if r.inside or not r.line_inside:
            continue
        assert f"outside the 2-colorant gamut of line solid: best 2-colorant screen ΔE00 {r.mean_de:.2f}" in (
            r.message
        )
        assert f"the line with more colorants reaches {r.line_mean_de:.2f}" in r.message
        assert r.needed_colorants is not None and r.needed_colorants > 2
        assert f"max colorants {r.needed_colorants}" in r.message
        assert _brute_force(d, r.needed_colorants) <= TOL + BORDER
        if r.needed_colorants > 3:
            assert _brute_force(d, 3) > TOL - BORDER
        # the N-colorant gamut lies inside the line's gamut: the same verdict for the line alone
        assert line_gamut(d, A3, line="solid").inside
        return
    pytest.fail("no design of the sample is refused by the colorant limit alone")


def test_outside_the_line_is_outside_every_colorant_count() -> None:
    ub = DB.upper_bounds[DB.names.index("white_tio2")]
    too_light = predict_lab(DB.vector({"white_tio2": float(ub)}), A3) + np.array([5.0, 0.0, 0.0])
    r = recipe_gamut(too_light, A3, line="solid", max_colorants=10)
    assert not r.inside and not r.line_inside and r.needed_colorants is None
    assert r.message.startswith("outside the gamut of line solid")


@pytest.mark.parametrize("bad", [0, 11, 2.5, True])
def test_max_colorants_out_of_range_names_the_field(bad: object) -> None:
    with pytest.raises(FormulateInputError, match="max_colorants"):
        recipe_gamut(_designs()[0], A3, line="solid", max_colorants=bad)  # type: ignore[arg-type]


def test_the_cli_says_when_only_the_colorant_limit_refuses_the_design(capsys: pytest.CaptureFixture) -> None:
    d = _designs()[2]  # no pair of the solid line reaches it (brute force 1.75), three colorants do
    lab = ";".join(",".join(f"{v:.3f}" for v in row) for row in d)
    assert main(["formulate", lab, "--line", "solid", "--max-colorants", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert not out["formulable"]
    gamut = out["gamut"]
    assert not gamut["inside"] and gamut["line_inside"] and gamut["max_colorants"] == 2
    assert gamut["needed_colorants"] == 3 and "allow 3 colorants (max colorants 3)" in gamut["message"]
    assert out["message"].endswith(gamut["message"])
    assert main(["formulate", lab, "--line", "solid", "--max-colorants", "3", "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["formulable"] and again["gamut"] is None
