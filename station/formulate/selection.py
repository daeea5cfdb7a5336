"""Colorant selection: recipes of a few colorants, weighable on the lab's scale, ranked as a chemist
compares them.

From the points the line-wide fit reached (:mod:`station.formulate.formulation`), :func:`subsets`
proposes colorant subsets of at most ``max_colorants`` colorants (the binder and the matting agent not
counted): for each point its ``max_colorants`` largest fractions, that set with one of the next two
colorants swapped in for its smallest ones, and that set less its smallest colorant (a simpler
alternative). Each subset is refitted on its own colorants (:func:`station.formulate.solver.fit_lab`;
the best :data:`REFINED` of them further by :func:`~station.formulate.solver.refine_de00`) and its recipe **rounded to the scale**: every
amount of a batch of ``batch_g`` grams to a multiple of ``scale_resolution_g`` (an amount under half
the resolution becomes 0) — at the load, among :data:`LOAD_FACTORS` × the fitted one, that rounds best
(a Kubelka–Munk colour depends mostly on the ratios of the colorants) — then a few steps of ±1 resolution on one colorant at a time while that lowers
Σ ΔE00² (:func:`round_to_scale`). The ΔE00 is reported before and after rounding.

Ranking (:func:`rank_options`), best first: formulable after rounding; the lower mean ΔE00 after
rounding, compared at :data:`RANK_DE_RESOLUTION`; the lower worst metamerism index over the test
illuminants (:data:`station.model.domain.METAMERISM_TEST_ILLUMINANTS`, A and F11) and the angles, at
the same resolution; fewer colorants; the lower cost per kg (:func:`station.formulate.lines.cost_per_kg`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations
from math import comb

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import nnls

from station.formulate.batch import batch_masses
from station.formulate.colorants import ColorantDatabase, predict_lab, predict_reflectance
from station.formulate.de_kernels import cie2000
from station.formulate.lines import cost_per_kg
from station.formulate.solver import Objective, Problem, fit_lab, lab_weights, refine_de00
from station.model.errors import ModelInputError
from station.model.illuminants import REFERENCE_ILLUMINANT
from station.model.spectra import metamerism_index, reflectance_from_lab
from station.wire import wire_form

#: ΔE00 and metamerism indices closer than this rank as equal.
RANK_DE_RESOLUTION = 0.1
#: Most subsets refitted per formulation (a count, so the same input always gives the same recipes).
MAX_SUBSETS = 10
#: Weighted-Lab evaluations per subset fit, and SLSQP iterations for the best :data:`REFINED` subsets.
SUBSET_NFEV = 15
SUBSET_MAXITER = 25
REFINED = 3
#: Loads (factors on every colorant but the matting agent) tried before rounding.
LOAD_FACTORS = (1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 12.0)
#: Passes of ±1 resolution steps after rounding.
ROUND_PASSES = 4
#: Most subsets of the linearised screen (:func:`screen`), its Gauss–Newton steps, their damping
#: (Levenberg–Marquardt, relative to the diagonal) and the subsets it hands on.
SCREEN_LIMIT = 126
SCREEN_STEPS = 8
SCREEN_DAMPING = 1e-2
SCREEN_KEEP = 4
#: The screen's coarse pass over a wider pool (a formulation that misses its tolerance): its Gauss–Newton
#: steps, and the most batched model evaluations it may take (subsets × (colorants + 1) × steps), which
#: sets how wide the pool may grow (13 colorants for 5-colorant recipes).
SCREEN_COARSE_STEPS = 2
SCREEN_COARSE_EVALUATIONS = 16_000
#: Points kept per step of the backward elimination (:func:`eliminate`).
ELIMINATION_BEAM = 3
#: Forward-difference step of the elimination's Jacobian (mass fraction).
_FD_STEP = 1e-7
#: Fractions at or below this count as absent before rounding.
_PRESENT = 1e-6


@dataclass(frozen=True)
class RecipeOption:
    """One recipe as the chemist weighs it out.

    ``recipe``: mass fractions after rounding; ``grams``: grams per colorant in a batch of ``batch_g``
    (multiples of ``scale_resolution_g``); ``mean_de``/``de_per_angle``: CIEDE2000 to the design after
    rounding, ``mean_de_unrounded`` before; ``metamerism``: worst index over the angles per test
    illuminant (``None`` when no reflectance reproduces the design, e.g. a specular L* over 100);
    ``colorants``: their number (binder and matting agent not counted); ``cost_per_kg`` in the data
    file's invented currency units.
    """

    rank: int
    recipe: dict[str, float]
    concentrations: NDArray[np.float64]
    grams: dict[str, float]
    binder_g: float
    batch_g: float
    scale_resolution_g: float
    de_per_angle: tuple[float, ...]
    mean_de: float
    mean_de_unrounded: float
    metamerism: dict[str, float] | None
    colorants: int
    cost_per_kg: float
    formulable: bool
    line: str
    start: str

    @property
    def worst_mi(self) -> float:
        """Largest metamerism index over the test illuminants (0 when not computed)."""
        return max(self.metamerism.values()) if self.metamerism else 0.0

    def to_dict(self) -> dict[str, object]:
        """JSON-able form (every field but the concentration vector)."""
        return wire_form(self, rename={"metamerism": "metamerism_index"}, omit={"concentrations"})


def subsets(points: Sequence[NDArray[np.float64]], max_colorants: int) -> list[tuple[int, ...]]:
    """Candidate colorant subsets (indices into the points' vectors), in proposal order (module doc)."""
    out: list[tuple[int, ...]] = []

    def add(s: Sequence[int]) -> None:
        key = tuple(sorted(int(i) for i in s))
        if key and key not in out:
            out.append(key)

    for x in points:
        order = [int(i) for i in np.argsort(-x, kind="stable") if x[i] > _PRESENT]
        top = order[:max_colorants]
        add(top)
        for extra in order[max_colorants : max_colorants + 2]:
            for drop in top[-2:]:
                add([i for i in top if i != drop] + [extra])
        if len(top) > 1:
            add(top[:-1])
    return out[:MAX_SUBSETS]


def _pool(base: Problem, seed: NDArray[np.float64], k: int, limit: int) -> list[int]:
    """The colorants (indices into ``base.free``) the screen combines: the seed's colorants by what
    removing each costs in Σ ΔE00², then the absent ones by how much adding a little helps (the
    forward difference of Σ ΔE00²), as many as keep C(pool, k) within *limit*."""
    n = base.free.size
    size = k
    while size < n and comb(size + 1, k) <= limit:
        size += 1
    present = np.flatnonzero(seed > _PRESENT)
    absent = np.flatnonzero(seed <= _PRESENT)
    drop = np.repeat(seed[None], present.size, axis=0)
    drop[np.arange(present.size), present] = 0.0
    add = np.repeat(seed[None], absent.size, axis=0)
    add[np.arange(absent.size), absent] += 1e-3
    f = base.sum_sq(np.vstack([seed[None], drop, add]))
    by_cost = present[np.argsort(-(f[1 : 1 + present.size] - f[0]), kind="stable")]
    by_gain = absent[np.argsort(f[1 + present.size :] - f[0], kind="stable")]
    return [int(i) for i in np.concatenate([by_cost, by_gain])[:size]]


def screen(
    base: Problem,
    seed: NDArray[np.float64],
    max_colorants: int,
    keep: int = SCREEN_KEEP,
    limit: int = SCREEN_LIMIT,
    coarse_evaluations: int = 0,
) -> list[tuple[tuple[int, ...], NDArray[np.float64]]]:
    """A cheap linearised first pass over every subset of ``max_colorants`` colorants of a pool
    (:func:`_pool`; a *limit* of C(line, max_colorants) or more screens every subset of the line, as a
    brute-force check does): all subsets at once, each started at the seed's load split evenly,
    :data:`SCREEN_STEPS` damped Gauss–Newton steps on the weighted Lab residual
    (:func:`station.formulate.solver.lab_weights`) with one batched model evaluation per step, clipped
    to the bounds and scaled into the total and effect limits. With *coarse_evaluations* the pool is as
    wide as a coarse pass of :data:`SCREEN_COARSE_STEPS` steps allows within that many batched model
    evaluations (subsets × (colorants + 1) × steps; at least *limit* subsets); when it holds more than
    *limit* subsets, the *limit* best after the coarse pass take the remaining steps. Returns the *keep* subsets of lowest Σ ΔE00² with their points (free
    fractions). Counts only: deterministic."""
    n = base.free.size
    k = min(max_colorants, n)
    wide = max(limit, coarse_evaluations // ((k + 1) * SCREEN_COARSE_STEPS))
    combos = np.array(list(combinations(sorted(_pool(base, seed, k, wide)), k)), dtype=np.intp)
    xs = np.minimum(np.full(combos.shape, max(float(seed.sum()), 1e-3) / k), base.upper[combos])
    best = (np.full(combos.shape[0], np.inf), xs.copy())
    steps = SCREEN_STEPS
    if combos.shape[0] > limit:  # coarse pass, then the best *limit* subsets go on from where they are
        xs, best = _gauss_newton(base, combos, xs, SCREEN_COARSE_STEPS - 1, best)
        go_on = np.sort(np.argsort(best[0], kind="stable")[:limit])
        combos, xs, best = combos[go_on], xs[go_on], (best[0][go_on], best[1][go_on])
        steps = SCREEN_STEPS - SCREEN_COARSE_STEPS + 1
    _, (_, best_x) = _gauss_newton(base, combos, xs, steps, best)
    m = combos.shape[0]
    points = np.zeros((m, n))
    points[np.arange(m)[:, None], combos] = best_x
    f = base.sum_sq(points)
    out: list[tuple[tuple[int, ...], NDArray[np.float64]]] = []
    for j in np.argsort(f, kind="stable"):
        key = tuple(int(i) for i in np.flatnonzero(points[j] > _PRESENT))
        if key and key not in [o for o, _ in out]:
            out.append((key, points[j]))
        if len(out) == keep:
            break
    return out


def _gauss_newton(
    base: Problem,
    combos: NDArray[np.intp],
    xs: NDArray[np.float64],
    steps: int,
    best: tuple[NDArray[np.float64], NDArray[np.float64]],
) -> tuple[NDArray[np.float64], tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """*steps* damped Gauss–Newton steps of :func:`screen` for every subset (rows of *combos*, indices
    into ``base.free``) from its point *xs* (free fractions of its colorants), with *steps* + 1 batched
    model evaluations; returns the last point and the (weighted-Lab Σ r², point) of the best one seen,
    *best* updated in place."""
    m, k = combos.shape
    n = base.free.size
    rows = np.arange(m)[:, None]
    upper = base.upper[combos]
    effect = base.effect[combos]
    weight = lab_weights(base.design).ravel()
    eye = np.eye(k)
    best_r, best_x = best
    for step in range(steps + 1):
        pts = np.zeros((m, k + 1, n))
        pts[rows, 0, combos] = xs
        for j in range(k):
            pts[rows, j + 1, combos] = xs
            pts[np.arange(m), j + 1, combos[:, j]] += _FD_STEP
        lab = predict_lab(base.full(pts.reshape(-1, n)), base.angles, base.db).reshape(m, k + 1, -1)
        r = (lab - base.design.ravel()) * weight
        norm = (r[:, 0] ** 2).sum(-1)
        better = norm < best_r
        best_r[better], best_x[better] = norm[better], xs[better]
        if step == steps:
            break
        jac = (r[:, 1:] - r[:, :1]) / _FD_STEP  # (m, k, 9)
        jtj = jac @ jac.transpose(0, 2, 1)
        grad = jac @ r[:, 0, :, None]
        damp = SCREEN_DAMPING * (np.einsum("mii->mi", jtj)[:, :, None] * eye + 1e-12 * eye)
        xs = np.clip(xs - np.linalg.solve(jtj + damp, grad)[..., 0], 0.0, upper)
        over_e = (xs * effect).sum(-1) / base.db.max_effect
        xs = np.where(effect > 0, xs / np.maximum(over_e, 1.0)[:, None], xs)
        xs = xs / np.maximum(xs.sum(-1) / base.max_total, 1.0)[:, None]
    return xs, (best_r, best_x)


def eliminate(
    base: Problem, x: NDArray[np.float64], max_colorants: int, beam: int = ELIMINATION_BEAM
) -> list[tuple[tuple[int, ...], NDArray[np.float64]]]:
    """Subsets of at most *max_colorants* colorants (indices into ``base.free``) by backward
    elimination from the line-wide point *x*, ranked by their contribution to the colour, not their mass.

    At each step every colorant of each kept point is removed in turn and the others re-balanced by one
    linearised step: the weighted Lab residual (:func:`station.formulate.solver.lab_weights`) with its
    forward-difference Jacobian at the point, solved by non-negative least squares, the result clipped
    to the bounds; all these candidates are scored by Σ ΔE00² in one batched model evaluation and the
    *beam* best (distinct colorant sets) kept. A colorant that weighs little but colours much (carbon
    black at 0.1 %) costs much when removed, so it stays. Ends when every kept point has at most
    *max_colorants* colorants; returns their sets with their points (free fractions), best first. A
    fixed number of steps: deterministic."""
    weight = lab_weights(base.design).ravel()
    states: list[NDArray[np.float64]] = [np.where(np.asarray(x) > _PRESENT, x, 0.0)]
    done: list[tuple[float, tuple[int, ...], NDArray[np.float64]]] = []
    while states:
        pending = [s for s in states if np.count_nonzero(s) > max_colorants]
        for s in states:
            if np.count_nonzero(s) <= max_colorants:
                done.append((float(base.sum_sq(s)), tuple(int(i) for i in np.flatnonzero(s)), s))
        if not pending:
            break
        cands: list[NDArray[np.float64]] = []
        for s in pending:
            support = np.flatnonzero(s)
            pts = np.repeat(s[None], support.size + 1, axis=0)
            pts[np.arange(1, support.size + 1), support] += _FD_STEP
            lab = predict_lab(base.full(pts), base.angles, base.db)
            r = ((lab - base.design[None]).reshape(support.size + 1, -1)) * weight
            jac = ((r[1:] - r[0]) / _FD_STEP).T  # (9, |support|)
            for k, i in enumerate(support):
                keep = np.delete(np.arange(support.size), k)
                # r(y) ≈ r0 + J (y − s): find y ≥ 0 on the kept colorants, y_i = 0
                target = jac @ s[support] - r[0]
                y, _ = nnls(jac[:, keep], target)
                c = np.zeros_like(s)
                c[support[keep]] = y
                c = base.project(c)
                c[i] = 0.0
                cands.append(np.where(c > _PRESENT, c, 0.0))
        scores = base.sum_sq(np.asarray(cands))
        states, seen = [], set[tuple[int, ...]]()
        for k in np.argsort(scores, kind="stable"):
            key = tuple(int(i) for i in np.flatnonzero(cands[k]))
            if key in seen or not key:
                continue
            seen.add(key)
            states.append(cands[k])
            if len(states) == beam:
                break
    done.sort(key=lambda t: t[0])
    out: list[tuple[tuple[int, ...], NDArray[np.float64]]] = []
    for _, key, point in done:
        if key and key not in [k for k, _ in out]:
            out.append((key, point))
    return out


def fit_subset(
    base: Problem, subset: tuple[int, ...], x0: NDArray[np.float64]
) -> tuple[float, NDArray[np.float64], Objective]:
    """Weighted-Lab fit of the colorants *subset* (indices into ``base.free``) from *x0*; returns
    (Σ ΔE00², free point, the subset's objective, for :func:`refine_subset`)."""
    free = base.free[list(subset)]
    obj = Objective(Problem(base.design, base.angles, base.db, free, base.fixed))
    f, x = fit_lab(obj, x0[list(subset)], max_nfev=SUBSET_NFEV)
    return f, x, obj


def refine_subset(obj: Objective, x: NDArray[np.float64], good_enough: float) -> NDArray[np.float64]:
    """SLSQP on Σ ΔE00² of a subset fit (:data:`SUBSET_MAXITER` iterations); the full vector."""
    _, x = refine_de00(obj, x, good_enough, maxiter=SUBSET_MAXITER)
    return obj.p.full(x)


def round_to_scale(
    c: NDArray[np.float64], base: Problem, step: float, matting_index: int
) -> NDArray[np.float64]:
    """Round every fraction of *c* to a multiple of *step* (= resolution / batch), then take ±1 steps
    on single colorants while Σ ΔE00² falls (at most :data:`ROUND_PASSES` passes)."""
    db = base.db
    c = np.asarray(c, dtype=np.float64)
    colorant = np.arange(c.size) != matting_index

    def feasible(u: NDArray[np.float64]) -> bool:
        x = u * step
        return bool(
            np.all(x <= db.upper_bounds + 1e-12)
            and x.sum() <= db.max_total + 1e-12
            and x[db.effect_mask].sum() <= db.max_effect + 1e-12
        )

    def score(u: NDArray[np.float64]) -> NDArray[np.float64]:
        de = cie2000(base.design, predict_lab(u * step, base.angles, db))
        return np.asarray((de * de).sum(-1))

    # a recipe at a tiny load rounds badly; the same colour at a higher load (Kubelka–Munk depends on
    # the ratios) may round well: try the loads LOAD_FACTORS and keep the best after rounding (the
    # fitted load, at a limit, always stays a candidate: rounded down it is feasible)
    grid = []
    for s in LOAD_FACTORS:
        x = np.where(colorant, c * s, c)
        if feasible(x / step):
            grid.append(np.round(x / step))
    grid.append(np.floor(c / step + 1e-9))
    units = grid[int(np.argmin(score(np.asarray(grid))))]
    units = np.minimum(units, np.floor(db.upper_bounds / step + 1e-9))
    present = [int(i) for i in np.flatnonzero(units > 0) if i != matting_index]

    while not feasible(units) and present:  # rounding up may cross a limit: take back one step
        units[max(present, key=lambda i: units[i])] -= 1
    current = float(score(units[None])[0])
    for _ in range(ROUND_PASSES):
        moves = [units.copy() for _ in range(2 * len(present))]
        for k, i in enumerate(present):
            moves[2 * k][i] += 1
            moves[2 * k + 1][i] -= 1
        moves = [u for u in moves if u.min() >= 0 and feasible(u)]
        if not moves:
            break
        scores = score(np.asarray(moves))
        k = int(np.argmin(scores))
        if scores[k] >= current:
            break
        units, current = moves[k], float(scores[k])
    return units * step


def metamerism(
    design: NDArray[np.float64],
    conc: NDArray[np.float64],
    angles: tuple[float, ...],
    db: ColorantDatabase,
    illuminants: Sequence[str],
) -> list[dict[str, float] | None]:
    """Worst index over the angles per illuminant of each recipe in *conc* (None for every recipe when
    no reflectance reproduces the design)."""
    try:
        ref = reflectance_from_lab(design)
    except ModelInputError:
        return [None] * len(conc)
    refl = predict_reflectance(conc, angles, db)
    out: list[dict[str, float] | None] = []
    for r in refl:
        mi = metamerism_index(ref, r, REFERENCE_ILLUMINANT, tuple(illuminants), method="cie2000")
        out.append({ill: float(np.max(mi[ill])) for ill in illuminants})
    return out


def make_option(
    c: NDArray[np.float64],
    unrounded: NDArray[np.float64],
    base: Problem,
    meta: dict[str, float] | None,
    spec: tuple[float, float, float, str, str],
) -> RecipeOption:
    """A :class:`RecipeOption` (rank 0) for the rounded vector *c*; *spec* = (batch g, resolution g,
    tolerance, line, start)."""
    batch_g, res_g, tolerance, line, start = spec
    db: ColorantDatabase = base.db
    de = cie2000(base.design, predict_lab(c, base.angles, db))
    de0 = cie2000(base.design, predict_lab(unrounded, base.angles, db))
    recipe = {k: float(f"{v:.10g}") for k, v in db.recipe(c, _PRESENT).items()}
    batch = batch_masses(recipe, batch_g)
    grams = {k: round(v / res_g) * res_g for k, v in batch.colorants_g.items()}
    binder = batch_g - sum(grams.values())
    return RecipeOption(
        rank=0,
        recipe=recipe,
        concentrations=c,
        grams={k: float(f"{v:.6g}") for k, v in grams.items()},
        binder_g=float(f"{binder:.6g}"),
        batch_g=batch_g,
        scale_resolution_g=res_g,
        de_per_angle=tuple(float(v) for v in de),
        mean_de=float(de.mean()),
        mean_de_unrounded=float(de0.mean()),
        metamerism=meta,
        colorants=sum(1 for k in recipe if k != db.names[db.matting_index]),
        cost_per_kg=cost_per_kg(c, db),
        formulable=bool(de.mean() <= tolerance),
        line=line,
        start=start,
    )


def rank_options(options: Sequence[RecipeOption], n: int) -> tuple[RecipeOption, ...]:
    """The *n* best distinct options under the module's ranking rule, numbered from 1."""

    def key(o: RecipeOption) -> tuple[bool, float, float, int, float]:
        return (
            not o.formulable,
            round(o.mean_de / RANK_DE_RESOLUTION),
            round(o.worst_mi / RANK_DE_RESOLUTION),
            o.colorants,
            o.cost_per_kg,
        )

    seen: list[dict[str, float]] = []
    out: list[RecipeOption] = []
    for o in sorted(options, key=key):
        if o.recipe in seen:
            continue
        seen.append(o.recipe)
        out.append(o)
    return tuple(RecipeOption(**{**o.__dict__, "rank": k + 1}) for k, o in enumerate(out[:n]))
