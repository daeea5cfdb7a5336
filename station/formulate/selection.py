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

import numpy as np
from numpy.typing import NDArray

from station.formulate.batch import batch_masses
from station.formulate.colorants import ColorantDatabase, predict_lab, predict_reflectance
from station.formulate.de_kernels import cie2000
from station.formulate.lines import cost_per_kg
from station.formulate.solver import Objective, Problem, fit_lab, refine_de00
from station.model.errors import ModelInputError
from station.model.illuminants import REFERENCE_ILLUMINANT
from station.model.spectra import metamerism_index, reflectance_from_lab

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
        """JSON-able form (every field)."""
        return {
            "rank": self.rank,
            "recipe": self.recipe,
            "grams": self.grams,
            "binder_g": self.binder_g,
            "batch_g": self.batch_g,
            "scale_resolution_g": self.scale_resolution_g,
            "de_per_angle": list(self.de_per_angle),
            "mean_de": self.mean_de,
            "mean_de_unrounded": self.mean_de_unrounded,
            "metamerism_index": self.metamerism,
            "colorants": self.colorants,
            "cost_per_kg": self.cost_per_kg,
            "formulable": self.formulable,
            "line": self.line,
            "start": self.start,
        }


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
    # a recipe at a tiny load rounds badly; the same colour at a higher load (Kubelka–Munk depends on
    # the ratios) may round well: try the loads LOAD_FACTORS and keep the best after rounding
    grid = []
    for s in LOAD_FACTORS:
        x = np.where(colorant, c * s, c)
        if (
            np.all(x <= db.upper_bounds)
            and x.sum() <= db.max_total
            and x[db.effect_mask].sum() <= db.max_effect
        ):
            grid.append(np.round(x / step))
    de = cie2000(base.design, predict_lab(np.asarray(grid) * step, base.angles, db))
    units = grid[int(np.argmin((de * de).sum(-1)))]
    units = np.minimum(units, np.floor(db.upper_bounds / step + 1e-9))
    present = [int(i) for i in np.flatnonzero(units > 0) if i != matting_index]

    def score(u: NDArray[np.float64]) -> NDArray[np.float64]:
        de = cie2000(base.design, predict_lab(u * step, base.angles, db))
        return np.asarray((de * de).sum(-1))

    def feasible(u: NDArray[np.float64]) -> bool:
        x = u * step
        return bool(
            np.all(x <= db.upper_bounds + 1e-12)
            and x.sum() <= db.max_total + 1e-12
            and x[db.effect_mask].sum() <= db.max_effect + 1e-12
        )

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
