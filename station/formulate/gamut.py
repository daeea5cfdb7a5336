"""The colorant gamut: whether a paint can be mixed from the shipped colorants, and the nearest that can.

Three questions, three functions:

* :func:`line_gamut` — **can the toner line mix it at all?** The line's gamut: the best recipe with
  every colorant of the line free and the amounts unrounded (the line-wide fit of
  :func:`station.formulate.formulation.line_wide_fit`, the matting agent set by the gloss) reaches the
  tolerance. A design outside it is refused before formulation: no recipe of that line, of any size,
  makes it, so a chemist's recipe of a few weighable colorants cannot either.
* :func:`recipe_gamut` — **can a recipe of at most N colorants of the line mix it?** (N: the chemist's
  ``max_colorants``, default :data:`station.model.domain.DEFAULT_MAX_COLORANTS`.) The **N-colorant
  gamut** of a line is the part of its gamut that a recipe of at most N of its colorants reaches. The
  check, cheaper than a formulation and independent of its output: the line-wide fit above; if it
  misses, the design is outside both gamuts (the N-colorant gamut is declared part of the line's). If
  it reaches the design with at most N colorants present, the design is inside. Otherwise the cheap
  linearised subset screen of the formulation's selection
  (:func:`station.formulate.selection.screen`, with its coarse pass over the widest pool
  :data:`~station.formulate.selection.SCREEN_COARSE_EVALUATIONS` allows: every N-subset of the solid
  and metallic lines for N = 5) ranks the N-subsets; the best :data:`RECIPE_GAMUT_REFITS` are refitted
  continuously (:func:`~station.formulate.selection.fit_subset` then
  :func:`~station.formulate.selection.refine_subset`), amounts unrounded; the design is inside when the
  best reaches the tolerance. (The screen's ordinary pool goes first; the coarse pass over the wider
  pool only when that misses.) Lines are tried in :func:`~station.formulate.lines.lines_for_design`'s
  order until one's N-colorant gamut holds the design. When only the colorant limit refuses it, the
  same screen with N + 1, N + 2, … colorants (up to the allowed maximum,
  :data:`station.model.domain.MAX_COLORANTS_RANGE`) names the fewest that would do.
  :func:`formulate_in_gamut` asks it for the fronts whenever a formulation misses its tolerance.
* :func:`colorant_gamut` — **does the chemist's recipe reach it?**

The second rule (one place; the QA step, the CLI and the service ask it): a paint is **inside the colorant
gamut** when the formulator (:func:`station.formulate.formulation.formulate`) reaches it within the
formulation tolerance (mean CIEDE2000 over 15/45/110°, :data:`station.model.domain.FORMULATION_TOLERANCE_DE00`).
Outside it, the **nearest achievable paint** is the colour of the best recipe: its predicted Lab at the
five standard angles, fitted to face/flop/travel/gloss (:func:`station.model.fit.fit_fftg`), with the
recipe that makes it. The analysis package's own "paintable" bound (station.analysis.gamut: sRGB
chromaticity, reflectance) is the physical pre-check; this one is the check against the colorants.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.colorants import (
    GLOSS_CLEAR_GU,
    ColorantDatabase,
    default_database,
    predict_gloss,
    predict_lab,
)
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import (
    DEFAULT_TOLERANCE,
    MAX_STARTS,
    FormulationOptions,
    FormulationResult,
    formulate,
    formulate_with,
    library_starts,
    line_wide_fit,
    matting_for_gloss,
)
from station.formulate.library import STANDARD_ANGLES, Library
from station.formulate.lines import lines_for_design
from station.formulate.result import RecipeGamutReport
from station.formulate.selection import (
    SCREEN_COARSE_EVALUATIONS,
    fit_subset,
    refine_subset,
    screen,
)
from station.formulate.snap import SnapIndex, SnapResult, validate_design_lab
from station.formulate.solver import Problem
from station.model import ANGLES_3, ANGLES_5, AspecularMeasurements, FaceFlopTravelGloss
from station.model.design_io import design_to_dict
from station.model.domain import DEFAULT_MAX_COLORANTS, MAX_COLORANTS_RANGE
from station.model.fit import fit_fftg
from station.wire import wire_form


@dataclass(frozen=True)
class ColorantGamutReport:
    """Verdict of :func:`colorant_gamut`.

    ``inside``: the paint is formulable within ``tolerance``; ``mean_de``: the best recipe's predicted
    mean ΔE00 at 15/45/110°; ``nearest``: the paint that recipe makes (the paint itself when inside);
    ``formulation``: the formulation result (recipe, batch); ``message``: one sentence.
    """

    inside: bool
    mean_de: float
    tolerance: float
    nearest: FaceFlopTravelGloss
    formulation: FormulationResult
    message: str

    def to_dict(self) -> dict[str, object]:
        """JSON-able form: the recipe and whether its colorants are synthetic in place of the formulation."""
        return wire_form(
            self,
            rename={"inside": "inside_colorant_gamut", "nearest": "nearest_achievable_paint"},
            convert={"nearest": design_to_dict},
            omit={"formulation"},
            after={
                "tolerance": {"metric": "cie2000"},
                "formulation": {"recipe": self.formulation.recipe},
                "message": {"synthetic_colorants": self.formulation.synthetic},
            },
        )


def colorant_gamut(
    paint: FaceFlopTravelGloss,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    time_budget_s: float | None = None,
) -> ColorantGamutReport:
    """Whether *paint* can be mixed from the colorants, and the nearest achievable paint (module docstring).

    *time_budget_s* is accepted for compatibility and ignored: the formulator stops on counts only."""
    del time_budget_s
    db = db or default_database()
    lab = paint.lab_at(np.array(ANGLES_3))
    result = formulate(lab, ANGLES_3, gloss_gu=paint.gloss_gu, tolerance=tolerance, db=db)
    if result.formulable:
        nearest = paint
        msg = f"inside the colorant gamut: mean ΔE00 {result.mean_de:.2f} <= {tolerance:g}"
    else:
        five = predict_lab(result.concentrations, ANGLES_5, db)
        gloss = float(predict_gloss(result.concentrations, db))
        fit = fit_fftg(AspecularMeasurements(ANGLES_5, five, gloss))
        nearest = FaceFlopTravelGloss(
            fit.design.face, fit.design.flop, fit.design.travel_deg, fit.design.gloss_gu, "nearest achievable"
        )
        msg = (
            f"outside the colorant gamut: the best recipe misses by mean ΔE00 {result.mean_de:.2f} > "
            f"{tolerance:g}; nearest achievable paint face {np.round(nearest.face, 1).tolist()}, "
            f"flop {np.round(nearest.flop, 1).tolist()}"
        )
    return ColorantGamutReport(result.formulable, result.mean_de, float(tolerance), nearest, result, msg)


@dataclass(frozen=True)
class LineGamutReport:
    """Verdict of :func:`line_gamut`: ``inside`` when the best line-wide recipe's mean ΔE00 (over the
    design's angles, amounts unrounded) is at most ``tolerance``; ``line`` the line that came closest,
    ``recipe`` its recipe (mass fractions), ``per_line`` the best mean ΔE00 of every line tried."""

    inside: bool
    mean_de: float
    tolerance: float
    line: str
    recipe: dict[str, float]
    per_line: dict[str, float]


def line_gamut(
    design_lab: ArrayLike,
    angles_deg: tuple[float, ...] = ANGLES_3,
    gloss_gu: float | None = None,
    *,
    line: str | None = None,
    paint_type: str | None = None,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
) -> LineGamutReport:
    """Whether the toner line (named, else from *paint_type*, else from the design's type, as
    :func:`station.formulate.lines.lines_for_design` picks it) can mix the design with any amounts of
    all its colorants (module docstring). *starts*: starting recipes (e.g. ColorSnap matches' recipes)
    besides the generic ones; *gloss_gu* sets the matting agent (``None``: full gloss)."""
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    c_mat, _ = matting_for_gloss(GLOSS_CLEAR_GU if gloss_gu is None else gloss_gu, db)
    given = [
        (
            lb,
            db.check(
                db.vector(r) if isinstance(r, dict) else np.asarray(r, dtype=np.float64), f"starts[{lb}]"
            ),
        )
        for lb, r in starts or []
    ]
    best: tuple[float, str, dict[str, float]] = (np.inf, "", {})
    per_line: dict[str, float] = {}
    for name in lines_for_design(design, line, paint_type):
        prob, _, tried = line_wide_fit(design, angles, given, c_mat, db, name, MAX_STARTS, tolerance)
        c = prob.full(tried[0][2])
        de = float(cie2000(design, predict_lab(c, angles, db)).mean())
        per_line[name] = de
        if de < best[0]:
            best = (de, name, db.recipe(c))
        if de <= tolerance:
            break
    return LineGamutReport(best[0] <= tolerance, best[0], float(tolerance), best[1], best[2], per_line)


#: Screened subsets the N-colorant gamut check refits continuously (:func:`recipe_gamut`).
RECIPE_GAMUT_REFITS = 4
#: Fractions at or below this count as absent (the selection's threshold).
_PRESENT = 1e-6


def _checked_starts(
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None, db: ColorantDatabase
) -> list[tuple[str, NDArray[np.float64]]]:
    """The starting recipes as checked full vectors (a typed error naming ``starts[label]``)."""
    return [
        (
            lb,
            db.check(
                db.vector(r) if isinstance(r, dict) else np.asarray(r, dtype=np.float64), f"starts[{lb}]"
            ),
        )
        for lb, r in starts or []
    ]


def subset_gamut_fit(
    prob: Problem,
    seed: NDArray[np.float64],
    max_colorants: int,
    tolerance: float,
    refits: int = RECIPE_GAMUT_REFITS,
) -> tuple[float, NDArray[np.float64]]:
    """Best mean ΔE00 over the design's angles of a recipe of at most *max_colorants* of the problem's
    free colorants, and its full concentration vector (amounts unrounded): the line-wide point *seed*
    itself when it has that few colorants, else the best of the *refits* best subsets of the screen
    (:func:`station.formulate.selection.screen`), each refitted continuously — first the screen's
    ordinary pool; when that misses *tolerance* (mean ΔE00), the coarse pass over the wider pool.
    Counts only: deterministic."""
    db = prob.db

    def mean_de(c: NDArray[np.float64]) -> float:
        return float(cie2000(prob.design, predict_lab(c, prob.angles, db)).mean())

    if np.count_nonzero(seed > _PRESENT) <= max_colorants:
        c = prob.full(np.where(seed > _PRESENT, seed, 0.0))
        return mean_de(c), c
    best: tuple[float, NDArray[np.float64]] = (np.inf, prob.full(np.zeros_like(seed)))
    good_enough = (0.02 * len(prob.angles)) ** 2
    fitted: set[tuple[int, ...]] = set()
    for coarse in (0, SCREEN_COARSE_EVALUATIONS):
        for sub, x0 in screen(prob, seed, max_colorants, keep=refits, coarse_evaluations=coarse):
            if sub in fitted:
                continue
            fitted.add(sub)
            _, x, obj = fit_subset(prob, sub, x0)
            c = refine_subset(obj, x, good_enough)
            de = mean_de(c)
            if de < best[0]:
                best = (de, c)
        if best[0] <= tolerance:
            break
    return best


def recipe_gamut(
    design_lab: ArrayLike,
    angles_deg: tuple[float, ...] = ANGLES_3,
    gloss_gu: float | None = None,
    *,
    max_colorants: int = DEFAULT_MAX_COLORANTS,
    line: str | None = None,
    paint_type: str | None = None,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
) -> RecipeGamutReport:
    """Whether a recipe of at most *max_colorants* colorants of the toner line (chosen as by
    :func:`line_gamut`) can mix the design, amounts unrounded (module docstring: the N-colorant gamut);
    *starts* and *gloss_gu* as for :func:`line_gamut`. Bad *max_colorants*: a typed error naming it."""
    lo, hi = MAX_COLORANTS_RANGE
    if isinstance(max_colorants, bool) or not isinstance(max_colorants, int) or not lo <= max_colorants <= hi:
        raise FormulateInputError("max_colorants", f"an integer in [{lo}, {hi}]", max_colorants)
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    c_mat, _ = matting_for_gloss(GLOSS_CLEAR_GU if gloss_gu is None else gloss_gu, db)
    given = _checked_starts(starts, db)
    line_best: tuple[float, str] = (np.inf, "")
    best: tuple[float, str, NDArray[np.float64]] = (np.inf, "", np.zeros(len(db.names)))
    inside_lines: list[tuple[str, Problem, NDArray[np.float64]]] = []
    for name in lines_for_design(design, line, paint_type):
        prob, _, tried = line_wide_fit(design, angles, given, c_mat, db, name, MAX_STARTS, tolerance)
        de_line = float(cie2000(design, predict_lab(prob.full(tried[0][2]), angles, db)).mean())
        if de_line < line_best[0]:
            line_best = (de_line, name)
        if de_line > tolerance:
            continue
        inside_lines.append((name, prob, tried[0][2]))
        de, c = subset_gamut_fit(prob, tried[0][2], max_colorants, tolerance)
        if de < best[0]:
            best = (de, name, c)
        if de <= tolerance:
            break
    line_inside = line_best[0] <= tolerance
    inside = line_inside and best[0] <= tolerance
    needed = None
    if line_inside and not inside:
        needed = _fewest_colorants(inside_lines, max_colorants, tolerance)
    shown_line = best[1] or line_best[1]
    msg = _gamut_message(
        inside, line_inside, best[0], line_best[0], max_colorants, tolerance, shown_line, needed
    )
    recipe = db.recipe(best[2], _PRESENT) if best[1] else {}
    return RecipeGamutReport(
        inside,
        line_inside,
        float(best[0]),
        float(line_best[0]),
        max_colorants,
        float(tolerance),
        shown_line,
        recipe,
        needed,
        msg,
    )


def _fewest_colorants(
    inside_lines: list[tuple[str, Problem, NDArray[np.float64]]], max_colorants: int, tolerance: float
) -> int | None:
    """The fewest colorants above *max_colorants* (up to the allowed maximum) whose subset screen
    (:func:`subset_gamut_fit`) reaches *tolerance* on one of the lines whose gamut holds the design."""
    for n in range(max_colorants + 1, MAX_COLORANTS_RANGE[1] + 1):
        for _, prob, seed in inside_lines:
            if n <= prob.free.size and subset_gamut_fit(prob, seed, n, tolerance)[0] <= tolerance:
                return n
    return None


def _gamut_message(
    inside: bool,
    line_inside: bool,
    de: float,
    de_line: float,
    n: int,
    tolerance: float,
    line: str,
    needed: int | None,
) -> str:
    """One sentence: inside the N-colorant gamut, outside it only for the colorant limit, or outside the
    line's gamut."""
    if inside:
        return f"inside the {n}-colorant gamut of line {line}: best {n}-colorant screen ΔE00 {de:.2f} <= {tolerance:g}"
    if line_inside:
        more = (
            f"allow {needed} colorants (max colorants {needed})"
            if needed is not None
            else f"no recipe of up to {MAX_COLORANTS_RANGE[1]} colorants was found by the screen"
        )
        return (
            f"outside the {n}-colorant gamut of line {line}: best {n}-colorant screen ΔE00 {de:.2f}; "
            f"the line with more colorants reaches {de_line:.2f}; {more}"
        )
    return (
        f"outside the gamut of line {line}: with every colorant of the line the best mean ΔE00 is "
        f"{de_line:.2f} > {tolerance:g}"
    )


def formulate_in_gamut(
    design_lab: ArrayLike,
    library: Library,
    index: SnapIndex | None = None,
    k: int = 3,
    gloss_gu: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    types: Collection[str] | None = None,
    candidates: int = 0,
    options: FormulationOptions | None = None,
) -> tuple[FormulationResult, SnapResult]:
    """:func:`station.formulate.formulation.formulate_from_library` as the fronts ask it:
    when the best recipe misses *tolerance*, :func:`recipe_gamut` (same starts, line choice, gloss and
    colorant limit) says why; its report is the result's ``gamut`` and its sentence ends the message."""
    db = db or default_database()
    starts, opts, snap = library_starts(design_lab, library, index, k, db, types, options)
    design = validate_design_lab(design_lab, 3, "design_lab")
    result = formulate_with(design, STANDARD_ANGLES, starts, gloss_gu, tolerance, db, opts, candidates)
    if result.formulable:
        return result, snap
    report = recipe_gamut(
        design,
        STANDARD_ANGLES,
        gloss_gu,
        max_colorants=opts.max_colorants,
        line=opts.line,
        paint_type=opts.paint_type,
        starts=starts,
        tolerance=tolerance,
        db=db,
    )
    return replace(result, gamut=report, message=f"{result.message} {report.message}"), snap
