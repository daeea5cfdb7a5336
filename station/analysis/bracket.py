"""Root bracketing for the goniogeometric index: the first crossing of ΔE(β) − ε, never a later one.

1. The first grid interval with F(lo) < 0 ≤ F(hi) (:func:`first_bracket`), after a guard against a
   crossing hidden between grid points: with ``K_j`` twice the largest second difference next to
   interval j (a local curvature bound), an interval whose bound ``max(F_j, F_{j+1}) + K_j h²/8``
   reaches 0 is subdivided (16 points, recursively, down to 1e-3°) first.
2. Vectorised 32-fold subdivisions of the brackets (:func:`shrink`), then Brent's method
   (:func:`brent`, ``xtol = 1e-7°``) inside a bracket.

Angles in degrees; ΔE in the seam model's formula (thesis eq 4.3.1).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq

from station.analysis.seam_model import SeamModel

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: Brent's absolute tolerance on β (degrees); the stated resolution of β_min is 1e-6°.
BRENT_XTOL_DEG = 1e-7
_GUARD_MIN_WIDTH_DEG = 1e-3
_GUARD_SUBDIV = 16


def _curvature(row: NDArray[np.float64], h: float) -> NDArray[np.float64]:
    """Per-interval curvature bound: twice the largest |second difference| / h² next to each interval."""
    n = len(row)
    d2 = np.zeros(n)
    if n >= 3:
        with np.errstate(invalid="ignore"):  # −inf marks hidden geometries; masked just below
            inner = np.abs(row[:-2] - 2.0 * row[1:-1] + row[2:]) / (h * h)
        d2[1:-1] = np.where(np.isfinite(inner), inner, 0.0)
        d2[0], d2[-1] = d2[1], d2[-2]
    # interval j spans points j, j+1: neighbours j-1 … j+2
    padded = np.concatenate([[d2[0]], d2, [d2[-1]]])
    win = np.maximum.reduce([padded[0 : n - 1], padded[1:n], padded[2 : n + 1], padded[3 : n + 2]])
    return 2.0 * win


def first_bracket(
    model: SeamModel,
    paint: FaceFlopTravelGloss,
    eps: float,
    sign: float,
    g: int,
    grid: NDArray[np.float64],
    row: NDArray[np.float64],
) -> tuple[float, float] | None:
    """First interval [lo, hi] of *grid* with F(lo) < 0 ≤ F(hi); ``(grid[0], grid[0])`` when F(grid[0]) ≥ 0
    already (the crossing is at the first point: ε was seen, so it is reached, never reported as missed).

    Before accepting it, every earlier interval whose curvature bound
    ``max(F_j, F_{j+1}) + K_j h²/8`` reaches 0 is searched on a finer grid (a crossing hidden between
    two grid points needs that much curvature).
    """
    hits = np.nonzero(row >= 0.0)[0]
    end = int(hits[0]) if hits.size else len(row)
    if end == 0:
        return float(grid[0]), float(grid[0])
    h = float(grid[1] - grid[0])
    finite = np.isfinite(row)
    last = min(end, int(np.sum(np.cumprod(finite)))) - 1  # last index before a hit or the invisible tail
    if last >= 1:
        K = _curvature(np.where(finite, row, np.nan), h)
        bound = np.maximum(row[:last], row[1 : last + 1]) + K[:last] * h * h / 8.0
        for j in np.nonzero(bound >= 0.0)[0]:
            ends = (float(row[j]), float(row[j + 1]))
            sub = _refine(model, paint, eps, sign, g, (float(grid[j]), float(grid[j + 1])), ends)
            if sub is not None:
                return sub
    if hits.size and end >= 1 and np.isfinite(row[end - 1]):
        return float(grid[end - 1]), float(grid[end])
    return None


def _refine(
    model: SeamModel,
    paint: FaceFlopTravelGloss,
    eps: float,
    sign: float,
    g: int,
    span: tuple[float, float],
    ends: tuple[float, float],
) -> tuple[float, float] | None:
    """Look for a crossing hidden inside *span* = [lo, hi] on a finer grid (recursive down to 1e-3°).

    *ends* are F(lo) and F(hi) as the coarser grid found them (both < 0); they are kept rather than
    evaluated again, so one β has one value throughout the search.
    """
    lo, hi = span
    if hi - lo < _GUARD_MIN_WIDTH_DEG:
        return None
    sub = np.linspace(lo, hi, _GUARD_SUBDIV + 1)
    F = model.delta_e(paint, paint, sign * sub, rows=np.array([g]))[0] - eps
    vis = model.visible(sign * sub)[g]
    F = np.where(np.cumprod(vis).astype(bool), F, -np.inf)
    F[0], F[-1] = ends
    return first_bracket(model, paint, eps, sign, g, sub, F)


def shrink(
    model: SeamModel,
    paint: FaceFlopTravelGloss,
    eps: float,
    signs: tuple[float, ...],
    brackets: list[tuple[float, float, int, int]],
    known: dict[tuple[int, int], dict[float, float]] | None = None,
) -> list[tuple[float, float]]:
    """Shrink each bracket 32-fold with one vectorised evaluation for all (keeps the first crossing).

    The values at the new bracket ends are stored in *known* (per (row, direction)) so Brent does not
    evaluate them again.
    """
    subs = np.array([np.linspace(lo, hi, 33) for lo, hi, _, _ in brackets])
    sign = np.array([signs[si] for _, _, _, si in brackets])[:, None]
    rows = np.array([g for _, _, g, _ in brackets])
    F = model.delta_e_rows(paint, paint, sign * subs, rows) - eps
    out = []
    for (lo, hi, g, si), sub, row in zip(brackets, subs, F, strict=True):
        j = int(np.argmax(row >= 0.0))
        if j > 0 and row[j] >= 0.0 and np.all(row[:j] < 0.0):
            out.append((float(sub[j - 1]), float(sub[j])))
            if known is not None:
                known.setdefault((int(g), int(si)), {}).update(
                    {float(sub[j - 1]): float(row[j - 1]), float(sub[j]): float(row[j])}
                )
        else:
            out.append((lo, hi))
    return out


def brent(
    model: SeamModel,
    paint: FaceFlopTravelGloss,
    eps: float,
    sign: float,
    g: int,
    lo: float,
    hi: float,
    known: dict[float, float] | None = None,
) -> float:
    """First crossing of ΔE − ε inside the bracket [lo, hi] (degrees) by Brent's method.

    *known* holds F at bracket ends already evaluated (by :func:`shrink`). An end evaluated here that
    does not bracket (F(lo) ≥ 0, or a degenerate bracket lo = hi from a crossing at the first grid
    point) gives that end: the crossing is there, within the stated resolution.
    """
    rows = np.array([g])
    known = dict(known or {})

    def f(b: float) -> float:
        if b not in known:  # bracket ends may already be evaluated by the shrink step
            known[b] = float(model.delta_e(paint, paint, np.array([sign * b]), rows=rows)[0, 0]) - eps
        return known[b]

    if hi <= lo or f(lo) >= 0.0:
        return lo
    if f(hi) < 0.0:
        return hi
    return float(brentq(f, lo, hi, xtol=BRENT_XTOL_DEG, rtol=4 * np.finfo(float).eps))
