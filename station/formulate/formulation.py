"""Recipe formulation: non-negative colorant fractions minimising the multi-angle CIEDE2000 to a design.

Problem (per design, Lab at the angles θ_j, illumination 45°, D65/10°):

    minimise   Σ_j ΔE00(design_j, predict_lab(c)_j)²
    subject to 0 ≤ c_i ≤ max_fraction_i,  Σ_i c_i ≤ max_total − c_matting,
               Σ_{i ∈ flakes, pearls} c_i ≤ max_effect,

with :func:`station.formulate.colorants.predict_lab` (Kubelka–Munk per geometry + Saunderson). The
matting fraction is set in closed form from the gloss target (G = 90 − 650 c_matting) because it does
not change the colour in this model. SciPy's SLSQP solves it, with gradients from one batched
forward-difference evaluation of the (vectorised) model, starting from the ColorSnap match's recipe
and, if that falls short, from the next matches' recipes and a few generic starts.

The result reports the predicted ΔE00 per angle; a design whose best mean ΔE00 over angles exceeds
the tolerance (default 1.0) is reported as "not formulable with these colorants".
"""

from __future__ import annotations

import functools
import time
from collections.abc import Collection
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import OptimizeResult, least_squares, minimize

from station.formulate.batch import batch_masses
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
from station.formulate.snap import SnapIndex, SnapResult, color_snap, validate_design_lab
from station.model.domain import FORMULATION_TOLERANCE_DE00, GLOSS_MAX_GU, GLOSS_MIN_GU

#: Mean CIEDE2000 over the angles accepted as "formulable" (station.model.domain).
DEFAULT_TOLERANCE = FORMULATION_TOLERANCE_DE00
_FD_STEP = 1e-7
_PENALTY = 2000.0
#: Fractions at or below this are dropped from a recipe (:meth:`ColorantDatabase.recipe`'s threshold).
_RECIPE_THRESHOLD = 1e-6


@dataclass(frozen=True)
class FormulationResult:
    """A formulated recipe and its predicted colour.

    Attributes
    ----------
    recipe
        ``{colorant: mass fraction}`` (fractions below 1e-6 omitted).
    concentrations
        The full vector, in :attr:`ColorantDatabase.names` order.
    angles_deg, design_lab, predicted_lab
        Angles (degrees) and Lab (D65/10°) of the design and of the recipe's prediction, shape (A, 3).
    de_per_angle
        Predicted CIEDE2000 per angle; ``mean_de`` and ``max_de`` summarise it.
    formulable
        ``mean_de <= tolerance``; ``message`` says "not formulable with these colorants" otherwise.
    gloss_gu
        Predicted 60° gloss (GU) of the recipe.
    start
        Where the winning start came from (a library code, "given" or "generic").
    candidates
        ``(start label, full concentration vector)`` of the distinct recipes the starts converged to,
        the winning recipe first (filled when :func:`formulate` is asked for ``candidates``); their
        metamerism ranking is :func:`station.formulate.metamerism.rank_formulation`.
    """

    recipe: dict[str, float]
    concentrations: NDArray[np.float64]
    angles_deg: tuple[float, ...]
    design_lab: NDArray[np.float64]
    predicted_lab: NDArray[np.float64]
    de_per_angle: tuple[float, ...]
    mean_de: float
    max_de: float
    formulable: bool
    tolerance: float
    gloss_gu: float
    start: str
    message: str
    elapsed_s: float = 0.0
    evaluations: int = 0
    synthetic: bool = True
    warnings: tuple[str, ...] = field(default=())
    candidates: tuple[tuple[str, NDArray[np.float64]], ...] = field(default=())

    def to_dict(self) -> dict[str, object]:
        """JSON-able form for the CLI and the service."""
        return {
            "recipe": self.recipe,
            "angles_deg": list(self.angles_deg),
            "design_lab": self.design_lab.tolist(),
            "predicted_lab": self.predicted_lab.tolist(),
            "de_per_angle": list(self.de_per_angle),
            "mean_de": self.mean_de,
            "max_de": self.max_de,
            "metric": "cie2000",
            "formulable": self.formulable,
            "tolerance": self.tolerance,
            "gloss_gu": self.gloss_gu,
            "start": self.start,
            "message": self.message,
            "elapsed_s": self.elapsed_s,
            "synthetic_colorants": self.synthetic,
            "warnings": list(self.warnings),
            "batch": batch_masses(self.recipe).to_dict(),
            "nearest_achievable_lab": None if self.formulable else self.predicted_lab.tolist(),
        }


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


class _Objective:
    """Σ ΔE00² to the design, with the batched forward-difference gradient; counts evaluations."""

    def __init__(
        self, design: NDArray, angles: tuple[float, ...], db: ColorantDatabase, free: NDArray, fixed: NDArray
    ):
        self.design = design
        self.angles = angles
        self.db = db
        self.free = free
        self.fixed = fixed
        self.evaluations = 0
        self._cache: tuple[bytes, float, NDArray] | None = None
        #: Best point evaluated so far (SLSQP's iterates are not monotone; a stopped run keeps this one).
        self.best: tuple[float, NDArray] = (np.inf, np.zeros(free.size))

    def full(self, x: NDArray) -> NDArray:
        c = np.broadcast_to(self.fixed, (*x.shape[:-1], self.fixed.size)).copy()
        c[..., self.free] = x
        return c

    def _eval(self, x: NDArray) -> tuple[float, NDArray]:
        key = x.tobytes()
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1], self._cache[2]
        n = x.size
        pts = np.repeat(x[None], n + 1, axis=0)
        pts[np.arange(1, n + 1), np.arange(n)] += _FD_STEP
        lab = predict_lab(self.full(pts), self.angles, self.db)
        de = cie2000(self.design[None], lab)
        f = (de * de).sum(-1)
        self.evaluations += n + 1
        grad = (f[1:] - f[0]) / _FD_STEP
        self._cache = (key, float(f[0]), grad)
        if f[0] < self.best[0]:
            self.best = (float(f[0]), x.copy())
        return float(f[0]), grad

    def value(self, x: NDArray) -> float:
        return self._eval(np.asarray(x, dtype=np.float64))[0]

    def grad(self, x: NDArray) -> NDArray:
        return self._eval(np.asarray(x, dtype=np.float64))[1]


class _LabLeastSquares:
    """Residuals for the fast phase: Lab differences per angle weighted as CIE94 weights them
    (ΔL*, Δa*/(1 + 0.03 C*), Δb*/(1 + 0.03 C*) with C* of the design), plus penalty rows for the two
    linear constraints (total and flake fractions); zero residual is an exact match in every metric."""

    def __init__(
        self,
        design: NDArray,
        angles: tuple[float, ...],
        db: ColorantDatabase,
        objective: _Objective,
        max_total: float,
        effect: NDArray,
    ):
        self.design = design
        chroma = np.hypot(design[:, 1], design[:, 2])
        self.weight = np.stack([np.ones_like(chroma), 1 / (1 + 0.03 * chroma), 1 / (1 + 0.03 * chroma)], -1)
        self.angles = angles
        self.db = db
        self.objective = objective
        self.max_total = max_total
        self.effect = effect
        self.max_effect = db.max_effect
        self._cache: tuple[bytes, NDArray, NDArray] | None = None

    def _eval(self, x: NDArray) -> tuple[NDArray, NDArray]:
        key = x.tobytes()
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1], self._cache[2]
        n = x.size
        pts = np.repeat(x[None], n + 1, axis=0)
        pts[np.arange(1, n + 1), np.arange(n)] += _FD_STEP
        lab = predict_lab(self.objective.full(pts), self.angles, self.db)
        r = ((lab - self.design[None]) * self.weight[None]).reshape(n + 1, -1)
        self.objective.evaluations += n + 1
        over_t = x.sum() - self.max_total
        over_e = self.effect @ x - self.max_effect
        pen = np.array([_PENALTY * max(over_t, 0.0), _PENALTY * max(over_e, 0.0)])
        jp = np.stack([_PENALTY * (over_t > 0) * np.ones(n), _PENALTY * (over_e > 0) * self.effect])
        res = np.concatenate([r[0], pen])
        jac = np.vstack([((r[1:] - r[0]) / _FD_STEP).T, jp])
        self._cache = (key, res, jac)
        return res, jac

    def residual(self, x: NDArray) -> NDArray:
        return self._eval(np.asarray(x, dtype=np.float64))[0]

    def jacobian(self, x: NDArray) -> NDArray:
        return self._eval(np.asarray(x, dtype=np.float64))[1]


def _project(x: NDArray, ub: NDArray, effect: NDArray, max_effect: float, max_total: float) -> NDArray:
    """Make an optimiser's point exactly feasible (SLSQP meets constraints only to ~1e-8): clip to the
    bounds, then scale the effect pigments and the total down to their limits."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, ub)
    e = x[effect].sum()
    if e > max_effect:
        x[effect] *= max_effect / e * (1 - 1e-12)
    t = x.sum()
    if t > max_total:
        x *= max_total / t * (1 - 1e-12)
    return x


def _generic_starts(db: ColorantDatabase, design: NDArray, angles: tuple[float, ...]) -> list[NDArray]:
    """A pool of generic starting recipes, best first by their multi-angle ΔE00 to the design.

    Bases: TiO2 white (solid), each aluminium grade and each adjacent pair, each pearl and interference pigment; each with
    one tint, or two tints adjacent in hue, at a low and a high loading. One batched model evaluation
    ranks the whole pool (about 200 recipes).
    """
    names = db.names
    idx = {n: i for i, n in enumerate(names)}
    tints = [c.name for c in db.colorants if c.family == "tint"]
    fam = {c.name: c.family for c in db.colorants}
    alu = [n for n in names if fam[n] == "aluminium"]
    bases: list[dict[str, float]] = [{"white_tio2": 0.05}, {"white_tio2": 0.15}]
    bases += [{a: 0.08} for a in alu] + [{alu[k]: 0.05, alu[k + 1]: 0.05} for k in range(len(alu) - 1)]
    bases += [{n: 0.08} for n in names if fam[n] in ("pearl", "interference")]
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
    c = np.asarray(pool)
    f = (cie2000(design[None], predict_lab(c, angles, db)) ** 2).sum(-1)
    return [c[k] for k in np.argsort(f, kind="stable")[:6]]


def formulate(
    design_lab: ArrayLike,
    angles_deg: tuple[float, ...] = STANDARD_ANGLES,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    gloss_gu: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    time_budget_s: float = 0.8,
    strict: bool = False,
    candidates: int = 0,
) -> FormulationResult:
    """Formulate a recipe for the design (see module docstring).

    Parameters
    ----------
    design_lab
        Design L*a*b* per angle, shape (A, 3).
    angles_deg
        The angles (degrees) of *design_lab*.
    starts
        ``[(label, recipe)]`` starting recipes, best first (e.g. the ColorSnap matches' recipes); a
        recipe is a vector or ``{colorant: fraction}``. Generic starts are added after them.
    gloss_gu
        60° gloss target (GU); ``None`` keeps full gloss.
    tolerance
        Mean predicted ΔE00 over angles above which the design is "not formulable".
    time_budget_s
        Further starts are tried only while the elapsed time is within this budget, and an optimiser run
        stops (keeping its best point) at 1.15 × the budget.
    strict
        Raise :class:`NotFormulableError` instead of returning an unformulable result.
    candidates
        Try at least this many starts to convergence, whatever the time budget, and keep each distinct
        recipe they reach as :attr:`FormulationResult.candidates` (0: stop at the first good enough).
    """
    if candidates < 0:
        raise FormulateInputError("candidates", "a count >= 0", candidates)
    t0 = time.perf_counter()
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise FormulateInputError("tolerance", "a positive ΔE00", tolerance)
    warnings: list[str] = []
    c_mat, warn = matting_for_gloss(GLOSS_CLEAR_GU if gloss_gu is None else gloss_gu, db)
    if warn:
        warnings.append(warn)
    n = len(db.names)
    free = np.array([i for i in range(n) if i != db.matting_index])
    fixed = np.zeros(n)
    fixed[db.matting_index] = c_mat
    ub = db.upper_bounds[free]
    effect = db.effect_mask[free].astype(float)

    def total_slack(x: NDArray[np.float64]) -> float:  # Σ c <= max_total - c_matting
        return float(db.max_total - c_mat - x.sum())

    def total_slack_grad(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return -np.ones_like(x)

    def effect_slack(x: NDArray[np.float64]) -> float:  # Σ c_effect <= max_effect
        return float(db.max_effect - effect @ x)

    def effect_slack_grad(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return -effect

    objective = _Objective(design, angles, db, free, fixed)
    starts_x: list[tuple[str, NDArray]] = []
    for label, rec in starts or []:
        vec = db.vector(rec) if isinstance(rec, dict) else np.asarray(rec, dtype=np.float64)
        starts_x.append((label, db.check(vec, field=f"starts[{label}]")[free]))
    starts_x += [("generic", s[free]) for s in _generic_starts(db, design, angles)]
    best: tuple[float, NDArray, str] | None = None
    good_enough = (0.02 * min(tolerance, 1.0)) ** 2 * len(angles)  # Σ ΔE00² of a mean ΔE00 of ~0.02
    deadline = t0 + max(time_budget_s, 0.05) * 1.15

    def stop(intermediate_result: OptimizeResult) -> None:  # SciPy's new-style callback: this exact name
        if (
            objective.value(np.asarray(intermediate_result.x)) <= good_enough
            or time.perf_counter() > deadline
        ):
            raise StopIteration

    proj = functools.partial(
        _project, ub=ub, effect=effect.astype(bool), max_effect=db.max_effect, max_total=db.max_total - c_mat
    )
    lsq = _LabLeastSquares(design, angles, db, objective, db.max_total - c_mat, effect)
    enough = (0.2 * min(tolerance, 1.0)) ** 2 * len(angles)  # Σ ΔE00² of a mean ΔE00 of 0.2 × tolerance
    tried: list[tuple[str, NDArray]] = []
    for label, x0 in starts_x:  # phase 1: Gauss–Newton (trust region) on weighted Lab residuals
        if (
            best is not None
            and len(tried) >= candidates
            and (time.perf_counter() - t0 > time_budget_s or best[0] <= enough)
        ):
            break
        res_ls = least_squares(
            lsq.residual,
            np.clip(x0, 0.0, ub),
            jac=lsq.jacobian,
            bounds=(np.zeros_like(ub), np.maximum(ub, 1e-12)),
            method="trf",
            max_nfev=25,
            xtol=1e-10,
            ftol=1e-10,
        )
        x = proj(res_ls.x)
        f = objective.value(x)
        tried.append((label, x))
        if best is None or f < best[0]:
            best = (f, x, label)
    assert best is not None  # noqa: S101 - starts_x is never empty (generic starts)
    if best[0] > enough and time.perf_counter() < deadline:  # phase 2: SLSQP on Σ ΔE00² itself
        res = minimize(
            objective.value,
            best[1],
            jac=objective.grad,
            method="SLSQP",
            bounds=list(zip(np.zeros_like(ub), ub, strict=True)),
            constraints=[
                {"type": "ineq", "fun": total_slack, "jac": total_slack_grad},
                {"type": "ineq", "fun": effect_slack, "jac": effect_slack_grad},
            ],
            options={"maxiter": 150, "ftol": 1e-9},
            callback=stop,
        )
        for point in (res.x, objective.best[1]):
            x = proj(point)
            f = objective.value(x)
            if f < best[0]:
                best = (f, x, best[2])
    c = objective.full(best[1])
    c[c <= _RECIPE_THRESHOLD] = 0.0  # the reported recipe omits these: predict exactly what it says
    pred = predict_lab(c, angles, db)
    de = cie2000(design, pred)
    mean_de = float(de.mean())
    formulable = mean_de <= tolerance
    message = (
        f"formulated: mean ΔE00 {mean_de:.2f} over {len(angles)} angles (tolerance {tolerance:g})"
        if formulable
        else f"not formulable with these colorants: best mean ΔE00 {mean_de:.2f} > tolerance {tolerance:g};"
        " the nearest achievable paint is the prediction of the best recipe (nearest_achievable_lab)"
    )
    if strict and not formulable:
        raise NotFormulableError(message)
    return FormulationResult(
        recipe=db.recipe(c, _RECIPE_THRESHOLD),
        concentrations=c,
        angles_deg=angles,
        design_lab=design,
        predicted_lab=pred,
        de_per_angle=tuple(float(v) for v in de),
        mean_de=mean_de,
        max_de=float(de.max()),
        formulable=formulable,
        tolerance=float(tolerance),
        gloss_gu=float(GLOSS_CLEAR_GU - GLOSS_PER_MATTING * c_mat),
        start=best[2],
        message=message,
        elapsed_s=time.perf_counter() - t0,
        evaluations=objective.evaluations,
        synthetic=db.synthetic,
        warnings=tuple(warnings),
        candidates=_distinct(best[2], c, [(lb, objective.full(x)) for lb, x in tried]) if candidates else (),
    )


def _distinct(
    label: str, winner: NDArray, tried: list[tuple[str, NDArray]]
) -> tuple[tuple[str, NDArray[np.float64]], ...]:
    """The winning recipe first, then each recipe *tried* that differs from every one kept (by more than
    :data:`_RECIPE_THRESHOLD` in some fraction), the reported threshold applied to each."""
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
    time_budget_s: float = 0.8,
    types: Collection[str] | None = None,
    candidates: int = 0,
) -> tuple[FormulationResult, SnapResult]:
    """ColorSnap (CIEDE2000) the design against a library with recipes, then formulate from the
    *k* best matches' recipes (thesis §5.3.4–5.3.5: the match is the formulation starting point).

    *types* restricts the matches (and so the starting recipes) to those paint types (``solid``,
    ``metallic``, ``pearl``); ``None`` searches every paint. *candidates*: see :func:`formulate`."""
    if library.recipes is None or library.colorant_names is None:
        raise FormulateInputError("library", "a library with recipes (the demo library)", library.name)
    db = db or default_database()
    if tuple(library.colorant_names) != db.names:
        raise FormulateInputError(
            "library.colorant_names", f"the colorants {db.names}", library.colorant_names
        )
    design = validate_design_lab(design_lab, 3, "design_lab")
    snap = color_snap(library, design, k=k, method="cie2000", index=index, types=types)
    starts = [(m.code, library.recipes[m.index]) for m in snap.matches]
    result = formulate(
        design, STANDARD_ANGLES, starts, gloss_gu, tolerance, db, time_budget_s, candidates=candidates
    )
    return result, snap
