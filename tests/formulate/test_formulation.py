"""Formulation (SLSQP on multi-angle CIEDE2000) and the closed loop."""

from __future__ import annotations

import numpy as np
import pytest

from station.formulate.batch import batch_masses
from station.formulate.closed_loop import closed_loop
from station.formulate.colorants import default_database, predict_lab
from station.formulate.demo import generate_recipes
from station.formulate.errors import FormulateInputError, NotFormulableError
from station.formulate.formulation import (
    FormulationOptions,
    _fit_line,
    formulate,
    formulate_from_library,
    formulation_options,
)
from station.formulate.library import Library
from station.formulate.sprayout import SprayOutModel
from station.model import AspecularMeasurements
from station.model.difference import delta_e

DB = default_database()
A3 = (15.0, 45.0, 110.0)
OUT_OF_GAMUT = np.array([[80.0, -90.0, -30.0], [78.0, -88.0, -30.0], [75.0, -85.0, -28.0]])


@pytest.fixture(scope="module")
def designs() -> tuple[np.ndarray, np.ndarray]:
    """Six in-gamut designs: predictions of recipes the library has never seen (seed 404)."""
    types, c = generate_recipes(2, 2, 2, seed=404)
    return types, c


def test_formulation_recovers_in_gamut_designs(small_library: Library, designs) -> None:
    _, conc = designs
    for c in conc:
        design = predict_lab(c, A3)
        result, snap = formulate_from_library(design, small_library)
        assert result.formulable, result.message
        assert result.mean_de <= 0.3
        assert result.elapsed_s < 3.0  # the 1 s bar is measured by bench/formulate.py on a quiet machine
        DB.check(result.concentrations)
        recomputed = delta_e(design, predict_lab(result.concentrations, A3), "cie2000")
        assert np.allclose(result.de_per_angle, recomputed, atol=1e-9)
        assert result.start in {m.code for m in snap.matches} | {"generic"}


def test_out_of_gamut_design_is_not_formulable() -> None:
    result = formulate(OUT_OF_GAMUT)
    assert not result.formulable
    assert "not formulable with these colorants" in result.message
    assert result.mean_de > 5
    with pytest.raises(NotFormulableError):
        formulate(OUT_OF_GAMUT, strict=True)


def test_gloss_target_sets_the_matting_fraction(designs) -> None:
    design = predict_lab(designs[1][0], A3)
    result = formulate(design, gloss_gu=50.0)
    # the matting agent is weighed too: its closed-form fraction rounded to 0.1 g in 1000 g
    assert result.recipe["matting_silica"] == pytest.approx((90.0 - 50.0) / 650.0, abs=0.5e-4)
    assert result.gloss_gu == pytest.approx(50.0, abs=650.0 * 0.5e-4)
    assert formulate(design, gloss_gu=99.0).warnings


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"design_lab": [[50, 0, 0]] * 2}, "design_lab"),
        ({"design_lab": [[50, 0, 0]] * 3, "tolerance": -1.0}, "tolerance"),
        ({"design_lab": [[50, 0, 0]] * 3, "gloss_gu": 150.0}, "gloss_gu"),
    ],
)
def test_bad_formulation_input(kwargs: dict, field: str) -> None:
    with pytest.raises(FormulateInputError) as err:
        formulate(**kwargs)
    assert err.value.field == field


@pytest.mark.parametrize(
    ("options", "field", "accepted"),
    [
        ({"max_colorants": True}, "max_colorants", "[1, 10]"),
        ({"recipes": True}, "recipes", "an integer"),
        ({"max_starts": False}, "max_starts", "[1, 50]"),
        ({"batch_g": 1e6 + 1.0}, "batch_g", "batch_g <="),
    ],
)
def test_formulation_options_refuse_booleans_and_oversized_batches(
    options: dict[str, object], field: str, accepted: str
) -> None:
    # True is an int to Python, but no count of colorants or recipes; a batch above the 1 000 kg scale
    # ceiling is refused by the options as by the batch weigh-out
    with pytest.raises(FormulateInputError) as err:
        formulation_options(FormulationOptions(**options))  # type: ignore[arg-type]
    assert err.value.field == field and accepted in str(err.value)
    if field == "batch_g":
        with pytest.raises(FormulateInputError) as weigh:
            batch_masses({"red_pr": 0.1}, 1e6 + 1.0)
        assert weigh.value.field == "batch_g"
    assert formulation_options(FormulationOptions(max_colorants=1, recipes=1, batch_g=1e6)).batch_g == 1e6


def test_closed_loop_converges_within_three_corrections(small_library: Library, designs) -> None:
    _, conc = designs
    for seed, c in enumerate(conc):
        design = predict_lab(c, A3)
        spray = SprayOutModel(seed=seed)
        job = closed_loop(design, spray.measure, starts=[("true-neighbour", c * 0.9)])
        assert job.status == "converged", job.message
        assert job.corrections <= 3 and job.steps[-1].mean_de <= 1.0
        assert spray.panels == len(job.steps)
        last = job.steps[-1]
        assert np.allclose(last.de_per_angle, delta_e(design, np.array(last.measured_lab), "cie2000"))
        steps = job.to_dict()["steps"]
        assert isinstance(steps, list) and steps[0]["kind"] == "initial"


def test_additive_instrument_bias_is_cancelled_in_one_correction(designs) -> None:
    design = predict_lab(designs[1][2], A3)
    bias = np.array([[2.0, -1.5, 1.0], [1.5, -1.0, 1.0], [1.0, -0.5, 0.5]])

    def measure(recipe: dict[str, float]) -> AspecularMeasurements:
        return AspecularMeasurements(A3, predict_lab(DB.vector(recipe), A3) + bias, 90.0)

    job = closed_loop(design, measure)
    assert job.status == "converged"
    assert job.corrections == 1
    first, second = job.steps
    assert (
        first.mean_de > 1.0 and first.predicted_mean_de <= 0.2
    )  # the model was right (refined to 0.2 × tolerance); the instrument biased
    # after the offset correction the panel misses the design by what the model misses the shifted target
    # (exactly so for ΔE*ab, where ΔE(design, P + bias) = ΔE(design − bias, P); to 0.25 for CIEDE2000)
    assert second.mean_de <= 1.0 and abs(second.mean_de - second.predicted_mean_de) < 0.25


def test_closed_loop_refuses_out_of_gamut_without_spraying() -> None:
    def measure(recipe: dict[str, float]) -> AspecularMeasurements:
        raise AssertionError("nothing should be sprayed")

    job = closed_loop(OUT_OF_GAMUT, measure)
    assert job.status == "not_formulable" and job.steps == () and job.final_recipe is None
    assert "not formulable" in job.message


def test_generic_starts_alone_reach_in_gamut_designs(designs) -> None:
    for c in designs[1]:
        result = formulate(predict_lab(c, A3))  # no library recipe to start from
        assert result.formulable, result.message
        DB.check(result.concentrations)


def test_a_line_that_cannot_reach_the_design_is_skipped_soundly(designs) -> None:
    """The metallic line is tried first for this pearl design (black, coarse aluminium, red interference);
    its line-wide fit misses by more than n × the tolerance in root-sum-square ΔE00, so with a wider line
    to follow it gives no options. Independent check: its full subset search (rounded recipes of at most
    5 colorants) finds none within the tolerance either, and the pearl line then reaches the design."""
    design = predict_lab(designs[1][5], A3)
    opts = FormulationOptions(paint_type="metallic")
    full = _fit_line(design, A3, [], 0.0, DB, "metallic", opts, 1.0, 0, more_lines=False)
    skipped = _fit_line(design, A3, [], 0.0, DB, "metallic", opts, 1.0, 0, more_lines=True)
    assert full.options and min(o.mean_de for o in full.options) > 1.0
    assert skipped.options == [] and skipped.evaluations < full.evaluations
    result = formulate(design, paint_type="metallic")
    assert result.formulable and result.line == "pearl"
