"""The numerical core of formulation: objectives and fits over a chosen set of free colorants.

A :class:`Problem` fixes the design, the angles, the colorant database, the colorants that may vary
(a toner line, or a subset of one) and the fixed matting fraction. On it:

* :func:`fit_lab` — trust-region least squares (SciPy ``least_squares``, ``trf``) on Lab differences
  weighted as CIE94 weights them (ΔL*, Δa*/(1 + 0.03 C*), Δb*/(1 + 0.03 C*), C* of the design), with
  penalty rows for the total and effect-pigment limits; a fixed evaluation count (``max_nfev``).
* :func:`refine_de00` — SLSQP on Σ_j ΔE00(design_j, predict_lab(c)_j)² itself with the linear limits
  as constraints; a fixed iteration count.

Both stop on counts and on the objective's value only: no clock changes a result. Gradients are one
batched forward difference of the vectorised colorant model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import OptimizeResult, least_squares, minimize

from station.formulate.colorants import ColorantDatabase, predict_lab
from station.formulate.de_kernels import cie2000

_FD_STEP = 1e-7
_PENALTY = 2000.0
#: Lab least-squares evaluations per fit (each a batch of n + 1 model evaluations).
LSQ_MAX_NFEV = 25
#: SLSQP iterations of the ΔE00 refinement.
SLSQP_MAXITER = 80


@dataclass(frozen=True)
class Problem:
    """What a fit varies: colorants *free* (indices into the database) with the others at *fixed*."""

    design: NDArray[np.float64]
    angles: tuple[float, ...]
    db: ColorantDatabase
    free: NDArray[np.intp]
    fixed: NDArray[np.float64]

    @property
    def upper(self) -> NDArray[np.float64]:
        """Upper bound of each free fraction."""
        return np.asarray(self.db.upper_bounds[self.free], dtype=np.float64)

    @property
    def effect(self) -> NDArray[np.float64]:
        """1.0 where a free colorant is an effect pigment (aluminium, pearl, interference)."""
        return np.asarray(self.db.effect_mask[self.free], dtype=np.float64)

    @property
    def max_total(self) -> float:
        """Largest Σ of the free fractions (the database's total less the fixed ones)."""
        return float(self.db.max_total - self.fixed.sum())

    def full(self, x: NDArray) -> NDArray[np.float64]:
        """Full concentration vector(s) from the free fractions *x* (..., n_free)."""
        c = np.broadcast_to(self.fixed, (*x.shape[:-1], self.fixed.size)).copy()
        c[..., self.free] = x
        return c

    def sum_sq(self, x: NDArray) -> NDArray[np.float64]:
        """Σ_j ΔE00² to the design of the free fractions *x* (..., n_free)."""
        de = cie2000(
            self.design, predict_lab(self.full(np.asarray(x, dtype=np.float64)), self.angles, self.db)
        )
        return np.asarray((de * de).sum(-1), dtype=np.float64)

    def project(self, x: NDArray) -> NDArray[np.float64]:
        """Exactly feasible point: clip to the bounds, then scale effect pigments and the total down."""
        x = np.clip(np.asarray(x, dtype=np.float64), 0.0, self.upper)
        eff = self.effect.astype(bool)
        e = x[eff].sum()
        if e > self.db.max_effect:
            x[eff] *= self.db.max_effect / e * (1 - 1e-12)
        t = x.sum()
        if t > self.max_total:
            x *= self.max_total / t * (1 - 1e-12)
        return x


class Objective:
    """Σ ΔE00² to the design with the batched forward-difference gradient; counts evaluations."""

    def __init__(self, problem: Problem):
        self.p = problem
        self.evaluations = 0
        self._cache: tuple[bytes, float, NDArray] | None = None
        #: Best point evaluated so far (SLSQP's iterates are not monotone; a stopped run keeps this one).
        self.best: tuple[float, NDArray] = (np.inf, np.zeros(problem.free.size))

    def _eval(self, x: NDArray) -> tuple[float, NDArray]:
        key = x.tobytes()
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1], self._cache[2]
        n = x.size
        pts = np.repeat(x[None], n + 1, axis=0)
        pts[np.arange(1, n + 1), np.arange(n)] += _FD_STEP
        f = self.p.sum_sq(pts)
        self.evaluations += n + 1
        grad = (f[1:] - f[0]) / _FD_STEP
        self._cache = (key, float(f[0]), grad)
        if f[0] < self.best[0]:
            self.best = (float(f[0]), x.copy())
        return float(f[0]), grad

    def value(self, x: NDArray) -> float:
        """Σ ΔE00² at *x*."""
        return self._eval(np.asarray(x, dtype=np.float64))[0]

    def grad(self, x: NDArray) -> NDArray:
        """Its gradient at *x* (forward differences)."""
        return self._eval(np.asarray(x, dtype=np.float64))[1]


def lab_weights(design: NDArray[np.float64]) -> NDArray[np.float64]:
    """Weights of the Lab residuals per angle (A, 3): 1 on ΔL*, 1/(1 + 0.03 C*) on Δa* and Δb*, C* of
    the design (the CIE94 weighting)."""
    chroma = np.hypot(design[:, 1], design[:, 2])
    return np.stack([np.ones_like(chroma), 1 / (1 + 0.03 * chroma), 1 / (1 + 0.03 * chroma)], -1)


class _LabLeastSquares:
    """Weighted Lab residuals plus penalty rows for the total and effect limits (zero residual is an
    exact match in every metric)."""

    def __init__(self, objective: Objective):
        self.weight = lab_weights(objective.p.design)
        self.objective = objective
        self._cache: tuple[bytes, NDArray, NDArray] | None = None

    def _eval(self, x: NDArray) -> tuple[NDArray, NDArray]:
        key = x.tobytes()
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1], self._cache[2]
        p = self.objective.p
        n = x.size
        pts = np.repeat(x[None], n + 1, axis=0)
        pts[np.arange(1, n + 1), np.arange(n)] += _FD_STEP
        lab = predict_lab(p.full(pts), p.angles, p.db)
        r = ((lab - p.design[None]) * self.weight[None]).reshape(n + 1, -1)
        self.objective.evaluations += n + 1
        effect = p.effect
        over_t = x.sum() - p.max_total
        over_e = effect @ x - p.db.max_effect
        pen = np.array([_PENALTY * max(over_t, 0.0), _PENALTY * max(over_e, 0.0)])
        jp = np.stack([_PENALTY * (over_t > 0) * np.ones(n), _PENALTY * (over_e > 0) * effect])
        res = np.concatenate([r[0], pen])
        jac = np.vstack([((r[1:] - r[0]) / _FD_STEP).T, jp])
        self._cache = (key, res, jac)
        return res, jac

    def residual(self, x: NDArray) -> NDArray:
        return self._eval(np.asarray(x, dtype=np.float64))[0]

    def jacobian(self, x: NDArray) -> NDArray:
        return self._eval(np.asarray(x, dtype=np.float64))[1]


def fit_lab(objective: Objective, x0: NDArray, max_nfev: int = LSQ_MAX_NFEV) -> tuple[float, NDArray]:
    """Weighted-Lab least squares from *x0* (free fractions); returns (Σ ΔE00², feasible point)."""
    p = objective.p
    ub = p.upper
    lsq = _LabLeastSquares(objective)
    res = least_squares(
        lsq.residual,
        np.clip(np.asarray(x0, dtype=np.float64), 0.0, ub),
        jac=lsq.jacobian,
        bounds=(np.zeros_like(ub), np.maximum(ub, 1e-12)),
        method="trf",
        max_nfev=max_nfev,
        xtol=1e-10,
        ftol=1e-10,
    )
    x = p.project(res.x)
    return objective.value(x), x


def refine_de00(
    objective: Objective, x0: NDArray, good_enough: float, maxiter: int = SLSQP_MAXITER
) -> tuple[float, NDArray]:
    """SLSQP on Σ ΔE00² from *x0*, stopping after *maxiter* iterations or once the objective is at
    most *good_enough*; returns (Σ ΔE00², feasible point), never worse than *x0*."""
    p = objective.p
    ub = p.upper
    effect = p.effect

    def stop(intermediate_result: OptimizeResult) -> None:  # SciPy's new-style callback: this exact name
        if objective.value(np.asarray(intermediate_result.x)) <= good_enough:
            raise StopIteration

    res = minimize(  # type: ignore[call-overload]
        objective.value,
        x0,
        jac=objective.grad,
        method="SLSQP",
        bounds=list(zip(np.zeros_like(ub), ub, strict=True)),
        constraints=[
            {"type": "ineq", "fun": lambda x: p.max_total - x.sum(), "jac": lambda x: -np.ones_like(x)},
            {"type": "ineq", "fun": lambda x: p.db.max_effect - effect @ x, "jac": lambda x: -effect},
        ],
        options={"maxiter": maxiter, "ftol": 1e-9},
        callback=stop,
    )
    best = (objective.value(x0), np.asarray(x0, dtype=np.float64))
    for point in (res.x, objective.best[1]):
        x = p.project(point)
        f = objective.value(x)
        if f < best[0]:
            best = (f, x)
    return best
