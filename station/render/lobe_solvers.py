"""Fixed-matrix non-negative least squares for the lobe fit (thesis eq 2.4.2; methods in
:mod:`station.render.lobe_fit`).

A :class:`_Part` holds one weighted design matrix A = QR with its pseudo-inverse and, for small bases,
the pseudo-inverse of every passive set; the solvers map reduced right-hand sides Qᵀb (k, n) to weights
x ≥ 0 (k, n): ``enum`` (passive-set enumeration), ``kkt`` (guess, verify the KKT conditions, repair),
``nnls`` (Lawson–Hanson) and ``clamped-lsq`` (least squares, negatives set to zero).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

#: Relative singular-value cut-off of every pseudo-inverse (columns scaled to unit norm first): near-
#: duplicate exponents are solved in their well-determined span instead of blowing up.
PINV_RCOND = 1e-7
#: Largest lobe count fitted by enumeration (2^(m+1) passive sets); larger bases use Lawson–Hanson.
ENUM_MAX_UNKNOWNS = 10


def _subset_maps(r: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """For the reduced k×k matrix R, stack pinv(R[:, P]) (padded to k×k) for every column subset P."""
    k = r.shape[1]
    n_sub = 1 << k
    masks = ((np.arange(n_sub)[:, None] >> np.arange(k)[None, :]) & 1).astype(bool)
    maps = np.zeros((n_sub, k, k))
    scale = np.linalg.norm(r, axis=0)
    scale = np.where(scale > 0.0, scale, 1.0)
    for s in range(1, n_sub):
        cols = np.flatnonzero(masks[s])
        sub = r[:, cols] / scale[cols]
        # rcond guards near-duplicate exponents: the subset is solved in its well-determined span only.
        maps[s][cols] = np.linalg.pinv(sub, rcond=PINV_RCOND) / scale[cols][:, None]
    return maps, masks


@dataclass(frozen=True)
class _Part:
    """One fixed-matrix part of the fit: A = Q R over weighted rows, plus the passive-set maps."""

    a: NDArray[np.float64]  # (rows, k) weighted design matrix
    q: NDArray[np.float64]  # (rows, k)
    r: NDArray[np.float64]  # (k, k)
    pinv: NDArray[np.float64]  # (k, rows) least-squares solution map

    @classmethod
    def build(cls, a: NDArray[np.float64]) -> _Part:
        q, r = np.linalg.qr(a)
        scale = np.linalg.norm(a, axis=0)
        scale = np.where(scale > 0.0, scale, 1.0)
        pinv = np.linalg.pinv(a / scale, rcond=PINV_RCOND) / scale[:, None]
        return cls(a, q, r, pinv)

    @cached_property
    def maps(self) -> NDArray[np.float64] | None:
        """(2^k·k, k) stacked passive-set maps on the reduced RHS (built on first use), None if k is large."""
        k = self.r.shape[1]
        return _subset_maps(self.r)[0].reshape(-1, k) if k <= ENUM_MAX_UNKNOWNS else None

    @cached_property
    def pinv_r(self) -> NDArray[np.float64]:
        """pinv(R) with the same column scaling and cut-off as :attr:`pinv` (pinv(A) = pinv(R) Qᵀ)."""
        scale = np.linalg.norm(self.r, axis=0)
        scale = np.where(scale > 0.0, scale, 1.0)
        return np.linalg.pinv(self.r / scale, rcond=PINV_RCOND) / scale[:, None]


def _solve_enum(part: _Part, d: NDArray[np.float64], chunk: int = 768) -> NDArray[np.float64]:
    """Exact NNLS of min ‖R x − d‖, x ≥ 0 for every column of d (k, n) by passive-set enumeration."""
    flat = part.maps
    if flat is None:
        return _solve_nnls(part, d)
    k = part.r.shape[1]
    n_sub = flat.shape[0] // k
    out = np.empty_like(d)
    for start in range(0, d.shape[1], chunk):
        dd = d[:, start : start + chunk]
        y = (flat @ dd).reshape(n_sub, k, -1)  # every passive-set solution
        score = np.einsum("skn,kn->sn", y, part.r.T @ dd)  # bᵀA x_P = ‖A x_P‖² (projection)
        score[(y < 0.0).any(axis=1)] = -np.inf
        best = score.argmax(axis=0)
        out[:, start : start + chunk] = y[best, :, np.arange(dd.shape[1])].T
    return out


def _solve_kkt(part: _Part, d: NDArray[np.float64], rounds: int = 4) -> NDArray[np.float64]:
    """Exact NNLS for many columns: guess each passive set, verify the KKT conditions, repair, fall back.

    Start from the signs of the unconstrained solution; solve on the guessed set with the precomputed
    passive-set map; a column is done when x ≥ 0 and the gradient Rᵀ(Rx − d) ≥ 0 off the set (the KKT
    conditions, sufficient for this convex problem). Otherwise drop negative entries and add violated
    ones, up to *rounds* times; columns still unresolved go to Lawson–Hanson. Exact, like ``enum``,
    at O(k²) per column instead of O(2^k k²).
    """
    flat = part.maps
    if flat is None:
        return _solve_nnls(part, d)
    k = part.r.shape[1]
    maps = flat.reshape(-1, k, k)
    bits = 1 << np.arange(k)
    out = np.zeros_like(d)
    todo = np.arange(d.shape[1])
    tol = 1e-10 * (np.abs(part.r).max() * np.abs(d).max(axis=0) + 1e-300)
    passive = (part.pinv_r @ d) > 0.0
    for _ in range(rounds):
        if todo.size == 0:
            return out
        dd = d[:, todo]
        x = np.einsum("nij,jn->in", maps[bits @ passive[:, todo]], dd)
        grad = part.r.T @ (part.r @ x - dd)
        ok = (x >= 0.0).all(axis=0) & (grad >= -tol[todo]).all(axis=0)
        out[:, todo[ok]] = x[:, ok]
        passive[:, todo] = (x > 0.0) | (grad < -tol[todo])
        todo = todo[~ok]
    if todo.size:
        out[:, todo] = _solve_nnls(part, d[:, todo])
    return out


def _solve_nnls(part: _Part, d: NDArray[np.float64]) -> NDArray[np.float64]:
    from scipy.optimize import nnls

    out = np.zeros_like(d)
    for j in range(d.shape[1]):
        out[:, j] = nnls(part.r, d[:, j], maxiter=50 * part.r.shape[1])[0]
    return out


def _solve_clamped(part: _Part, d: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.maximum(part.pinv_r @ d, 0.0)
