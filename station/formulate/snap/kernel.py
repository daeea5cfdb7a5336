"""The numba-compiled CIEDE2000 best-first walk of ColorSnap (proof in :mod:`station.formulate.snap`).

:func:`best_first_cie2000` and the scalar box bound it calls (:func:`box_bound_one`) are plain Python
functions written in the subset numba compiles; :func:`compiled_search` returns the compiled walk
(built once per process, cached on disk) or ``None`` where numba is missing or cannot compile, and
the NumPy path of :class:`~station.formulate.snap.index.SnapIndex` runs instead. Nothing here is
rebound: numba learns to compile calls to :func:`box_bound_one` by registration
(``numba.extending.register_jitable``), so the plain functions stay what tests call.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from station.formulate.snap.bounds import SAFETY, SIN60, pair_bounds2
from station.jit import CompiledLoops
from station.model.cie2000 import CIE2000_K7

__all__ = ["CandidateSearch", "best_first_cie2000", "box_bound_one", "compiled_search"]

#: The walk's signature: (q, group boxes lo/hi/cmax, leaf boxes lo/hi/cmax, group, rows, leaf Lab,
#: library size, k) -> (candidate rows, leaves visited).
CandidateSearch = Callable[..., tuple[NDArray[np.intp], int]]


def box_bound_one(q: NDArray, cq: NDArray, lo: NDArray, hi: NDArray, cmax: NDArray, i: int) -> float:
    """The ``hue=False`` CIEDE2000 box bound of :func:`box_bounds` for box *i* (scalar form, compiled)."""
    k7 = CIE2000_K7
    total = 0.0
    for t in range(q.shape[0]):
        d0 = max(lo[i, t, 0] - q[t, 0], q[t, 0] - hi[i, t, 0], 0.0)
        d1 = max(lo[i, t, 1] - q[t, 1], q[t, 1] - hi[i, t, 1], 0.0)
        d2 = max(lo[i, t, 2] - q[t, 2], q[t, 2] - hi[i, t, 2], 0.0)
        x = max(abs((q[t, 0] + lo[i, t, 0]) / 2 - 50.0), abs((q[t, 0] + hi[i, t, 0]) / 2 - 50.0))
        s_l = 1.0 + 0.015 * x * x / math.sqrt(20.0 + x * x)
        cbar = (cq[t] + cmax[i, t]) / 2
        c7 = cbar**7
        cpbar = (1.0 + 0.5 * (1.0 - math.sqrt(c7 / (c7 + k7)))) * cbar * (1 + 1e-12) + 1e-12
        cp7 = cpbar**7
        r_c = 2.0 * math.sqrt(cp7 / (cp7 + k7))
        s_c = 1.0 + 0.045 * cpbar
        total += math.sqrt(
            d0 * d0 / (s_l * s_l) + (1.0 - r_c * SIN60 / 2.0) * (d1 * d1 + d2 * d2) / (s_c * s_c)
        )
    return total * SAFETY - 1e-12


def paint_bounds_one(q: NDArray, cq: NDArray, blab: NDArray, i: int, w: int) -> tuple[float, float]:
    """Lower and upper bounds of the summed CIEDE2000 of paint (*i*, *w*) of the leaf table *blab* to
    the query *q* (chromas *cq*): :func:`~station.formulate.snap.bounds.pair_bounds2` per angle (the
    NumPy path's own arithmetic), summed with :func:`point_bounds_cie2000`'s margins (compiled inline
    into :func:`best_first_cie2000`)."""
    lower = 0.0
    upper = 0.0
    for t in range(q.shape[0]):
        pa, pb = blab[i, w, t, 1], blab[i, w, t, 2]
        lo2, hi2 = pair_bounds2(
            q[t, 0], q[t, 1], q[t, 2], cq[t], blab[i, w, t, 0], pa, pb, math.sqrt(pa * pa + pb * pb)
        )
        lower += math.sqrt(lo2)
        upper += math.sqrt(hi2)
    return lower * SAFETY - 1e-10, upper * (2.0 - SAFETY) + 1e-10


def insert_sorted(best: NDArray, value: float) -> None:
    """Insert *value* into the ascending array *best*, dropping its largest entry."""
    m = best.shape[0] - 1
    while m > 0 and best[m - 1] > value:
        best[m] = best[m - 1]
        m -= 1
    best[m] = value


def best_first_cie2000(
    q: NDArray[np.float64],
    glo: NDArray,
    ghi: NDArray,
    gcmax: NDArray,
    lo: NDArray,
    hi: NDArray,
    cmax: NDArray,
    group: int,
    rows: NDArray,
    blab: NDArray,
    size: int,
    k: int,
) -> tuple[NDArray[np.intp], int]:
    """Candidates of the exact CIEDE2000 top-k: every paint whose summed ΔE00 could be ≤ the k-th best.

    Compiled with numba where it is installed (:func:`compiled_search`); plain Python otherwise (tests).
    Leaves are visited in order of their box bound (the ``hue=False`` form of :func:`box_bounds`); in
    each, every paint gets the lower and upper bounds of :func:`point_bounds_cie2000` (the same
    arithmetic, per element, with the same margins); u is the k-th smallest upper bound so far (≥ S_k,
    the true k-th best sum). The walk stops at the first leaf whose bound exceeds u: every later leaf's
    bound is larger. A paint with S ≤ S_k has lower bound ≤ S ≤ S_k ≤ u and its leaf's bound ≤ S_k ≤ u
    at every moment, so it was visited and kept; the result is the paints with lower bound ≤ the final u.
    Returns (candidate rows, leaves visited). Only +, −, ×, ÷, √, min, max and abs (correctly rounded or
    exact IEEE operations, as in NumPy) are used, so the margins of :func:`point_bounds_cie2000` hold.
    """
    nb, width, na = rows.shape[0], rows.shape[1], q.shape[0]
    cq = np.empty(na)
    for t in range(na):
        cq[t] = math.sqrt(q[t, 1] * q[t, 1] + q[t, 2] * q[t, 2])
    ng = glo.shape[0]
    glb = np.empty(ng)
    for g in range(ng):
        glb[g] = box_bound_one(q, cq, glo, ghi, gcmax, g)
    gorder = np.argsort(glb)
    best = np.full(k, np.inf)  # the k smallest upper bounds, ascending
    cand = np.empty(nb * width, dtype=np.intp)
    cand_lb = np.empty(nb * width)
    lb = np.empty(group)
    nc = 0
    visited = 0
    for gj in range(ng):
        g = gorder[gj]
        if glb[g] > best[k - 1]:
            break
        if group == 1:
            lb[0] = glb[g]
        else:
            for m in range(group):
                lb[m] = box_bound_one(q, cq, lo, hi, cmax, g * group + m)
        order = np.argsort(lb)
        for j in range(group):
            i = g * group + order[j]
            if lb[order[j]] > best[k - 1]:
                break
            visited += 1
            for w in range(width):
                row = rows[i, w]
                if row >= size:
                    continue
                lower, upper = paint_bounds_one(q, cq, blab, i, w)
                if lower <= best[k - 1]:
                    cand[nc] = row
                    cand_lb[nc] = lower
                    nc += 1
                if upper < best[k - 1]:
                    insert_sorted(best, upper)
    u = best[k - 1]
    keep = cand_lb[:nc] <= u
    return cand[:nc][keep], visited


def _warm_up(search: CandidateSearch) -> None:
    """Compile (or load from the cache) now, not mid-query."""
    box, one = np.zeros((1, 1, 3)), np.zeros((1, 1))
    search(
        np.zeros((1, 3)),
        box,
        box,
        one,
        box,
        box,
        one,
        1,
        np.zeros((1, 1), dtype=np.intp),
        np.zeros((1, 1, 1, 3)),
        1,
        1,
    )


#: The walk and the helpers it calls, compiled inline (not rebound).
_LOOPS = CompiledLoops(
    (best_first_cie2000,),
    inline=(pair_bounds2, box_bound_one, paint_bounds_one, insert_sorted),
    warm_up=_warm_up,
)


def compiled_search() -> CandidateSearch | None:
    """:func:`best_first_cie2000` compiled by numba (once per process, cached on disk), or None where
    numba is missing or cannot compile here."""
    loops = _LOOPS.get()
    return None if loops is None else loops[0]
