"""The Formulation tab's tables, Qt-free: a correction only a fresh batch reaches is shown as the new
recipe (never additions), additions scale with the screen's batch, the loop's outcome is one sentence,
and ranked recipe options (``RecipeOption.to_dict()`` shape) become columns in grams per kg."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pytest

from station.formulate.batch import Tinting, batch_masses, tinting_additions
from ui.models import formulation_tables as ft


@dataclass(frozen=True)
class _Step:
    number: int
    kind: str
    recipe: dict[str, float]
    mean_de: float
    additions: Tinting | None = None


@dataclass(frozen=True)
class _Job:
    status: str
    message: str
    steps: tuple[_Step, ...]
    tolerance: float = 1.0
    warnings: tuple[str, ...] = field(default=())

    @property
    def corrections(self) -> int:
        return sum(1 for s in self.steps if s.kind == "correction")


FIRST = {"blue_pb": 0.02, "alu_fine": 0.05}
TINTED = {"blue_pb": 0.025, "alu_fine": 0.05, "yellow_py": 0.004}
REMADE = {"alu_fine": 0.06, "yellow_py": 0.004}  # blue_pb removed: only a fresh batch reaches it


def test_additions_scale_with_the_batch():
    step = _Step(1, "correction", TINTED, 0.5, tinting_additions(FIRST, TINTED, 1000.0))
    g = ft.step_group(step, 250.0)
    want = tinting_additions(FIRST, TINTED, 250.0)  # a_i = c'_i M' - c_i M, by the core at 250 g
    assert g.action == "add" and not want.remake
    got = {name: float(text.removeprefix("+").split()[0]) for name, text in g.lines}
    shown = {k: v for k, v in {**want.additions_g, "binder": want.binder_g}.items() if v >= 0.005}
    assert got == pytest.approx(shown, abs=0.006) and "binder" not in got  # nothing to add: not listed
    assert all(text.startswith("+") for _n, text in g.lines)


def test_remake_lists_the_new_recipe_not_additions():
    tint = tinting_additions(TINTED, REMADE, 1000.0)
    assert tint.remake
    g = ft.step_group(_Step(2, "correction", REMADE, 0.4, tint), 500.0)
    b = batch_masses(REMADE, 500.0)
    assert g.action == "remake" and "blue_pb" in g.note
    got = {name: float(text.split()[0]) for name, text in g.lines}
    assert got == pytest.approx({**b.colorants_g, "binder": b.binder_g}, abs=0.006)
    assert not any(text.startswith("+") for _n, text in g.lines)


def test_loop_summary_is_one_sentence():
    steps = (
        _Step(0, "initial", FIRST, 1.26),
        _Step(1, "correction", TINTED, 0.5, tinting_additions(FIRST, TINTED)),
    )
    done = _Job("converged", "converged: mean ΔE00 0.50 after 1 correction(s)", steps)
    text = ft.loop_summary(done)
    assert text == "Closed loop converged after 1 correction: measured mean ΔE00 1.26 → 0.50 (tolerance 1)."
    none = _Job("converged", "converged: mean ΔE00 0.40 after 0 correction(s)", steps[:1])
    assert ft.loop_summary(none).startswith("Closed loop converged after 0 corrections: ")
    far = _Job(
        "not_converged",
        "not converged: mean ΔE00 1.90 after 3 correction(s); the design is likely outside the gamut",
        steps,
        warnings=("45°: ΔE00 2.1 over the tolerance",),
    )
    text = ft.loop_summary(far)
    assert text.count("converge") == 1 and text.count("correction") == 1
    assert "outside the gamut" in text and "warning: 45°" in text
    refused = _Job("not_formulable", "not formulable with these colorants (mean ΔE00 3.10)", ())
    assert ft.loop_summary(refused) == (
        "Closed loop not sprayed: not formulable with these colorants (mean ΔE00 3.10)."
    )


def _option(rank: int, grams: dict[str, float], batch_g: float, **kw: Any) -> dict[str, Any]:
    base = {
        "rank": rank,
        "grams": grams,
        "binder_g": batch_g - sum(grams.values()),
        "batch_g": batch_g,
        "scale_resolution_g": 0.1,
        "mean_de": 0.42,
        "mean_de_unrounded": 0.37,
        "metamerism_index": {"A": 0.31, "F11": 0.12},
        "colorants": len(grams),
        "cost_per_kg": 12.5,
        "formulable": True,
        "start": "M-001",
    }
    return {**base, **kw}


def test_ranked_options_side_by_side():
    @dataclass(frozen=True)
    class _Result:
        recipes: tuple[dict[str, Any], ...]

    result = _Result(
        (_option(1, {"blue_pb": 20.3, "alu_fine": 50.0}, 1000.0), _option(2, {"alu_fine": 120.4}, 2000.0))
    )
    labels, cells = ft.recipe_table(ft.recipe_columns(result))
    # colorants largest first in the first recipe; the 2000 g batch's grams halved to per kg
    assert labels[:3] == ["alu_fine (g/kg)", "blue_pb (g/kg)", "binder (g/kg)"]
    assert cells[:3] == [["50.0", "60.2"], ["20.3", ""], ["929.7", "939.8"]]
    rows = dict(zip(labels, cells, strict=True))
    assert rows["ΔE00 before rounding"] == ["0.37", "0.37"] and rows["ΔE00 after rounding"] == ["0.42"] * 2
    assert rows["MI A"] == ["0.31"] * 2 and rows["MI F11"] == ["0.12"] * 2
    assert rows["colorants"] == ["2", "1"] and rows["cost per kg"] == ["12.50"] * 2
    assert [c.label for c in ft.recipe_columns(result)] == ["#1 from M-001", "#2 from M-001"]
