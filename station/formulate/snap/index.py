"""ColorSnap's exact index: median-split leaves with bounding boxes, the branch-and-bound search and
the brute-force reference (proof of exactness in :mod:`station.formulate.snap`).

An index is immutable after construction except for the finer CIEDE2000 index it builds once on first
use (under a lock); every query keeps its own statistics (:class:`SnapHits`), so one index serves
concurrent requests.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Collection
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.de_kernels import KERNELS, cie2000_columns
from station.formulate.errors import FormulateInputError
from station.formulate.library import PAINT_TYPES, STANDARD_ANGLES, Library
from station.formulate.snap.bounds import (
    METHODS,
    SAFETY,
    TABLE_STEP,
    W_AB,
    W_L,
    box_bounds,
    box_bounds_cie2000_fast,
    median_leaves,
    pair_bounds_cie2000,
    point_bounds_cie2000,
)
from station.formulate.snap.kernel import CandidateSearch, compiled_search
from station.formulate.snap.results import SnapMatch, SnapResult, SnapStats, snap_warnings
from station.formulate.snap.validation import validate_design_lab

__all__ = ["SnapHits", "SnapIndex", "brute_force", "color_snap"]

_SENTINEL = 1.0e6
#: Leaves evaluated per batch once a k-th best is known (each batch tightens it for the rest).
_BATCH_LEAVES = 40
#: Libraries up to this size get a finer partition for the compiled CIEDE2000 walk.
_FINE_MAX = 50_000
#: Leaves whose paints give the first k-th smallest upper bound (CIEDE2000, flat index).
_FIRST_LEAVES = 8
#: Above this many candidates the sharper per-paint CIEDE2000 bound filters them before the exact kernel.
_REFINE_ABOVE = 64


class SnapHits(NamedTuple):
    """One query's top-k: library rows, summed ΔE and ΔE per angle (best first), and its statistics."""

    rows: NDArray[np.intp]
    sums: NDArray[np.float64]
    per_angle: NDArray[np.float64]
    stats: SnapStats


class SnapIndex:
    """Exact top-k ColorSnap index over a library (or a raw ``(N, n_angles, 3)`` Lab array).

    Two tiers of boxes: leaves of ``leaf_size`` paints and groups of ``group`` consecutive leaves
    (consecutive in the median-split order, so spatially coherent). A query bounds the groups, opens
    the best group to get a first k-th best, then evaluates every leaf of every group whose bound does
    not exceed it. For CIEDE2000 a per-paint bound (the box bound of a single point, a fraction of the
    cost of the full formula) filters the gathered paints before the exact kernel runs.

    Parameters
    ----------
    library
        A :class:`Library` (its Lab at *angles_deg* is indexed) or an array ``(N, len(angles_deg), 3)``.
    angles_deg
        The angles summed over (degrees); default the standard 15/45/110.
    leaf_size, group
        Paints per leaf and leaves per group; defaults grow with N.
    """

    def __init__(
        self,
        library: Library | ArrayLike,
        angles_deg: tuple[float, ...] = STANDARD_ANGLES,
        leaf_size: int | None = None,
        group: int | None = None,
    ) -> None:
        if isinstance(library, Library):
            lab = library.angle_columns(angles_deg)
            self.codes: NDArray[np.str_] | None = library.codes
        else:
            lab = np.asarray(library, dtype=np.float64)
            self.codes = None
        if lab.ndim != 3 or lab.shape[1:] != (len(angles_deg), 3) or lab.shape[0] == 0:
            raise FormulateInputError("library", f"(N >= 1, {len(angles_deg)}, 3) Lab", lab.shape)
        self.angles_deg = tuple(float(a) for a in angles_deg)
        self._alpha = np.abs(np.asarray(self.angles_deg, dtype=np.float64))  # |α| of DIN 6175-2, (A,)
        self._alpha.flags.writeable = False
        self.lab = np.ascontiguousarray(lab)
        n, na = lab.shape[0], lab.shape[1]
        self.size = n
        if leaf_size is None:
            leaf_size = 32 if n <= 20_000 else 64
        perm, buckets = median_leaves(lab.reshape(n, -1), leaf_size)
        if group is None:
            group = 1 if len(buckets) <= 512 else 64
        nb = -(-len(buckets) // group) * group
        width = max(hi - lo for lo, hi in buckets)
        rows = np.full((nb, width), n, dtype=np.intp)
        for b, (lo, hi) in enumerate(buckets):
            rows[b, : hi - lo] = perm[lo:hi]
        self._rows = rows  # (nb, width) original row; n marks padding
        padded = np.concatenate([lab, np.full((1, na, 3), _SENTINEL)], axis=0)
        self._blab = padded[rows]  # (nb, width, A, 3)
        chroma = np.hypot(self._blab[..., 1], self._blab[..., 2])
        # columns L*, a*, b*, C*_ab per leaf, (nb, 4, width·A) contiguous: the per-paint bounds' layout
        self._cols = np.ascontiguousarray(
            np.stack([self._blab[..., 0], self._blab[..., 1], self._blab[..., 2], chroma], axis=1).reshape(
                len(rows), 4, -1
            )
        )
        real = (rows < n)[..., None, None]
        self._lo = np.where(real, self._blab, np.inf).min(axis=1)  # (nb, A, 3)
        self._hi = np.where(real, self._blab, -np.inf).max(axis=1)
        self._cmax = np.where(real[..., 0], chroma, -np.inf).max(axis=1)  # (nb, A)
        empty = ~(rows < n).any(axis=1)
        self._lo[empty] = self._hi[empty] = _SENTINEL
        self._cmax[empty] = _SENTINEL
        self._lab_t = np.ascontiguousarray(np.moveaxis(self.lab, -1, 0))  # (3, N, A): exact-kernel columns
        self._lo_l = np.ascontiguousarray(self._lo[..., 0])
        self._hi_l = np.ascontiguousarray(self._hi[..., 0])
        self.group = group
        ng = nb // group
        self._glo = self._lo.reshape(ng, group, na, 3).min(axis=1)
        self._ghi = self._hi.reshape(ng, group, na, 3).max(axis=1)
        self._gcmax = self._cmax.reshape(ng, group, na).max(axis=1)
        self.n_buckets = nb
        self._fine: SnapIndex | None = None
        self._fine_lock = threading.Lock()
        self.n_groups = ng

    def bucket_bounds(self, q: NDArray[np.float64], method: str) -> NDArray[np.float64]:
        """Lower bound of the summed ΔE over each leaf, shape (n_buckets,) (see module docstring)."""
        return box_bounds(q, self._lo, self._hi, self._cmax, method, alpha=self._alpha)

    # -- search -------------------------------------------------------------------------------------
    def query(
        self, lab: ArrayLike, k: int = 5, method: str = "cie76", use_numba: bool = True
    ) -> tuple[NDArray[np.intp], NDArray, NDArray]:
        """Return (rows, summed ΔE, ΔE per angle) of the *k* best paints, best first (exact).

        Ties in the sum are broken by the lower library row, as :func:`brute_force` does. For
        CIEDE2000 the numba-compiled walk runs where numba is installed and *use_numba* is true, the
        NumPy path otherwise (same result). :meth:`search` also returns the query's statistics.
        """
        found = self.search(lab, k, method, use_numba)
        return found.rows, found.sums, found.per_angle

    def search(self, lab: ArrayLike, k: int = 5, method: str = "cie76", use_numba: bool = True) -> SnapHits:
        """:meth:`query` with the statistics of this query (kept per call: queries may run concurrently)."""
        if method not in METHODS:
            raise FormulateInputError("de", f"one of {', '.join(METHODS)}", method)
        if not isinstance(k, (int, np.integer)) or isinstance(k, bool) or k < 1:
            raise FormulateInputError("k", "an integer >= 1", k)
        k = min(int(k), self.size)
        q = validate_design_lab(lab, len(self.angles_deg))
        kernel = KERNELS[method]
        first = max(1, -(-k // self._rows.shape[1])) + 1
        flat = self.n_groups == 1 or self.group == 1
        if method == "cie2000" and use_numba and (walk := compiled_search()) is not None:
            fine = self._cie2000_index()
            return fine._query_cie2000_compiled(q, k, walk)
        if flat and method == "cie2000":
            return self._query_cie2000_flat(q, k)
        leaves, lb, glb = self._first_leaves(q, method, first, flat)
        first = min(first, lb.size)
        pick = np.argpartition(lb, first - 1)[:first] if first < lb.size else np.arange(lb.size)
        sel = leaves[pick]
        rows, s, per = self._evaluate(kernel, q, sel, math.inf, k, method)
        kth = np.partition(s, k - 1)[k - 1] if s.size >= k else math.inf
        if flat:
            more, more_lb = self._more_flat(q, method, leaves, lb, pick, kth)
        else:
            more, more_lb = self._more_grouped(q, method, glb, sel, kth)
        found = (rows, s, per)
        rows, s, per, visited, evaluated = self._drain(kernel, q, k, method, more, more_lb, found, kth)
        visited += sel.size
        if s.size > k:
            keep_k = s <= np.partition(s, k - 1)[k - 1]
            rows, s, per = rows[keep_k], s[keep_k], per[keep_k]
        top = np.lexsort((rows, s))[:k]
        return SnapHits(
            rows[top], s[top], per[top], SnapStats(int(visited), self.n_buckets, evaluated, "bounded")
        )

    def _first_leaves(
        self, q: NDArray[np.float64], method: str, first: int, flat: bool
    ) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.float64]]:
        """Leaves to open first and their lower bounds (and the groups' bounds; empty when flat)."""
        if flat:  # (for CIEDE2000 the cheap bound first; the hue-aware one on the survivors later)
            lb = box_bounds(
                q, self._lo, self._hi, self._cmax, method, hue=method != "cie2000", alpha=self._alpha
            )
            return np.arange(lb.size), lb, np.empty(0)
        g = self.group  # open the best group(s) first: enough leaves for a k-th best
        glb = box_bounds(q, self._glo, self._ghi, self._gcmax, method, alpha=self._alpha)
        ng_first = min(self.n_groups, -(-first // g))
        gsel = (
            np.argpartition(glb, ng_first - 1)[:ng_first]
            if ng_first < self.n_groups
            else np.arange(self.n_groups)
        )
        leaves = (gsel[:, None] * g + np.arange(g)).ravel()
        lb = box_bounds(q, self._lo[leaves], self._hi[leaves], self._cmax[leaves], method, alpha=self._alpha)
        return leaves, lb, glb

    def _more_flat(
        self,
        q: NDArray[np.float64],
        method: str,
        leaves: NDArray[np.intp],
        lb: NDArray[np.float64],
        pick: NDArray[np.intp],
        kth: float,
    ) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
        """Unopened leaves whose bound does not exclude them (flat index)."""
        rest = lb <= kth
        rest[pick] = False
        more, more_lb = leaves[rest], lb[rest]
        if method == "cie2000" and more.size:
            more_lb = box_bounds(
                q, self._lo[more], self._hi[more], self._cmax[more], method, alpha=self._alpha
            )
            keep = more_lb <= kth
            more, more_lb = more[keep], more_lb[keep]
        return more, more_lb

    def _more_grouped(
        self, q: NDArray[np.float64], method: str, glb: NDArray[np.float64], sel: NDArray[np.intp], kth: float
    ) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
        """Unopened leaves of the groups whose bound does not exclude them (two-tier index)."""
        g = self.group
        gmore = np.flatnonzero(glb <= kth)
        cand = (gmore[:, None] * g + np.arange(g)).ravel()
        keep = ~np.isin(cand, sel)
        if method == "cie2000":  # cheap bound first, the hue-aware one on the survivors
            cand = cand[keep]
            keep = (
                box_bounds(
                    q, self._lo[cand], self._hi[cand], self._cmax[cand], method, hue=False, alpha=self._alpha
                )
                <= kth
            )
        cand = cand[keep]
        clb = box_bounds(q, self._lo[cand], self._hi[cand], self._cmax[cand], method, alpha=self._alpha)
        keep = clb <= kth
        return cand[keep], clb[keep]

    def _drain(
        self,
        kernel: Any,
        q: NDArray[np.float64],
        k: int,
        method: str,
        more: NDArray[np.intp],
        more_lb: NDArray[np.float64],
        found: tuple[NDArray, NDArray, NDArray],
        kth: float,
    ) -> tuple[NDArray, NDArray, NDArray, int, int]:
        """Open the remaining leaves best-bounded first, each batch tightening the k-th best; returns
        (rows, sums, per-angle, leaves visited, paints evaluated including *found*)."""
        rows, s, per = found
        visited = 0
        evaluated = rows.size
        while more.size:
            if more.size > 2 * _BATCH_LEAVES:
                part = np.argpartition(more_lb, _BATCH_LEAVES)
                now, later = part[:_BATCH_LEAVES], part[_BATCH_LEAVES:]
            else:
                now, later = np.arange(more.size), np.empty(0, dtype=np.intp)
            visited += now.size
            rows2, s2, per2 = self._evaluate(kernel, q, more[now], float(kth), k, method)
            evaluated += rows2.size
            rows = np.concatenate([rows, rows2])
            s = np.concatenate([s, s2])
            per = np.concatenate([per, per2])
            if s.size >= k:
                kth = np.partition(s, k - 1)[k - 1]
            still = more_lb[later] <= kth
            more, more_lb = more[later][still], more_lb[later][still]
        return rows, s, per, visited, evaluated

    def _tile(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The query's L*, a*, b*, C*_ab in the layout of a leaf's columns: (4, width·A)."""
        qcols = np.concatenate([q.T, np.hypot(q[:, 1], q[:, 2])[None]])
        return np.broadcast_to(qcols[:, None, :], (4, self._rows.shape[1], q.shape[0])).reshape(4, -1)

    def _gather(
        self, q: NDArray[np.float64], qt: NDArray[np.float64], leaves: NDArray[np.intp]
    ) -> tuple[NDArray, NDArray, NDArray]:
        """Real paints of *leaves*: (rows, per-paint CIEDE2000 lower and upper bounds of the summed ΔE00);
        *qt* is :meth:`_tile` of *q*."""
        rows = self._rows[leaves].ravel()
        cols = self._cols[leaves]
        lower2, upper2 = pair_bounds_cie2000(
            qt[0], qt[1], qt[2], qt[3], cols[:, 0], cols[:, 1], cols[:, 2], cols[:, 3]
        )
        na = q.shape[0]
        lower = np.sqrt(lower2).reshape(-1, na).sum(-1) * SAFETY - 1e-10
        upper = np.sqrt(upper2).reshape(-1, na).sum(-1) * (2.0 - SAFETY) + 1e-10  # type: ignore[arg-type]
        real = rows < self.size
        if not real.all():
            rows, lower, upper = rows[real], lower[real], upper[real]
        return rows, lower, upper

    def _cie2000_index(self) -> SnapIndex:
        """The index the compiled CIEDE2000 walk uses: for up to :data:`_FINE_MAX` paints a finer one
        (leaves of 8 in groups of 8: tighter boxes, fewer paints bounded; built on first use, ~10 ms for
        6000 paints), else this one."""
        if self.size > _FINE_MAX or (self._rows.shape[1] <= 8 and self.group == 8):
            return self
        with self._fine_lock:  # built once even when the first queries arrive together
            if self._fine is None:
                self._fine = SnapIndex(self.lab, self.angles_deg, leaf_size=8, group=8)
            return self._fine

    def _query_cie2000_compiled(self, q: NDArray[np.float64], k: int, walk: CandidateSearch) -> SnapHits:
        """Exact CIEDE2000 top-k: candidates from the compiled best-first walk (:func:`best_first_cie2000`),
        then the exact kernel on them and the (sum, row) order of a brute-force scan."""
        rows, visited = walk(
            np.ascontiguousarray(q),
            self._glo,
            self._ghi,
            self._gcmax,
            self._lo,
            self._hi,
            self._cmax,
            self.group,
            self._rows,
            self._blab,
            self.size,
            k,
        )
        n, na = rows.size, q.shape[0]
        pc = self._lab_t[:, rows].reshape(3, -1)
        qc = np.broadcast_to(q.T[:, None, :], (3, n, na)).reshape(3, -1)
        per = cie2000_columns(qc[0], qc[1], qc[2], pc[0], pc[1], pc[2]).reshape(n, na)
        s = per.sum(-1)
        top = np.lexsort((rows, s))[:k]
        return SnapHits(rows[top], s[top], per[top], SnapStats(int(visited), self.n_buckets, n, "compiled"))

    def _cheap_bounds(
        self, q: NDArray[np.float64], qt: NDArray[np.float64], leaves: NDArray[np.intp]
    ) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
        """Real paints of *leaves*: (rows, lower bound of the summed ΔE00), the bound of
        :func:`box_bounds_cie2000_fast` for single points (boxes of one paint); *qt* is :meth:`_tile` of *q*."""
        cols = self._cols[leaves]
        ql = qt[0]
        dl = cols[:, 0] - ql
        x = np.abs(cols[:, 0] + (ql - 100.0))
        x *= 1.0 / TABLE_STEP
        np.minimum(x, W_L.size - 1, out=x)
        xi = x.astype(np.intp)
        da = cols[:, 1] - qt[1]
        db = cols[:, 2] - qt[2]
        c = cols[:, 3] + qt[3]
        c *= 1.0 / TABLE_STEP
        np.minimum(c, W_AB.size - 1, out=c)
        ci = c.astype(np.intp)
        dl *= dl
        da *= da
        db *= db
        da += db
        na = q.shape[0]
        lower = np.sqrt(dl * W_L[xi] + da * W_AB[ci]).reshape(-1, na).sum(-1) * SAFETY - 1e-12
        rows = self._rows[leaves].ravel()
        real = rows < self.size
        if not real.all():
            rows, lower = rows[real], lower[real]
        return rows, lower

    def _query_cie2000_flat(self, q: NDArray[np.float64], k: int) -> SnapHits:
        """Exact CIEDE2000 top-k with one call of the exact kernel (libraries of a few thousand paints).

        The NumPy path (no numba):

        1. Box bound of every leaf (:func:`box_bounds_cie2000_fast`).
        2. The :data:`_FIRST_LEAVES` best leaves: per-paint lower and upper bounds
           (:func:`pair_bounds_cie2000`); u = k-th smallest upper bound ≥ S_k (the true k-th best sum),
           since k real paints have sums ≤ their upper bounds.
        3. Every other leaf whose bound is ≤ u: the table per-paint lower bound (:meth:`_cheap_bounds`);
           above :data:`_REFINE_ABOVE` candidates the sharp per-paint lower bound filters them again.
        4. The exact kernel on the paints whose lower bound is ≤ u, then (sum, row) order. A paint with
           S ≤ S_k has every lower bound ≤ S ≤ u and its leaf's bound ≤ S ≤ u, so it is among them: the
           top-k, ties included, is the brute-force one.
        """
        lb = box_bounds_cie2000_fast(q, self._lo, self._hi, self._lo_l, self._hi_l, self._cmax)
        width = self._rows.shape[1]
        first = min(lb.size, max(_FIRST_LEAVES, -(-k // width) + 1))
        sel = np.argpartition(lb, first - 1)[:first] if first < lb.size else np.arange(lb.size)
        qt = self._tile(q)
        rows, plb, pub = self._gather(q, qt, sel)
        u = np.partition(pub, k - 1)[k - 1] if pub.size >= k else math.inf
        rest = lb <= u
        rest[sel] = False
        more = np.flatnonzero(rest)
        rows = rows[plb <= u]
        if more.size:
            rows2, plb2 = self._cheap_bounds(q, qt, more)
            rows = np.concatenate([rows, rows2[plb2 <= u]])
        if rows.size > _REFINE_ABOVE:  # the sharper per-paint bound first when the cheap one left many
            pc = self._lab_t[:, rows]
            chroma = np.hypot(pc[1], pc[2])
            lower2, _ = pair_bounds_cie2000(
                q[:, 0],
                q[:, 1],
                q[:, 2],
                np.hypot(q[:, 1], q[:, 2]),
                pc[0],
                pc[1],
                pc[2],
                chroma,
                upper=False,
            )
            rows = rows[np.sqrt(lower2).sum(-1) * SAFETY - 1e-10 <= u]
        n, na = rows.size, q.shape[0]
        pc = self._lab_t[:, rows].reshape(3, -1)
        qc = np.broadcast_to(q.T[:, None, :], (3, n, na)).reshape(3, -1)
        per = cie2000_columns(qc[0], qc[1], qc[2], pc[0], pc[1], pc[2]).reshape(n, na)
        s = per.sum(-1)
        top = np.lexsort((rows, s))[:k]
        stats = SnapStats(int(sel.size + more.size), self.n_buckets, n, "flat")
        return SnapHits(rows[top], s[top], per[top], stats)

    def _evaluate(
        self,
        kernel: object,
        q: NDArray[np.float64],
        buckets: NDArray[np.intp],
        kth: float,
        k: int,
        method: str,
    ) -> tuple[NDArray, NDArray, NDArray]:
        """Exact ΔE of the real paints in *buckets* that could be within *kth*: (rows, sums, per-angle)."""
        rows = self._rows[buckets].ravel()
        pts = self._blab[buckets].reshape(-1, *q.shape)
        real = rows < self.size
        if not real.all():
            rows, pts = rows[real], pts[real]
        if method == "cie2000" and rows.size > 8 * k:
            plb = point_bounds_cie2000(q, pts)
            if kth == math.inf:  # the best few by bound give a k-th best to filter the rest with
                m = 4 * k
                head = np.argpartition(plb, m - 1)[:m]
                per_h = kernel(q, pts[head], self._alpha)  # type: ignore[operator]
                s_h = per_h.sum(-1)
                kth = float(np.partition(s_h, k - 1)[k - 1])
                keep = plb <= kth
                keep[head] = False
                per_r = kernel(q, pts[keep], self._alpha)  # type: ignore[operator]
                per = np.concatenate([per_h, per_r])
                return np.concatenate([rows[head], rows[keep]]), per.sum(-1), per
            keep = plb <= kth
            rows, pts = rows[keep], pts[keep]
        per = kernel(q, pts, self._alpha)  # type: ignore[operator]
        return rows, per.sum(-1), per

    def snap(self, lab: ArrayLike, k: int = 5, method: str = "cie76", use_numba: bool = True) -> SnapResult:
        """Run :meth:`search` and wrap it with codes (when built from a library) and its statistics;
        no warnings."""
        found = self.search(lab, k, method, use_numba)
        rows, s, per = found.rows, found.sums, found.per_angle
        matches = tuple(
            SnapMatch(
                int(r),
                str(self.codes[r]) if self.codes is not None else str(int(r)),
                float(v),
                tuple(float(x) for x in p),
            )
            for r, v, p in zip(rows, s, per, strict=True)
        )
        q = np.asarray(lab, dtype=np.float64)
        return SnapResult(
            matches,
            method,
            self.angles_deg,
            tuple((float(row[0]), float(row[1]), float(row[2])) for row in q),
            stats=found.stats,
        )


def brute_force(
    lib_lab: ArrayLike,
    lab: ArrayLike,
    k: int = 5,
    method: str = "cie76",
    angles_deg: tuple[float, ...] = STANDARD_ANGLES,
) -> tuple[NDArray[np.intp], NDArray, NDArray]:
    """Reference scan through :func:`station.model.difference.delta_e`: (rows, sums, per-angle), best first.

    *angles_deg* are the aspecular angles of the Lab columns (read by ``din6175``)."""
    from station.model.difference import delta_e

    lib_lab = np.asarray(lib_lab, dtype=np.float64)
    per = delta_e(np.asarray(lab, dtype=np.float64)[None], lib_lab, method, aspecular_deg=angles_deg)
    s = per.sum(-1)
    top = np.lexsort((np.arange(s.size), s))[: min(k, s.size)]
    return top, s[top], per[top]


def type_rows(
    library: Library, types: Collection[str] | None, field: str = "type"
) -> NDArray[np.intp] | None:
    """Rows of *library* whose paint type is in *types*; ``None`` when *types* restricts nothing.

    Raises :class:`FormulateInputError` (naming *field*) for an unknown type or when no paint of the
    library has one of the types."""
    if types is None:
        return None
    chosen = frozenset(str(t) for t in types)
    unknown = sorted(chosen - set(PAINT_TYPES))
    if unknown or not chosen:
        raise FormulateInputError(field, " | ".join(PAINT_TYPES), ",".join(unknown) or "none")
    if chosen >= set(library.types.tolist()):
        return None
    rows = np.flatnonzero(np.isin(library.types, sorted(chosen)))
    if rows.size == 0:
        held = sorted(set(library.types.tolist()))
        raise FormulateInputError(
            field, f"a type the library holds: {' | '.join(held)}", ",".join(sorted(chosen))
        )
    return rows


def color_snap(
    library: Library,
    lab: ArrayLike,
    k: int = 5,
    method: str = "cie76",
    index: SnapIndex | None = None,
    use_numba: bool = True,
    types: Collection[str] | None = None,
) -> SnapResult:
    """ColorSnap: top-*k* library paints nearest to the design Lab (15/45/110), with warnings.

    Parameters
    ----------
    library
        The library to search.
    lab
        Design L*a*b* at the standard angles, shape (3, 3).
    k
        Number of matches.
    method
        ``"cie76"`` (ΔE*ab, the thesis's), ``"cie2000"`` or ``"din6175"``.
    index
        A prebuilt :class:`SnapIndex` of *library* (building one costs ~10 ms for 6000 paints).
    use_numba
        Run CIEDE2000 through the numba-compiled walk where numba is installed (the NumPy path
        otherwise; same matches).
    types
        Paint types to search (``solid``, ``metallic``, ``pearl``); ``None`` searches every paint. A
        restriction searches an index of those paints only (built per call, ~10 ms for 6000 paints;
        *index* is then not used) and reports the matches by their row in *library*.
    """
    rows = type_rows(library, types)
    if rows is not None:
        sub = library.subset(rows)
        found = color_snap(sub, lab, min(k, len(sub)), method, None, use_numba)
        return SnapResult(
            tuple(SnapMatch(int(rows[m.index]), m.code, m.sum_de, m.de_per_angle) for m in found.matches),
            found.method,
            found.angles_deg,
            found.design_lab,
            found.warnings,
            found.stats,
        )
    index = index or SnapIndex(library)
    result = index.snap(lab, k, method, use_numba)
    return SnapResult(
        result.matches,
        result.method,
        result.angles_deg,
        result.design_lab,
        snap_warnings(library, result),
        result.stats,
    )
