"""The θ_clamp search of the face/flop/travel fit (thesis §3.3.3; :mod:`station.model.fit`, module notes).

For a given θ_clamp the model is linear in face and flop (variable projection): :func:`project` solves them
by least squares, :func:`box_project` inside the Lab bound. The projected cost is evaluated on a fixed grid
(:func:`free_grid`, :func:`constrained_grid`) and the best grid point refined by a bracketed root search
on the exact slope (:func:`search_travel`); three angles have a closed form (:func:`three_angle_travel`).
Sums over the angles are written out term by term, so a paint's result does not depend on its batch.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from station.model.domain import LAB_HI, LAB_LO
from station.model.representations import FACE_ANGLE_DEG, TRAVEL_MAX_DEG, shape_factor

#: Lower end of the θ_clamp search: just above the face angle (a vertex at or below 15° is refused).
TC_LOW = FACE_ANGLE_DEG + 1e-3
#: Paints per block of the grid search (bounds the working memory: block × grid × angles × 3 floats).
_BLOCK = 128
#: Most steps of the root search on the slope (it stops at one ulp of θ_c long before).
_ROOT_STEPS = 100

F64 = NDArray[np.float64]
Solve = Callable[[F64, F64], tuple[F64, F64, F64]]


# ------------------------------------------------------------------------------ sums over angles


def sum_angles(x: F64) -> F64:
    """Σ over the angle axis (the last) term by term: the same rounding whatever the leading shape."""
    acc = x[..., 0].copy()
    for j in range(1, x.shape[-1]):
        acc += x[..., j]
    return acc


def sum_angles_lab(x: F64) -> F64:
    """Σ over the angle axis of (..., k, 3) arrays, term by term → (..., 3)."""
    acc = x[..., 0, :].copy()
    for j in range(1, x.shape[-2]):
        acc += x[..., j, :]
    return acc


# ------------------------------------------------------------------------------ linear parts


def project(u: F64, y: F64) -> tuple[F64, F64, F64]:
    """Linear least squares X = face·u + flop·(1 − u) per channel for fixed s² = *u*.

    *u* is (..., k), *y* (..., k, 3) (broadcasting); returns face (..., 3), flop (..., 3) and the model
    (..., k, 3). Solved by a QR factorisation of [u, 1 − u] (modified Gram–Schmidt, two columns); when
    u is 0 at every angle (θ_c at or below the first measured angle) face is undetermined and the
    minimum-norm answer face = 0 is returned.
    """
    a1, a2 = u, 1.0 - u
    n1 = np.sqrt(sum_angles(a1 * a1))
    has_face = n1 > 0.0
    q1 = np.divide(a1, n1[..., None], out=np.zeros_like(a1), where=has_face[..., None])
    r12 = sum_angles(q1 * a2)
    v = a2 - r12[..., None] * q1
    n2 = np.sqrt(sum_angles(v * v))
    q2 = np.divide(v, n2[..., None], out=np.zeros_like(v), where=(n2 > 0.0)[..., None])
    z1 = sum_angles_lab(q1[..., None] * y)
    w = y - q1[..., None] * z1[..., None, :]
    z2 = sum_angles_lab(q2[..., None] * w)
    flop = np.divide(z2, n2[..., None], out=np.zeros_like(z2), where=(n2 > 0.0)[..., None])
    face = np.divide(
        z1 - r12[..., None] * flop, n1[..., None], out=np.zeros_like(z1), where=has_face[..., None]
    )
    model = u[..., None] * face[..., None, :] + a2[..., None] * flop[..., None, :]
    return face, flop, model


def box_project(u: F64, y: F64) -> tuple[F64, F64, F64]:
    """As :func:`project` with face and flop of each channel held inside the Lab bound.

    A convex quadratic in two variables per channel: the optimum is the unconstrained solution when it
    lies in the box, otherwise on one of the four edges, where it is the clipped 1-D minimiser.
    """
    lo, hi = np.asarray(LAB_LO, dtype=float), np.asarray(LAB_HI, dtype=float)
    face0, flop0, _ = project(u, y)
    inside = (face0 >= lo) & (face0 <= hi) & (flop0 >= lo) & (flop0 <= hi)
    cols = (u, 1.0 - u)
    candidates: list[tuple[F64, F64, F64]] = []
    for j in (0, 1):  # variable j held on a bound, the other solved and clipped
        cj, ck = cols[j][..., None], cols[1 - j][..., None]
        norm = sum_angles(cols[1 - j] * cols[1 - j])[..., None]
        for bound in (lo, hi):
            r = y - cj * bound
            num = sum_angles_lab(ck * r)
            xk = np.clip(np.divide(num, norm, out=np.zeros_like(num), where=norm > 0.0), lo, hi)
            xk = np.where(norm > 0.0, xk, lo)
            xj = np.broadcast_to(bound, xk.shape)
            face, flop = (xj, xk) if j == 0 else (xk, xj)
            miss = u[..., None] * face[..., None, :] + cols[1][..., None] * flop[..., None, :] - y
            candidates.append((face, flop, sum_angles_lab(miss * miss)))
    best_face, best_flop, best_cost = candidates[0]
    for face, flop, cost in candidates[1:]:  # the first of equal costs is kept
        better = cost < best_cost
        best_face = np.where(better, face, best_face)
        best_flop = np.where(better, flop, best_flop)
        best_cost = np.where(better, cost, best_cost)
    face = np.where(inside, face0, best_face)
    flop = np.where(inside, flop0, best_flop)
    model = u[..., None] * face[..., None, :] + cols[1][..., None] * flop[..., None, :]
    return face, flop, model


# ------------------------------------------------------------------------------ θ_clamp search


def cost(model: F64, y: F64) -> F64:
    miss = model - y
    return sum_angles(sum_angles_lab(miss * miss))


def cost_and_slope(theta: F64, y: F64, tc: F64, solve: Solve) -> tuple[F64, F64]:
    """Projected cost f(θ_c) and its exact slope f'(θ_c) per paint (module notes); *tc* is (M,)."""
    col = tc[:, None]
    u = shape_factor(theta, col)
    face, flop, model = solve(u, y)
    clamped = np.minimum(theta, col)
    du = 2.0 * np.sqrt(u) * (clamped - FACE_ANGLE_DEG) / (col - FACE_ANGLE_DEG) ** 2  # ∂s²/∂θ_c
    miss = model - y
    weighted = miss * (face - flop)[:, None, :]
    per_angle = weighted[..., 0] + weighted[..., 1] + weighted[..., 2]  # Σ_c, (M, k)
    return cost(model, y), 2.0 * sum_angles(du * per_angle)


def grid_costs(theta: F64, y: F64, grid: F64, solve: Solve) -> F64:
    """f(θ_c) of every paint (rows of *y*) at every grid point: (M, G)."""
    u = shape_factor(theta[None, :], grid[:, None])[None]  # (1, G, k)
    out = np.empty((y.shape[0], grid.size))
    for start in range(0, y.shape[0], _BLOCK):
        yb = y[start : start + _BLOCK, None]  # (b, 1, k, 3)
        out[start : start + _BLOCK] = cost(solve(u, yb)[2], yb)
    return out


def free_grid_costs(theta: F64, y: F64, grid: F64) -> F64:
    """f(θ_c) of the unconstrained fit on the grid, (M, G): |y|² − |Qᵀy|² with the orthonormal basis Q of
    [u, 1 − u] at each grid point (shared by all paints, so no (M, G, k, 3) array is formed). The
    subtraction costs accuracy near a zero residual (about 1e-16 of |y|²); these costs only rank the
    grid points, and the costs compared afterwards are computed from the residual itself."""
    u = shape_factor(theta[None, :], grid[:, None])  # (G, k)
    a2 = 1.0 - u
    n1 = np.sqrt(sum_angles(u * u))
    q1 = np.divide(u, n1[:, None], out=np.zeros_like(u), where=n1[:, None] > 0.0)
    r12 = sum_angles(q1 * a2)
    v = a2 - r12[:, None] * q1
    n2 = np.sqrt(sum_angles(v * v))
    q2 = np.divide(v, n2[:, None], out=np.zeros_like(v), where=n2[:, None] > 0.0)
    out = np.empty((y.shape[0], grid.size))
    for start in range(0, y.shape[0], 4 * _BLOCK):
        yb = y[start : start + 4 * _BLOCK]  # (b, k, 3)
        sq = yb * yb
        total = sum_angles(sq[..., 0] + sq[..., 1] + sq[..., 2])
        z1 = q1[None, :, 0, None] * yb[:, None, 0, :]  # (b, G, 3)
        z2 = q2[None, :, 0, None] * yb[:, None, 0, :]
        for j in range(1, theta.size):
            z1 += q1[None, :, j, None] * yb[:, None, j, :]
            z2 += q2[None, :, j, None] * yb[:, None, j, :]
        p = z1 * z1 + z2 * z2
        out[start : start + 4 * _BLOCK] = total[:, None] - (p[..., 0] + p[..., 1] + p[..., 2])
    return out


def slope_root(slope: Callable[[F64, NDArray[np.intp]], F64], lo: F64, hi: F64, g_lo: F64, g_hi: F64) -> F64:
    """Root of the slope inside brackets with g_lo < 0 < g_hi, per row (Illinois regula falsi).

    Each step takes the secant point of the bracket (halving the weight of an end kept twice in a
    row, so both ends move), falling back to the midpoint where the secant leaves the bracket; a row
    stops once its bracket is two ulps wide or its step no longer moves θ_c. ``slope(x, rows)`` gives
    f' at x for the given rows. A stopped row is not touched again, so its result does not depend on
    the other rows.
    """
    lo, hi, g_lo, g_hi = lo.copy(), hi.copy(), g_lo.copy(), g_hi.copy()
    x = 0.5 * (lo + hi)
    side = np.zeros(lo.size, dtype=int)  # -1: lo moved last, +1: hi moved last
    running = np.ones(lo.size, dtype=bool)
    for _ in range(_ROOT_STEPS):
        running &= hi - lo > 2.0 * np.spacing(hi)
        sel = np.flatnonzero(running)
        if sel.size == 0:
            break
        a, b, ga, gb = lo[sel], hi[sel], g_lo[sel], g_hi[sel]
        secant = b - gb * (b - a) / (gb - ga)
        mid = 0.5 * (a + b)
        xs = np.where((secant > a) & (secant < b), secant, mid)
        g = slope(xs, sel)
        still = np.abs(xs - x[sel]) > np.spacing(xs)
        x[sel] = xs
        falling = g < 0.0
        rising = g > 0.0
        s_prev = side[sel]
        lo[sel] = np.where(falling, xs, a)
        g_lo[sel] = np.where(falling, g, np.where(rising & (s_prev == 1), 0.5 * ga, ga))
        hi[sel] = np.where(rising, xs, b)
        g_hi[sel] = np.where(rising, g, np.where(falling & (s_prev == -1), 0.5 * gb, gb))
        side[sel] = np.where(falling, -1, np.where(rising, 1, 0))
        running[sel] = still & (g != 0.0)
    return x


def search_travel(theta: F64, y: F64, grid: F64, costs: F64, solve: Solve) -> F64:
    """θ_clamp of least projected cost per paint: the best point of the grid (*costs*, (M, G)), refined
    by the root search on the slope inside its two neighbours."""
    i = np.argmin(costs, axis=1)
    m = grid[i]
    a, b = grid[np.maximum(i - 1, 0)], grid[np.minimum(i + 1, grid.size - 1)]
    _, da = cost_and_slope(theta, y, a, solve)
    best, dm = cost_and_slope(theta, y, m, solve)
    _, db = cost_and_slope(theta, y, b, solve)
    right = dm < 0.0  # cost still falling at the grid's best: the minimum lies towards b
    lo, hi = np.where(right, m, a), np.where(right, b, m)
    ok = np.where(right, db > 0.0, (dm > 0.0) & (da < 0.0))
    rows = np.flatnonzero(ok)
    tc = m.copy()
    if rows.size:
        yr = y[rows]
        refined = slope_root(
            lambda x, sel: cost_and_slope(theta, yr[sel], x, solve)[1],
            lo[rows],
            hi[rows],
            np.where(right, dm, da)[rows],
            np.where(right, db, dm)[rows],
        )
        cost, _ = cost_and_slope(theta, yr, refined, solve)
        tc[rows] = np.where(cost <= best[rows], refined, m[rows])
    return tc


def free_grid() -> F64:
    return np.unique(
        np.concatenate([np.linspace(TC_LOW, 30.0, 60), np.arange(30.0, TRAVEL_MAX_DEG + 1e-9, 0.5)])
    )


def constrained_grid() -> F64:
    low = TC_LOW + 2e-2  # stay clear of the refused vertex at the face angle
    return np.unique(
        np.concatenate([np.linspace(low, 30.0, 80), np.arange(30.0, TRAVEL_MAX_DEG + 1e-9, 0.25)])
    )


def three_angle_travel(angles: F64, lum: F64) -> F64:
    """θ_clamp that makes L pass exactly through three values (closed form) per paint, NaN where none.

    Case A, θ_c >= θ3: the unclamped parabola through the three points has its vertex at θ_c (eq 3.3.4).
    Case B, θ2 < θ_c < θ3: flop = L3 and (L2 − flop)/(L1 − flop) = ((θ_c − θ2)/(θ_c − θ1))².
    *lum* is (N, 3).
    """
    t1, t2, t3 = float(angles[0]), float(angles[1]), float(angles[2])
    l1, l2, l3 = lum[:, 0], lum[:, 1], lum[:, 2]
    # the parabola X_a θ² + X_b θ + X_c through the three points, in Lagrange form
    w1, w2, w3 = 1.0 / ((t1 - t2) * (t1 - t3)), 1.0 / ((t2 - t1) * (t2 - t3)), 1.0 / ((t3 - t1) * (t3 - t2))
    xa = w1 * l1 + w2 * l2 + w3 * l3
    xb = -(w1 * (t2 + t3) * l1 + w2 * (t1 + t3) * l2 + w3 * (t1 + t2) * l3)
    vertex = np.divide(-xb, 2.0 * xa, out=np.full_like(xb, np.nan), where=xa != 0.0)
    case_a = (vertex >= t3) & (vertex <= TRAVEL_MAX_DEG) & (vertex > FACE_ANGLE_DEG)  # NaN: False
    d1, d2 = lum[:, 0] - lum[:, 2], lum[:, 1] - lum[:, 2]
    rho = np.divide(d2, d1, out=np.full_like(d2, np.nan), where=d1 != 0.0)
    ok_rho = (rho > 0.0) & (rho < 1.0)
    r = np.sqrt(np.where(ok_rho, rho, 0.25))
    tc_b = (t2 - t1 * r) / (1.0 - r)
    case_b = ok_rho & (tc_b > t2) & (tc_b < t3) & (tc_b > FACE_ANGLE_DEG)
    return np.where(case_a, vertex, np.where(case_b, tc_b, np.nan))
