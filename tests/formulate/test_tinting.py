"""Corrections as tinting: add-only, within the batch's bounds, or an honest remake."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from station.formulate.batch import MAX_GROWTH
from station.formulate.closed_loop import closed_loop, correct_batch
from station.formulate.colorants import default_database, predict_lab
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import FormulationOptions
from station.formulate.lines import toner_line
from station.formulate.tinting import tint
from station.model import AspecularMeasurements

A3 = (15.0, 45.0, 110.0)
DB = default_database()


def test_tinting_adds_only_and_stays_in_the_can() -> None:
    c = DB.vector({"white_tio2": 0.2, "red_pr": 0.03, "yellow_py": 0.02})
    masses = c * 1000.0
    binder = 1000.0 - masses.sum()
    target = predict_lab(DB.vector({"white_tio2": 0.2, "red_pr": 0.036, "yellow_py": 0.02}), A3)
    t = tint(masses, binder, target, A3, DB, 0.1, 1000.0)
    assert all(g >= 0 for g in t.tinting.additions_g.values()) and t.tinting.binder_g >= 0
    assert set(t.tinting.additions_g) <= {"white_tio2", "red_pr", "yellow_py"}
    assert np.all(t.masses_g >= masses - 1e-9)
    total = t.masses_g.sum() + t.binder_g
    assert total <= MAX_GROWTH * 1000.0 + 1e-6
    np.testing.assert_allclose(t.concentrations, t.masses_g / total)
    # more red was asked for: red is added, and the additions bring the prediction closer
    assert t.tinting.additions_g.get("red_pr", 0.0) > 0
    before = np.abs(predict_lab(c, A3) - target).sum()
    assert np.abs(t.predicted_lab - target).sum() < before


def test_a_lighter_target_than_black_and_blue_can_reach_is_a_remake() -> None:
    design = predict_lab(DB.vector({"white_tio2": 0.15, "blue_pb": 0.02, "black_carbon": 0.004}), A3)

    def measure(recipe: dict[str, float]) -> AspecularMeasurements:  # panels read 12 L* too dark
        return AspecularMeasurements(A3, predict_lab(DB.vector(recipe), A3) - [12.0, 0.0, 0.0], 90.0)

    job = closed_loop(design, measure, max_corrections=2)
    corrections = [s for s in job.steps if s.kind == "correction"]
    assert corrections
    for step in corrections:
        t = step.additions
        assert t is not None
        if t.remake:
            assert t.additions_g == {} and "remake" in t.message and step.batch_g == pytest.approx(1000.0)
        else:
            assert all(g >= 0 for g in t.additions_g.values())
            assert t.new_total_g <= MAX_GROWTH * 1000.0 + 1e-6
    # a panel that stays 12 L* off can never pass: each angle's failure is said
    if job.status != "converged":
        assert any("worse than the tolerance" in w for w in job.warnings)
    for step in job.steps:
        total = sum(step.recipe.values())
        assert total <= 1.0


def test_an_offset_the_sprayed_colorants_cannot_cancel_is_a_remake_with_other_colorants() -> None:
    recipe = {"white_tio2": 0.1, "red_pr": 0.03, "yellow_py": 0.01}
    design = predict_lab(DB.vector(recipe), A3)

    def measure(r: dict[str, float]) -> AspecularMeasurements:  # this batch of red_pr sprays 40 L* dark
        dark = np.array([40.0, 0.0, 0.0]) if r.get("red_pr", 0.0) > 0 else 0.0
        return AspecularMeasurements(A3, np.clip(predict_lab(DB.vector(r), A3) - dark, 0.0, None), 90.0)

    job = closed_loop(design, measure, starts=[("start", recipe)], max_corrections=2)
    assert job.steps[0].recipe.get("red_pr", 0.0) > 0 and job.steps[0].mean_de > 20.0
    # with red_pr the corrected target is 40 L* lighter than the design at the red's chroma, which no
    # recipe reaches; a recipe of another red sprays as predicted: the loop remakes with it and passes
    switch = job.steps[1]
    assert switch.additions is not None and switch.additions.remake
    assert "other colorants" in switch.additions.message and switch.additions.additions_g == {}
    assert "red_pr" not in switch.recipe
    assert job.status == "converged", job.message
    assert job.steps[-1].mean_de == pytest.approx(
        float(np.mean(cie2000(design, np.array(job.steps[-1].measured_lab))))
    )


@pytest.mark.parametrize("resolution_g", [5.0, 25.0])
def test_rounded_additions_keep_the_effect_limit_and_never_take_back_binder(
    resolution_g: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    import station.formulate.tinting as tinting

    fits: list[Any] = []
    fit = tinting.least_squares

    def spy(*args: Any, **kwargs: Any) -> Any:
        fits.append(fit(*args, **kwargs))
        return fits[-1]

    monkeypatch.setattr(tinting, "least_squares", spy)
    # a batch at its flake limit (0.15 + 0.10 = max_effect) and a target that wants more flake
    recipe = {"white_tio2": 0.05, "blue_pb": 0.03, "alu_bright": 0.15, "pearl_white": 0.10}
    c = DB.vector(recipe)
    assert c[DB.effect_mask].sum() == pytest.approx(DB.max_effect)
    masses = c * 1000.0
    binder = 1000.0 - masses.sum()
    target = predict_lab(DB.vector({**recipe, "alu_bright": 0.17, "pearl_white": 0.12}), A3)
    t = tint(masses, binder, target, A3, DB, resolution_g, 1000.0)
    after = t.concentrations
    # every bound of the colorant database holds after rounding (DB.check raises otherwise)
    DB.check(after)
    assert after[DB.effect_mask].sum() <= DB.max_effect + 1e-12
    assert t.masses_g.sum() + t.binder_g <= MAX_GROWTH * 1000.0 + 1e-6
    # the binder is the fit's, rounded to the scale: never the one taken back
    total = masses.sum() + binder
    fit_binder = fits[-1].x[-1] * total
    assert t.tinting.binder_g == pytest.approx(np.round(fit_binder / resolution_g) * resolution_g)
    assert t.tinting.binder_g > 0
    # flake is still added (a take-back stops at the bound, it does not strip the correction)
    assert t.tinting.additions_g.get("alu_bright", 0.0) > 0
    for g in t.tinting.additions_g.values():
        assert g / resolution_g == pytest.approx(round(g / resolution_g))


def test_a_remake_after_tinting_stays_with_the_line_sprayed(monkeypatch: pytest.MonkeyPatch) -> None:
    """A solid is sprayed from the solid line and tinted once; the tinted panel then reads with an
    angle-dependent offset, so the corrected target looks like an effect paint. The remake must be
    formulated from the toner line in the can (solid), not inferred again from the target."""
    import importlib

    loop = importlib.import_module("station.formulate.closed_loop")
    lines_used: list[str] = []
    formulate_with = loop.formulate_with

    def spy(*args: Any, **kwargs: Any) -> Any:
        result = formulate_with(*args, **kwargs)
        lines_used.append(result.line)
        return result

    monkeypatch.setattr(loop, "formulate_with", spy)
    recipe = {"white_tio2": 0.2, "red_pr": 0.03, "yellow_py": 0.02}
    design = predict_lab(DB.vector(recipe), A3)
    flop = np.column_stack([15.0 * np.cos(np.radians(A3)) - 4.5, np.zeros(3), np.zeros(3)])
    sprayed: list[dict[str, float]] = []

    def measure(r: dict[str, float]) -> AspecularMeasurements:
        sprayed.append(r)
        offset = np.array([-1.5, 0.0, 0.0]) if len(sprayed) == 1 else flop  # then 15° light, 110° dark
        return AspecularMeasurements(A3, predict_lab(DB.vector(r), A3) + offset, 90.0)

    job = closed_loop(design, measure, starts=[("start", recipe)], max_corrections=2)
    kinds = [(s.additions.remake if s.additions else None) for s in job.steps]
    assert kinds[:2] == [None, False] and True in kinds[2:], kinds  # tinted, then remade
    assert job.initial is not None and job.initial.line == "solid"
    # every recipe the loop formulated (the initial one and each remake) is drawn from the solid line
    assert lines_used and set(lines_used) == {"solid"}, lines_used
    solid = set(toner_line("solid").families)
    for step in job.steps:
        assert {DB.colorants[DB.names.index(n)].family for n in step.recipe} <= solid | {"matting"}


def _on_scale(grams: float, step: float = 0.1) -> bool:
    return abs(grams / step - round(grams / step)) < 1e-6


def test_the_matting_top_up_is_weighed_on_the_scale_and_predicted_as_weighed() -> None:
    """A batch with matting agent: every addition, the matting agent's included, is a multiple of the
    scale's resolution and the batch after is the batch before plus the additions, to the gram; the
    prediction is of that batch (fractions = masses / total)."""
    masses = DB.vector({"white_tio2": 37.0, "orange_po": 12.3, "yellow_py": 4.7, "matting_silica": 3.1})
    binder = 1000.0 - masses.sum()
    target = predict_lab(DB.vector({"white_tio2": 0.037, "orange_po": 0.0150, "yellow_py": 0.0047}), A3)
    t = tint(masses, binder, target, A3, DB, 0.1, 1000.0)
    adds = t.tinting.additions_g
    assert adds.get("orange_po", 0.0) > 0 and all(g > 0 and _on_scale(g) for g in adds.values())
    for name, before, after in zip(DB.names, masses, t.masses_g, strict=True):
        assert after == pytest.approx(before + adds.get(name, 0.0), abs=1e-9)
    total = t.masses_g.sum() + t.binder_g
    assert t.tinting.new_total_g == pytest.approx(total, abs=1e-9)
    np.testing.assert_allclose(t.predicted_lab, predict_lab(t.masses_g / total, A3))


def _batch(grams: dict[str, float]) -> tuple[dict[str, float], float]:
    return grams, 1000.0 - sum(grams.values())


def test_correct_batch_tints_toward_the_offset_corrected_target() -> None:
    """The measured panel reads 20 % less orange than the can holds (a weak toner): the correction adds
    orange, and its predicted ΔE00 is that of the batch after against design − (measured − predicted),
    recomputed here from the public predict_lab."""
    grams, binder = _batch({"white_tio2": 37.0, "orange_po": 12.3, "yellow_py": 4.7})
    c0 = DB.vector({n: g / 1000.0 for n, g in grams.items()})
    design = predict_lab(c0, A3) + [0.2, 0.1, 0.0]
    weak = c0.copy()
    weak[DB.names.index("orange_po")] *= 0.8
    measured = predict_lab(weak, A3)
    fix = correct_batch(design, measured, grams, binder, A3, options=FormulationOptions(line="solid"))
    assert not fix.tinting.remake and fix.tinting.additions_g.get("orange_po", 0.0) > 0
    target = design - (measured - predict_lab(c0, A3))
    after = DB.vector(fix.masses_g) / (sum(fix.masses_g.values()) + fix.binder_g)
    expected = float(cie2000(target, predict_lab(after, A3)).mean())
    assert fix.predicted_mean_de == pytest.approx(expected, abs=1e-9)
    assert expected < fix.measured_mean_de == pytest.approx(float(cie2000(design, measured).mean()))


def test_correct_batch_adds_nothing_to_a_panel_within_the_tolerance() -> None:
    grams, binder = _batch({"white_tio2": 37.0, "orange_po": 12.3, "yellow_py": 4.7})
    lab = predict_lab(DB.vector({n: g / 1000.0 for n, g in grams.items()}), A3)
    fix = correct_batch(lab, lab + [0.3, 0.0, 0.0], grams, binder, A3)
    assert fix.tinting.additions_g == {} and "within the tolerance" in fix.tinting.message
    assert fix.masses_g == grams and fix.binder_g == binder


def test_correct_batch_refuses_a_colorant_of_another_line_and_bad_masses() -> None:
    grams, binder = _batch({"white_tio2": 37.0, "alu_bright": 12.3})
    lab = predict_lab(DB.vector({n: g / 1000.0 for n, g in grams.items()}), A3)
    with pytest.raises(FormulateInputError) as err:
        correct_batch(lab, lab, grams, binder, A3, options=FormulationOptions(line="solid"))
    assert err.value.field == "recipe.alu_bright"
    with pytest.raises(FormulateInputError) as err:
        correct_batch(lab, lab, {"white_tio2": -1.0}, binder, A3)
    assert err.value.field == "batch.colorants_g.white_tio2"
    with pytest.raises(FormulateInputError) as err:
        correct_batch(lab, lab[:2], grams, binder, A3)
    assert err.value.field.startswith("measured_lab")
