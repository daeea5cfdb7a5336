"""Corrections as tinting: additions to the batch already mixed, never more than the batch can take.

Nothing can be taken out of a can. With the batch's masses m_i (g, colorants of the recipe and the
matting agent) and binder b (g), total M, a correction adds a_i ≥ 0 g of the recipe's own colorants
and a_b ≥ 0 g of binder; the matting agent is topped up to keep its fraction (the gloss) unchanged:

    M′ = (Σ_{i≠mat} (m_i + a_i) + b + a_b) / (1 − c_mat),   c′_i = (m_i + a_i) / M′,

the matting top-up then rounded to the scale like every other addition (the fractions predicted are
those of the batch as weighed).

The additions minimise the weighted-Lab difference (as :mod:`station.formulate.solver`) between the
colorant model's prediction of c′ and the corrected target T = design − (measured − predicted) (the
additive batch correction), within the batch's bounds: M′ ≤ :data:`~station.formulate.batch.MAX_GROWTH`
× the first batch (a can holds so much), every c′_i within its colorant's limit, Σ c′ and the effect pigments within theirs
(penalty rows). The additions are rounded to the scale's resolution (:func:`tint`); where rounding up
crosses one of these bounds, colorant additions feeding it are taken back a step at a time (never the
binder, which would raise every fraction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from station.formulate.batch import MAX_GROWTH, Tinting
from station.formulate.colorants import ColorantDatabase, predict_lab
from station.formulate.de_kernels import cie2000

_FD_STEP = 1e-6
_PENALTY = 2000.0
#: Weighted-Lab evaluations of a tinting fit (a count: no clock changes the additions).
TINT_NFEV = 40


@dataclass(frozen=True)
class TintResult:
    """Rounded additions and what they predict: ``masses_g`` (after, per colorant in database order),
    ``binder_g`` (after), ``concentrations`` (fractions after), ``predicted_lab`` and its
    ``predicted_mean_de`` to the corrected target; ``tinting`` the additions as the lab reads them."""

    masses_g: NDArray[np.float64]
    binder_g: float
    concentrations: NDArray[np.float64]
    predicted_lab: NDArray[np.float64]
    predicted_mean_de: float
    tinting: Tinting


class _TintModel:
    """The forward map additions → fractions → Lab, with the residuals and penalties of the fit."""

    def __init__(
        self,
        masses: NDArray,
        binder: float,
        target: NDArray,
        angles: tuple[float, ...],
        db: ColorantDatabase,
        limit_g: float,
    ):
        self.m, self.b, self.target, self.angles, self.db = masses, binder, target, angles, db
        self.total = float(masses.sum() + binder)
        self.limit = float(limit_g)
        self.mat = db.matting_index
        self.c_mat = float(masses[self.mat] / self.total)
        self.free = np.array([i for i in np.flatnonzero(masses > 0) if i != self.mat], dtype=np.intp)
        chroma = np.hypot(target[:, 1], target[:, 2])
        self.weight = np.stack([np.ones_like(chroma), 1 / (1 + 0.03 * chroma), 1 / (1 + 0.03 * chroma)], -1)

    def after(self, u: NDArray) -> tuple[NDArray, NDArray]:
        """(masses after, fractions after) for additions *u* (g / first batch, colorants then binder),
        *u* of shape (..., n_free + 1)."""
        u = np.asarray(u, dtype=np.float64)
        m = np.broadcast_to(self.m, (*u.shape[:-1], self.m.size)).copy()
        m[..., self.free] += u[..., :-1] * self.total
        rest = m.sum(-1) - m[..., self.mat] + self.b + u[..., -1] * self.total
        new_total = rest / (1.0 - self.c_mat)
        m[..., self.mat] = np.maximum(self.c_mat * new_total, self.m[self.mat])
        return m, m / new_total[..., None]

    def residual(self, u: NDArray) -> NDArray:
        m, c = self.after(u)
        lab = predict_lab(c, self.angles, self.db)
        r = ((lab - self.target) * self.weight).ravel()
        db = self.db
        grow = m.sum() + self.b + u[-1] * self.total - self.limit
        over = np.concatenate(
            [
                np.maximum(c - db.upper_bounds, 0.0),
                [max(c.sum() - db.max_total, 0.0), max(c[db.effect_mask].sum() - db.max_effect, 0.0)],
                [max(grow / self.total, 0.0)],
            ]
        )
        return np.concatenate([r, _PENALTY * over])

    def jacobian(self, u: NDArray) -> NDArray:
        pts = np.repeat(np.asarray(u, dtype=np.float64)[None], u.size + 1, axis=0)
        pts[np.arange(1, u.size + 1), np.arange(u.size)] += _FD_STEP
        res = np.array([self.residual(p) for p in pts])
        return np.asarray(((res[1:] - res[0]) / _FD_STEP).T)


def _take_back(
    grams: NDArray[np.float64],
    model: _TintModel,
    m: NDArray[np.float64],
    c: NDArray[np.float64],
    limit: float,
) -> int | None:
    """Index into *grams* (g, colorant additions then binder) of the addition to take one step back
    from, or None when the rounded batch (*m* g, fractions *c*) is within every bound of the colorant
    database (each c_i, Σ c, the effect pigments) and the can (*limit* g).

    The largest colorant addition that feeds a crossed bound is taken back; the binder only when the can
    overflows with no colorant addition left (taking binder back raises every fraction)."""
    db = model.db
    added = grams[:-1] > 0
    free = model.free
    over_each = (c > db.upper_bounds + 1e-12)[free]
    over_total = c.sum() > db.max_total + 1e-12
    over_effect = c[db.effect_mask].sum() > db.max_effect + 1e-12
    over_can = m.sum() + model.b + grams[-1] > limit + 1e-9
    if not (over_each.any() or over_total or over_effect or over_can):
        return None
    if over_each.any():
        feeds = over_each
    elif over_effect and not (over_total or over_can):
        feeds = db.effect_mask[free]
    else:
        feeds = np.ones(free.size, dtype=bool)
    for pool in (added & feeds, added):
        if pool.any():
            return int(np.flatnonzero(pool)[np.argmax(grams[:-1][pool])])
    return grams.size - 1 if over_can and grams[-1] > 0 else None


def _weighed(
    model: _TintModel, grams: NDArray[np.float64], resolution_g: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(masses after, fractions after) of the additions *grams* (g, colorants then binder) as weighed:
    the matting agent's top-up rounded to the scale like every other addition (the prediction is of
    the batch the chemist actually weighs)."""
    m, _ = model.after(grams / model.total)
    mat = model.mat
    top_up = max(float(np.round((m[mat] - model.m[mat]) / resolution_g)), 0.0) * resolution_g
    m[mat] = model.m[mat] + top_up
    return m, m / float(m.sum() + model.b + grams[-1])


def tint(
    masses_g: NDArray[np.float64],
    binder_g: float,
    target: NDArray[np.float64],
    angles: tuple[float, ...],
    db: ColorantDatabase,
    resolution_g: float,
    first_batch_g: float,
) -> TintResult:
    """Best add-only correction of the batch (*masses_g* per colorant in database order, *binder_g*)
    toward *target* (module docstring), the additions rounded to *resolution_g*; the batch may grow to
    :data:`~station.formulate.batch.MAX_GROWTH` × *first_batch_g*."""
    limit = MAX_GROWTH * first_batch_g
    model = _TintModel(np.asarray(masses_g, dtype=np.float64), float(binder_g), target, angles, db, limit)
    n = model.free.size + 1
    res = least_squares(
        model.residual,
        np.zeros(n),
        jac=model.jacobian,
        bounds=(np.zeros(n), np.full(n, max(limit / model.total - 1.0, 1e-9))),
        method="trf",
        max_nfev=TINT_NFEV,
        xtol=1e-10,
        ftol=1e-10,
    )
    grams = np.round(res.x * model.total / resolution_g) * resolution_g
    while True:  # rounding up may cross a bound: take back one step of a colorant addition
        m, c = _weighed(model, grams, resolution_g)
        take = _take_back(grams, model, m, c, limit)
        if take is None:
            break
        grams[take] -= resolution_g
    lab = predict_lab(c, angles, db)
    additions = {db.names[i]: float(f"{g:.6g}") for i, g in zip(model.free, grams[:-1], strict=True) if g > 0}
    mat_add = float(m[model.mat] - model.m[model.mat])
    if mat_add > 0:
        additions[db.names[model.mat]] = float(f"{mat_add:.6g}")
    new_total = float(m.sum() + model.b + grams[-1])
    tinting = Tinting(
        additions,
        float(grams[-1]),
        new_total,
        False,
        f"add to the {model.total:g} g batch: {new_total:.1f} g after",
    )
    de = cie2000(target, lab)
    return TintResult(m, model.b + float(grams[-1]), c, lab, float(de.mean()), tinting)
