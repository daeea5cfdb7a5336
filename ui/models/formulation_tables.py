"""What the Formulation screen's tables show, Qt-free: the recipes side by side, the closed loop's
steps with their tinting additions, and the loop's one-sentence summary.

**Recipes side by side** (:func:`recipe_columns`): one column per recipe, as a chemist compares them —
grams per kg of batch per colorant (rounded to the scale's resolution where the formulation rounds),
the binder, mean ΔE00 before and after rounding, the metamerism index under A and F11 (worst over the
angles), the number of colorants (binder and matting agent not counted) and the cost per kg.

The columns come from the formulation's ranked recipes when it has them (a ``recipes`` sequence of
options, each an object with ``to_dict()`` or already a dict of that shape: ``grams``, ``binder_g``,
``batch_g``, ``scale_resolution_g``, ``mean_de``, ``mean_de_unrounded``, ``metamerism_index``,
``colorants``, ``cost_per_kg``, ``formulable``, ``start``); a formulation with a single unrounded
recipe gives one column, with the cells it cannot fill (ΔE after rounding, cost) shown as "—".

**Closed loop** (:func:`loop_groups`): per step the measured mean ΔE00 and what the chemist does — the
initial batch is the recipe; a correction lists its **additions** (colorant, grams) to the batch
mixed so far; a correction that only a fresh batch can reach says "remake" and lists the new recipe
in grams, never additions. Grams are for the screen's batch M: the loop runs for it, and should the
batch change afterwards the additions (masses, linear in the batch: every mass of the job scales with
its first batch M₀) are shown × M / M₀ (``station.formulate.batch``, ``station.formulate.tinting``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from station.decimals import step_decimals
from station.formulate.batch import DEFAULT_BATCH_G, batch_masses
from station.model.domain import METAMERISM_TEST_ILLUMINANTS

#: Rows under the colorant rows of the side-by-side table.
SUMMARY_ROWS: tuple[str, ...] = (
    "ΔE00 before rounding",
    "ΔE00 after rounding",
    *(f"MI {name}" for name in METAMERISM_TEST_ILLUMINANTS),
    "colorants",
    "cost per kg",
)
#: Grams per kg of batch: the side-by-side table's unit.
PER_KG_G = 1000.0
NOT_SHOWN = "—"


@dataclass(frozen=True)
class RecipeColumn:
    """One recipe of the side-by-side table: ``g_per_kg`` per colorant and ``binder_g_per_kg``;
    ``resolution_g`` the scale's resolution as a step of ``g_per_kg`` (g/kg: the resolution × 1000 g / the
    batch; None: not rounded); ΔE00 mean
    before (``de_unrounded``) and after rounding (``de_rounded``, None when not rounded); ``metamerism``
    per test illuminant; ``colorants`` their number; ``cost_per_kg`` (None when not known)."""

    label: str
    g_per_kg: dict[str, float]
    binder_g_per_kg: float
    resolution_g: float | None
    de_unrounded: float
    de_rounded: float | None
    metamerism: dict[str, float] | None
    colorants: int
    cost_per_kg: float | None
    formulable: bool


def _number(value: Any) -> float | None:
    return None if value is None or not math.isfinite(float(value)) else float(value)


def column_from_option(option: dict[str, Any]) -> RecipeColumn:
    """A column from one ranked recipe option (``RecipeOption.to_dict()`` shape, module docstring)."""
    scale = PER_KG_G / float(option["batch_g"])
    rounded = _number(option.get("mean_de"))
    before = _number(option.get("mean_de_unrounded"))
    start = str(option.get("start", ""))
    resolution = _number(option.get("scale_resolution_g"))
    return RecipeColumn(
        f"#{option.get('rank', 1)}" + (f" from {start}" if start else ""),
        {str(k): float(v) * scale for k, v in option["grams"].items()},
        float(option["binder_g"]) * scale,
        None if resolution is None else resolution * scale,
        before if before is not None else float(rounded or 0.0),
        rounded,
        option.get("metamerism_index"),
        int(option["colorants"]),
        _number(option.get("cost_per_kg")),
        bool(option.get("formulable", True)),
    )


def single_column(result: Any, metamerism: dict[str, float] | None) -> RecipeColumn:
    """The one column of a formulation without ranked recipes: its recipe, unrounded, per kg."""
    b = batch_masses(dict(result.recipe), PER_KG_G)
    return RecipeColumn(
        f"from {result.start}" if getattr(result, "start", "") else "recipe",
        dict(b.colorants_g),
        b.binder_g,
        None,
        float(result.mean_de),
        None,
        metamerism,
        sum(1 for v in result.recipe.values() if v > 0),
        None,
        bool(result.formulable),
    )


def recipe_columns(result: Any, metamerism: dict[str, float] | None = None) -> list[RecipeColumn]:
    """The side-by-side columns of a formulation *result* (local or the service's): its ranked
    ``recipes`` when it carries them, else its single recipe with *metamerism* (module docstring)."""
    options = tuple(getattr(result, "recipes", ()) or ())
    if options:
        return [column_from_option(o if isinstance(o, dict) else o.to_dict()) for o in options]
    return [single_column(result, metamerism)]


def _fmt(value: float | None, digits: int = 2) -> str:
    return NOT_SHOWN if value is None else f"{value:.{digits}f}"


def _grams(value: float, digits: int) -> str:
    """*value* (g/kg) to *digits* decimals, trailing zeros dropped down to one decimal (60.20 → 60.2,
    60.25 stays; 50.00 → 50.0)."""
    text = f"{value:.{digits}f}"
    while digits > 1 and text.endswith("0"):
        text, digits = text[:-1], digits - 1
    return text


def recipe_table(columns: Sequence[RecipeColumn]) -> tuple[list[str], list[list[str]]]:
    """Row labels and cells (rows × columns) of the side-by-side table: the colorants (largest in the
    first recipe first), the binder, then :data:`SUMMARY_ROWS`; a colorant a recipe lacks is blank."""
    names: list[str] = []
    for c in columns:
        names += [n for n in sorted(c.g_per_kg, key=lambda k: -c.g_per_kg[k]) if n not in names]
    labels = [f"{n} (g/kg)" for n in names] + ["binder (g/kg)", *SUMMARY_ROWS]
    cells: list[list[str]] = [[] for _ in labels]
    for c in columns:
        digits = 2 if c.resolution_g is None else step_decimals(c.resolution_g)
        col = [_grams(c.g_per_kg[n], digits) if n in c.g_per_kg else "" for n in names]
        mi = [_fmt(c.metamerism.get(i) if c.metamerism else None) for i in METAMERISM_TEST_ILLUMINANTS]
        col += [_grams(c.binder_g_per_kg, digits), _fmt(c.de_unrounded), _fmt(c.de_rounded), *mi]
        col += [str(c.colorants), _fmt(c.cost_per_kg)]
        for row, text in zip(cells, col, strict=True):
            row.append(text)
    return labels, cells


@dataclass(frozen=True)
class StepGroup:
    """One closed-loop step as the table shows it: number, what the chemist does (``initial``,
    ``add``, ``remake``), measured mean ΔE00, and (colorant, grams text) lines; *note* the engine's
    tinting message."""

    number: int
    action: str
    mean_de: float
    lines: tuple[tuple[str, str], ...]
    note: str = ""


def _additions(step: Any) -> dict[str, Any] | None:
    """A step's additions as ``Tinting.to_dict()``, or None (the initial batch)."""
    additions = getattr(step, "additions", None)
    if additions is not None and not isinstance(additions, dict):
        additions = additions.to_dict()
    return additions


def first_batch_g(steps: Sequence[Any]) -> float:
    """The mass (g) of the job's first batch, which every mass of the job is proportional to."""
    return float(getattr(steps[0], "batch_g", DEFAULT_BATCH_G)) if steps else DEFAULT_BATCH_G


def step_group(step: Any, batch_g: float, job_batch_g: float = DEFAULT_BATCH_G) -> StepGroup:
    """What a closed-loop *step* (``LoopStep`` or the service's step) of a job whose first batch was
    *job_batch_g* g asks of a first batch of *batch_g* g."""
    recipe, additions, step_batch = dict(step.recipe), _additions(step), job_batch_g
    de = float(step.mean_de)
    if additions is None:
        return StepGroup(step.number, "initial", de, (("the recipe", f"{batch_g:g} g batch"),))
    note = str(additions.get("message", ""))
    if additions.get("remake"):
        b = batch_masses(recipe, batch_g)
        new = sorted(b.colorants_g.items(), key=lambda kv: -kv[1])
        lines = tuple((name, f"{g:.2f} g") for name, g in [*new, ("binder", b.binder_g)])
        return StepGroup(step.number, "remake", de, lines, note)
    scale = batch_g / step_batch
    adds = [(str(k), float(v) * scale) for k, v in additions.get("additions_g", {}).items()]
    adds.sort(key=lambda kv: -kv[1])
    adds.append(("binder", float(additions.get("binder_g", 0.0)) * scale))
    lines = tuple((name, f"+{g:.2f} g") for name, g in adds if g >= 0.005)
    return StepGroup(step.number, "add", de, lines or (("nothing to add", ""),), note)


def loop_groups(steps: Sequence[Any], batch_g: float) -> list[StepGroup]:
    """:func:`step_group` of each step, in order, for a first batch of *batch_g* g."""
    first = first_batch_g(steps)
    return [step_group(s, batch_g, first) for s in steps]


def loop_summary(job: Any) -> str:
    """One sentence on a closed loop *job*: converged or not, after how many corrections, the measured
    mean ΔE00 from the first to the last step (and the tolerance), then the engine's further notes
    (what follows the first "; " of its message) and warnings; with no step sprayed, the reason."""
    if not job.steps:  # nothing sprayed (a design the colorants cannot reach): the engine's reason
        return f"Closed loop not sprayed: {str(job.message).rstrip('.')}."
    n = int(job.corrections)
    state = "converged" if job.status == "converged" else "did not converge"
    des = [float(s.mean_de) for s in job.steps]
    text = f"Closed loop {state} after {n} correction{'' if n == 1 else 's'}"
    if des:
        text += f": measured mean ΔE00 {des[0]:.2f}" + (f" → {des[-1]:.2f}" if len(des) > 1 else "")
    tolerance = getattr(job, "tolerance", None)
    if tolerance is not None:
        text += f" (tolerance {float(tolerance):g})"
    _head, _sep, detail = str(job.message).partition("; ")
    if detail:
        text += f"; {detail}"
    warnings = tuple(getattr(job, "warnings", ()) or ())
    if warnings:
        text += "; warning: " + "; ".join(warnings)
    return text + "."
