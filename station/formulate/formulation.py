"""Recipe formulation: a few colorants of the right toner line, weighable, the same every time.

Problem (per design, Lab at the angles θ_j, illumination 45°, D65/10°), over the colorants c of a
toner line (:mod:`station.formulate.lines`):

    minimise   Σ_j ΔE00(design_j, predict_lab(c)_j)²
    subject to 0 ≤ c_i ≤ max_fraction_i,  Σ_i c_i ≤ max_total − c_matting,
               Σ_{i ∈ flakes, pearls} c_i ≤ max_effect,

with :func:`station.formulate.colorants.predict_lab` (Kubelka–Munk per geometry + Saunderson). The
matting fraction is set in closed form from the gloss target (G = 90 − 650 c_matting) because it does
not change the colour in this model.

1. **Line-wide fit** (:mod:`station.formulate.solver`): weighted-Lab least squares from the starting
   recipes (the ColorSnap matches' recipes, then generic starts built from the line), at most
   ``max_starts`` of them, stopping early once a start comes within a fifth of the tolerance; then SLSQP
   on Σ ΔE00² from the best.
2. **Selection** (:mod:`station.formulate.selection`): subsets of at most ``max_colorants`` colorants
   refitted, rounded to the scale, and ranked by ΔE00 after rounding, metamerism index (A, F11), number
   of colorants and cost (the metamerism index computed for the best 2 × ``recipes`` only); the best
   ``recipes`` are returned, the first is the result's recipe.

Every stop is an iteration or evaluation count or a value of the objective: the same input gives the
same recipe on any machine at any load (no clock is read but to report ``elapsed_s``).

A design whose best mean ΔE00 over angles (after rounding) exceeds the tolerance (default 1.0) is
reported as "not formulable with these colorants".
"""

from __future__ import annotations

import time
from collections.abc import Collection, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.batch import DEFAULT_BATCH_G
from station.formulate.colorants import (
    GLOSS_CLEAR_GU,
    GLOSS_PER_MATTING,
    ColorantDatabase,
    default_database,
    predict_lab,
)
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError, NotFormulableError
from station.formulate.library import STANDARD_ANGLES, Library
from station.formulate.lines import lines_for_design, toner_line
from station.formulate.options import MAX_STARTS, FormulationOptions, formulation_options
from station.formulate.result import FormulationResult
from station.formulate.selection import (
    MAX_SUBSETS,
    REFINED,
    SCREEN_COARSE_EVALUATIONS,
    RecipeOption,
    eliminate,
    fit_subset,
    make_option,
    metamerism,
    rank_options,
    refine_subset,
    round_to_scale,
    screen,
    subsets,
)
from station.formulate.snap import SnapIndex, SnapResult, color_snap, validate_design_lab
from station.formulate.solver import Objective, Problem, fit_lab, refine_de00
from station.model.domain import (
    DEFAULT_MAX_COLORANTS,
    DEFAULT_RECIPE_COUNT,
    DEFAULT_SCALE_RESOLUTION_G,
    FORMULATION_TOLERANCE_DE00,
    GLOSS_MAX_GU,
    GLOSS_MIN_GU,
    METAMERISM_TEST_ILLUMINANTS,
)

#: Mean CIEDE2000 over the angles accepted as "formulable" (station.model.domain).
DEFAULT_TOLERANCE = FORMULATION_TOLERANCE_DE00
#: Fractions at or below this are dropped from a recipe (:meth:`ColorantDatabase.recipe`'s threshold).
_RECIPE_THRESHOLD = 1e-6
#: Line-wide points (best first) the backward elimination of the selection starts from.
ELIMINATED_POINTS = 2


def matting_for_gloss(gloss_gu: float, db: ColorantDatabase) -> tuple[float, str | None]:
    """Matting fraction giving *gloss_gu* (closed form), and a warning if the gloss is out of reach."""
    if not np.isfinite(gloss_gu) or not GLOSS_MIN_GU <= gloss_gu <= GLOSS_MAX_GU:
        raise FormulateInputError(
            "gloss_gu", f"{GLOSS_MIN_GU:g} <= gloss_gu <= {GLOSS_MAX_GU:g} GU", gloss_gu
        )
    ub = db.upper_bounds[db.matting_index]
    c = (GLOSS_CLEAR_GU - gloss_gu) / GLOSS_PER_MATTING
    if c < 0:
        return 0.0, f"gloss {gloss_gu:g} GU is above the clear coat's {GLOSS_CLEAR_GU:g} GU; using full gloss"
    if c > ub:
        g_min = GLOSS_CLEAR_GU - GLOSS_PER_MATTING * ub
        return float(
            ub
        ), f"gloss {gloss_gu:g} GU is below the reachable {g_min:.1f} GU; using the most matting"
    return float(c), None


def _generic_starts(
    db: ColorantDatabase, design: NDArray, angles: tuple[float, ...], allowed: NDArray[np.bool_]
) -> list[NDArray]:
    """A pool of generic starting recipes from the colorants *allowed*, best first by their
    multi-angle ΔE00 to the design.

    Bases: TiO2 white (two loadings), carbon black, each aluminium grade and each adjacent pair, each
    pearl and interference pigment (those the line allows); each with one tint, or two tints adjacent in
    hue, at a low and a high loading. One batched model evaluation ranks the whole pool.
    """
    names = db.names
    idx = {n: i for i, n in enumerate(names)}
    fam = {c.name: c.family for c in db.colorants}
    ok = {n for n, a in zip(names, allowed, strict=True) if a}
    tints = [n for n in names if fam[n] == "tint" and n in ok]
    alu = [n for n in names if fam[n] == "aluminium" and n in ok]
    bases: list[dict[str, float]] = [{"white_tio2": 0.05}, {"white_tio2": 0.15}, {"black_carbon": 0.01}]
    bases += [{a: 0.08} for a in alu] + [{alu[k]: 0.05, alu[k + 1]: 0.05} for k in range(len(alu) - 1)]
    effects = [n for n in names if fam[n] in ("pearl", "interference") and n in ok]
    bases += [{n: 0.08} for n in effects] + [{a: 0.04, e: 0.04} for a in alu for e in effects]
    bases = [b for b in bases if set(b) <= ok]
    mixes = [[t] for t in tints] + [[tints[k], tints[(k + 1) % len(tints)]] for k in range(len(tints))] + [[]]
    pool = []
    for base in bases:
        for mix in mixes:
            for amount in (0.01, 0.04):
                c = np.zeros(len(names))
                for n, v in base.items():
                    c[idx[n]] = v
                for t in mix:
                    c[idx[t]] += amount / max(len(mix), 1)
                pool.append(c)
    c = np.unique(np.asarray(pool), axis=0)  # a base without tint is the same at both loadings
    f = (cie2000(design[None], predict_lab(c, angles, db)) ** 2).sum(-1)
    return [c[k] for k in np.argsort(f, kind="stable")[:6]]


@dataclass
class _LineFit:
    """What one toner line gave: ranked-to-be options, the starts' points, evaluations spent."""

    options: list[RecipeOption]
    tried: list[tuple[str, NDArray[np.float64]]]
    evaluations: int


def line_wide_fit(
    design: NDArray,
    angles: tuple[float, ...],
    starts: Sequence[tuple[str, NDArray[np.float64]]],
    c_mat: float,
    db: ColorantDatabase,
    line: str,
    max_starts: int,
    tolerance: float,
    candidates: int = 0,
) -> tuple[Problem, Objective, list[tuple[str, float, NDArray[np.float64]]]]:
    """Step 1 of the module docstring on one toner line, every colorant of it free, amounts unrounded:
    weighted-Lab fits from the starts (given ones, then :func:`_generic_starts`), at most
    ``max(max_starts, candidates)`` of them, stopping once ``candidates`` are fitted and one is within
    a fifth of the tolerance; SLSQP on Σ ΔE00² from the best unless it already is. Returns the problem,
    its objective (evaluation count) and the fitted ``(label, Σ ΔE00², free point)``, best first."""
    allowed = toner_line(line).mask(db)
    fixed = np.zeros(len(db.names))
    fixed[db.matting_index] = c_mat
    prob = Problem(design, angles, db, np.flatnonzero(allowed), fixed)
    obj = Objective(prob)
    xs = [(lb, np.where(allowed, v, 0.0)[prob.free]) for lb, v in starts]
    xs += [("generic", s[prob.free]) for s in _generic_starts(db, design, angles, allowed)]
    good_enough = (0.02 * min(tolerance, 1.0)) ** 2 * len(angles)  # Σ ΔE00² of a mean ΔE00 of ~0.02
    enough = (0.2 * min(tolerance, 1.0)) ** 2 * len(angles)  # Σ ΔE00² of a mean ΔE00 of 0.2 × tolerance
    tried: list[tuple[str, float, NDArray[np.float64]]] = []
    for label, x0 in xs[: max(max_starts, candidates)]:
        if tried and len(tried) >= candidates and min(t[1] for t in tried) <= enough:
            break
        f, x = fit_lab(obj, x0)
        tried.append((label, f, x))
    tried.sort(key=lambda t: t[1])  # stable: equal values keep the starts' order
    if tried[0][1] > enough:
        f, x = refine_de00(obj, tried[0][2], good_enough)
        tried[0] = (tried[0][0], f, x)
    return prob, obj, tried


def _fit_line(
    design: NDArray,
    angles: tuple[float, ...],
    starts: Sequence[tuple[str, NDArray[np.float64]]],
    c_mat: float,
    db: ColorantDatabase,
    line: str,
    opts: FormulationOptions,
    tolerance: float,
    candidates: int,
    more_lines: bool = False,
) -> _LineFit:
    """Line-wide fit from the starts, then the subset search, rounding and scoring (module docstring).

    With *more_lines* (another line follows) a line whose line-wide fit leaves Σ_j ΔE00² above n² × the
    tolerance² (n angles) gives no options: a subset's Σ ΔE00² is at least the line's, and a mean over n
    angles is at least the root-mean-square over √n, so no subset of it can reach the tolerance."""
    prob, obj, tried = line_wide_fit(
        design, angles, starts, c_mat, db, line, opts.max_starts, tolerance, candidates
    )
    good_enough = (0.02 * min(tolerance, 1.0)) ** 2 * len(angles)
    points = [t[2] for t in tried]
    if more_lines and tried[0][1] > (len(angles) * tolerance) ** 2:
        return _LineFit([], [(lb, prob.full(x)) for lb, _, x in tried], obj.evaluations)
    step = opts.scale_resolution_g / opts.batch_g
    spec_base = (opts.batch_g, opts.scale_resolution_g, tolerance, line)
    evaluations = obj.evaluations
    proposals: list[tuple[tuple[int, ...], NDArray[np.float64], str]] = []
    for label, _, point in tried[:ELIMINATED_POINTS]:
        for sub, x0 in eliminate(prob, point, opts.max_colorants):
            if all(sub != s for s, _, _ in proposals):
                proposals.append((sub, x0, label))
    for sub, x0 in screen(prob, points[0], opts.max_colorants):
        if all(sub != s for s, _, _ in proposals):
            proposals.append((sub, x0, tried[0][0]))
    for sub in subsets(points, opts.max_colorants):
        if len(proposals) >= MAX_SUBSETS:
            break
        if all(sub != s for s, _, _ in proposals):
            k = int(np.argmax([p[list(sub)].sum() for p in points]))
            proposals.append((sub, points[k], tried[k][0]))
    options, evaluations = _fit_proposals(prob, proposals, good_enough, step, spec_base, evaluations)
    if not any(o.mean_de <= tolerance for o in options):  # a miss: screen a wider pool of the line
        wider = [
            (sub, x0, tried[0][0])
            for sub, x0 in screen(
                prob, points[0], opts.max_colorants, coarse_evaluations=SCREEN_COARSE_EVALUATIONS
            )
            if all(sub != s for s, _, _ in proposals)
        ]
        more, evaluations = _fit_proposals(prob, wider, good_enough, step, spec_base, evaluations)
        options += more
    return _LineFit(options, [(lb, prob.full(x)) for lb, _, x in tried], evaluations)


def _fit_proposals(
    prob: Problem,
    proposals: list[tuple[tuple[int, ...], NDArray[np.float64], str]],
    good_enough: float,
    step: float,
    spec_base: tuple[float, float, float, str],
    evaluations: int,
) -> tuple[list[RecipeOption], int]:
    """Fit each proposed subset (indices into ``prob.free``, start, label), refine the best
    :data:`REFINED`, round to the scale's *step* (fraction) and score: the options and the model
    evaluations counted so far."""
    fitted: list[tuple[float, int, NDArray[np.float64], Objective, str]] = []
    for sub, x0, label in proposals:
        f, x, sub_obj = fit_subset(prob, sub, x0)
        fitted.append((f, len(fitted), x, sub_obj, label))
    fitted.sort(key=lambda t: (t[0], t[1]))
    rows: list[tuple[NDArray[np.float64], NDArray[np.float64], str]] = []
    for n, (_, _, x, sub_obj, label) in enumerate(fitted):
        c = refine_subset(sub_obj, x, good_enough) if n < REFINED else sub_obj.p.full(x)
        evaluations += sub_obj.evaluations
        rows.append((round_to_scale(c, prob, step, prob.db.matting_index), c, label))
    options = [make_option(c_r, c, prob, None, (*spec_base, label)) for c_r, c, label in rows]
    return options, evaluations


def formulate(
    design_lab: ArrayLike,
    angles_deg: tuple[float, ...] = STANDARD_ANGLES,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    gloss_gu: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    time_budget_s: float | None = None,
    strict: bool = False,
    candidates: int = 0,
    *,
    line: str | None = None,
    paint_type: str | None = None,
    max_colorants: int = DEFAULT_MAX_COLORANTS,
    scale_resolution_g: float = DEFAULT_SCALE_RESOLUTION_G,
    batch_g: float = DEFAULT_BATCH_G,
    recipes: int = DEFAULT_RECIPE_COUNT,
    illuminants: tuple[str, ...] = METAMERISM_TEST_ILLUMINANTS,
    max_starts: int = MAX_STARTS,
) -> FormulationResult:
    """Formulate the best few recipes for the design (see module docstring).

    Parameters
    ----------
    design_lab
        Design L*a*b* per angle, shape (A, 3).
    angles_deg
        The angles (degrees) of *design_lab*.
    starts
        ``[(label, recipe)]`` starting recipes, best first (e.g. the ColorSnap matches' recipes); a
        recipe is a vector or ``{colorant: fraction}``; colorants outside the toner line are dropped.
    gloss_gu
        60° gloss target (GU); ``None`` keeps full gloss (no matting agent).
    tolerance
        Mean predicted ΔE00 (after rounding) over angles above which the design is "not formulable".
    time_budget_s
        Accepted for compatibility and ignored: every stop is a count, so no clock changes the result.
    strict
        Raise :class:`NotFormulableError` instead of returning an unformulable result.
    candidates
        Fit at least this many starts and keep each distinct recipe they reach as
        :attr:`FormulationResult.candidates` (0: stop at the first good enough).
    line, paint_type
        The toner line (default: from *paint_type*, else from the design's type; :mod:`~station.formulate.lines`).
    max_colorants, scale_resolution_g, batch_g, recipes
        At most this many colorants (binder and matting agent not counted), amounts rounded to this
        resolution (g) in a batch of this mass (g), and this many recipes returned.
    illuminants
        Test illuminants of the metamerism index (reference D65).
    max_starts
        Starting recipes fitted at most per toner line.
    """
    del time_budget_s
    options = FormulationOptions(
        line, paint_type, max_colorants, scale_resolution_g, batch_g, recipes, tuple(illuminants), max_starts
    )
    return formulate_with(
        design_lab, angles_deg, starts, gloss_gu, tolerance, db, options, candidates, strict
    )


def _ranked_options(
    design: NDArray,
    angles: tuple[float, ...],
    starts: Sequence[tuple[str, NDArray[np.float64]]],
    c_mat: float,
    db: ColorantDatabase,
    opts: FormulationOptions,
    tolerance: float,
    candidates: int,
) -> tuple[tuple[RecipeOption, ...], list[tuple[str, _LineFit]]]:
    """Each toner line in turn until one reaches the design; the recipes ranked, the metamerism index
    computed for the best 2 × ``recipes`` (it costs a constrained fit of the reference reflectance)."""
    pool: list[RecipeOption] = []
    fits: list[tuple[str, _LineFit]] = []
    lines = lines_for_design(design, opts.line, opts.paint_type)
    for n, line in enumerate(lines):
        more = n + 1 < len(lines)
        fit = _fit_line(design, angles, starts, c_mat, db, line, opts, tolerance, candidates, more)
        fits.append((line, fit))
        pool += fit.options
        if pool and rank_options(pool, 1)[0].formulable:
            break
    shortlist = rank_options(pool, 2 * opts.recipes)
    meta = metamerism(design, np.asarray([o.concentrations for o in shortlist]), angles, db, opts.illuminants)
    ranked = rank_options(
        [replace(o, metamerism=m) for o, m in zip(shortlist, meta, strict=True)], opts.recipes
    )
    return ranked, fits


def _checked_inputs(
    design_lab: ArrayLike,
    angles: tuple[float, ...],
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None,
    tolerance: float,
    db: ColorantDatabase,
) -> tuple[NDArray[np.float64], list[tuple[str, NDArray[np.float64]]]]:
    """The design (A, 3) and the starting recipes as checked full vectors; bad input raises
    :class:`FormulateInputError` naming the field."""
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise FormulateInputError("tolerance", "a positive ΔE00", tolerance)
    starts_c = []
    for lb, rec in starts or []:
        vec = db.vector(rec) if isinstance(rec, dict) else np.asarray(rec, dtype=np.float64)
        starts_c.append((lb, db.check(vec, f"starts[{lb}]")))
    return design, starts_c


def _result(
    design: NDArray,
    angles: tuple[float, ...],
    db: ColorantDatabase,
    ranked: tuple[RecipeOption, ...],
    fits: list[tuple[str, _LineFit]],
    tolerance: float,
    c_mat: float,
    warn: str | None,
    strict: bool,
    candidates: int,
    t0: float,
) -> FormulationResult:
    """The :class:`FormulationResult` of the first-ranked recipe."""
    best = ranked[0]
    c = best.concentrations
    pred = predict_lab(c, angles, db)
    mean_de = best.mean_de
    message = (
        f"formulated: mean ΔE00 {mean_de:.2f} over {len(angles)} angles after rounding to "
        f"{best.scale_resolution_g:g} g (tolerance {tolerance:g}), {best.colorants} colorants of the "
        f"{best.line} line"
        if best.formulable
        else f"not formulable with these colorants: best mean ΔE00 {mean_de:.2f} > tolerance {tolerance:g};"
        " the nearest achievable paint is the prediction of the best recipe (nearest_achievable_lab)"
    )
    if strict and not best.formulable:
        raise NotFormulableError(message)
    tried = [t for line, fit in fits if line == best.line for t in fit.tried]
    warnings = [warn] if warn else []
    if best.metamerism is None:
        warnings.append("metamerism index not computed: no reflectance reproduces the design's Lab")
    return FormulationResult(
        recipe=best.recipe,
        concentrations=c,
        angles_deg=angles,
        design_lab=design,
        predicted_lab=pred,
        de_per_angle=best.de_per_angle,
        mean_de=mean_de,
        max_de=max(best.de_per_angle),
        formulable=best.formulable,
        tolerance=tolerance,
        gloss_gu=float(GLOSS_CLEAR_GU - GLOSS_PER_MATTING * c[db.matting_index]),
        start=best.start,
        message=message,
        elapsed_s=time.perf_counter() - t0,
        evaluations=sum(f.evaluations for _, f in fits),
        synthetic=db.synthetic,
        warnings=tuple(warnings),
        candidates=_distinct(best.start, c, tried) if candidates else (),
        line=best.line,
        recipes=ranked,
        mean_de_unrounded=best.mean_de_unrounded,
    )


def _distinct(
    label: str, winner: NDArray, tried: list[tuple[str, NDArray]]
) -> tuple[tuple[str, NDArray[np.float64]], ...]:
    """The winning recipe first, then each recipe *tried* that differs from every one kept (by more than
    1e-4 in some fraction), the reported threshold applied to each."""
    kept: list[tuple[str, NDArray[np.float64]]] = [(label, winner)]
    for lb, x in tried:
        x = np.where(x <= _RECIPE_THRESHOLD, 0.0, x)
        if all(np.max(np.abs(x - k)) > 1e-4 for _, k in kept):
            kept.append((lb, x))
    return tuple(kept)


def formulate_from_library(
    design_lab: ArrayLike,
    library: Library,
    index: SnapIndex | None = None,
    k: int = 3,
    gloss_gu: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    time_budget_s: float | None = None,
    types: Collection[str] | None = None,
    candidates: int = 0,
    options: FormulationOptions | None = None,
) -> tuple[FormulationResult, SnapResult]:
    """ColorSnap (CIEDE2000) the design against a library with recipes, then formulate from the
    *k* best matches' recipes (thesis §5.3.4–5.3.5: the match is the formulation starting point).

    *types* restricts the matches (and so the starting recipes) to those paint types (``solid``,
    ``metallic``, ``pearl``); ``None`` searches every paint. Unless ``line`` is given the toner line
    follows the paint type: the single type of *types*, else the best match's type.
    *time_budget_s* is ignored (see :func:`formulate`); *candidates*: see :func:`formulate`; *options*
    the chemist's limits (:class:`FormulationOptions`, default ones when ``None``)."""
    del time_budget_s
    db = db or default_database()
    starts, opts, snap = library_starts(design_lab, library, index, k, db, types, options)
    design = validate_design_lab(design_lab, 3, "design_lab")
    result = formulate_with(design, STANDARD_ANGLES, starts, gloss_gu, tolerance, db, opts, candidates)
    return result, snap


def library_starts(
    design_lab: ArrayLike,
    library: Library,
    index: SnapIndex | None = None,
    k: int = 3,
    db: ColorantDatabase | None = None,
    types: Collection[str] | None = None,
    options: FormulationOptions | None = None,
) -> tuple[list[tuple[str, ArrayLike | dict[str, float]]], FormulationOptions, SnapResult]:
    """The starting recipes of :func:`formulate_from_library` (the *k* best ColorSnap matches' recipes),
    the options with the paint type that picks the toner line filled in, and the ColorSnap result."""
    if library.recipes is None or library.colorant_names is None:
        raise FormulateInputError("library", "a library with recipes (the demo library)", library.name)
    db = db or default_database()
    if tuple(library.colorant_names) != db.names:
        raise FormulateInputError(
            "library.colorant_names", f"the colorants {db.names}", library.colorant_names
        )
    design = validate_design_lab(design_lab, 3, "design_lab")
    snap = color_snap(library, design, k=k, method="cie2000", index=index, types=types)
    recipes = library.recipes
    starts: list[tuple[str, ArrayLike | dict[str, float]]] = [
        (m.code, recipes[m.index]) for m in snap.matches
    ]
    opts = options or FormulationOptions()
    if opts.line is None and opts.paint_type is None:
        kinds = sorted(set(types)) if types else []
        if len(kinds) == 1:
            opts = replace(opts, paint_type=kinds[0])
        elif snap.matches:
            opts = replace(opts, paint_type=str(library.types[snap.matches[0].index]))
    return starts, opts, snap


def formulate_with(
    design_lab: ArrayLike,
    angles_deg: tuple[float, ...],
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None,
    gloss_gu: float | None,
    tolerance: float,
    db: ColorantDatabase | None,
    options: FormulationOptions,
    candidates: int = 0,
    strict: bool = False,
) -> FormulationResult:
    """:func:`formulate` with the chemist's limits as one :class:`FormulationOptions` (checked here by
    :func:`formulation_options`); the other arguments as for :func:`formulate`."""
    if not isinstance(candidates, int) or candidates < 0:
        raise FormulateInputError("candidates", "a count >= 0", candidates)
    opts = formulation_options(replace(options, illuminants=tuple(options.illuminants)))
    t0 = time.perf_counter()
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design, starts_c = _checked_inputs(design_lab, angles, starts, tolerance, db)
    c_mat, warn = matting_for_gloss(GLOSS_CLEAR_GU if gloss_gu is None else gloss_gu, db)
    ranked, fits = _ranked_options(design, angles, starts_c, c_mat, db, opts, float(tolerance), candidates)
    return _result(design, angles, db, ranked, fits, float(tolerance), c_mat, warn, strict, candidates, t0)
