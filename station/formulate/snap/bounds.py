"""Lower (and upper) bounds of the summed colour difference between a design and boxes or paints.

The arithmetic behind ColorSnap's exact search (proof in :mod:`station.formulate.snap`): a lower bound
of Σ_θ ΔE(design_θ, x_θ) over every paint x of a box [lo, hi] (per angle L*, a*, b* ranges and the
largest chroma), for ΔE*ab, DIN 6175-2 (:func:`_din6175_box`) and CIEDE2000 (:func:`box_bounds`); the cheap CIEDE2000 form
with its weights from tables (:func:`box_bounds_cie2000_fast`); and trigonometry-free per-paint
CIEDE2000 lower and upper bounds (:func:`point_bounds_cie2000`, :func:`pair_bounds_cie2000`). All
quantities are in CIELAB units (ΔE, L*, a*, b*, C*), hues in degrees.
"""

from __future__ import annotations

import math
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import NDArray

from station.formulate.errors import FormulateInputError
from station.model.cie2000 import CIE2000_K7
from station.model.difference import DIN6175_COEFFICIENTS
from station.model.domain import SNAP_METRICS

__all__ = [
    "METHODS",
    "SAFETY",
    "SIN60",
    "TABLE_STEP",
    "T_MAX",
    "T_MIN",
    "W_AB",
    "W_L",
    "box_bounds",
    "box_bounds_cie2000_fast",
    "cie2000_weight_tables",
    "hue_geometry",
    "pair_bounds2",
    "pair_bounds_cie2000",
    "point_bounds_cie2000",
]

#: The colour-difference formulas ColorSnap ranks by (:data:`station.formulate.de_kernels.KERNELS`).
METHODS = SNAP_METRICS
#: sin 60°, the largest |sin 2Δθ| in CIEDE2000's R_T (Δθ ≤ 30°), rounded up.
SIN60 = math.sin(math.pi / 3) + 1e-12
#: Factor on every lower bound (upper bounds take 2 − SAFETY): margin for rounding in the bound arithmetic.
SAFETY = 1.0 - 1e-9
#: Range of CIEDE2000's T(h) (0.3621 … 1.5725 on a 1e-4° grid).
T_MIN, T_MAX = 0.36, 1.58
#: Grid step of the CIEDE2000 weight tables (CIELAB units).
TABLE_STEP = 0.1


def _wrap(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle difference wrapped to [-180, 180) degrees."""
    return (x + 180.0) % 360.0 - 180.0


def hue_geometry(
    q: NDArray[np.float64], lo: NDArray, hi: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Bounds from the primed hues h' = hue((1+G)a*, b*), G ∈ [0, 0.5], of the design and of a box.

    Returns ``(max_sin_2dtheta, min_hue_gap_deg)``:

    * an upper bound of sin(2Δθ) in CIEDE2000's R_T, Δθ = 30° exp(−((h̄' − 275°)/25°)²), h̄' being the
      midpoint of the shorter arc between h'_1 and h'_2. Each hue set is an arc (the design's over G,
      the box's over the stretched box when it does not hold the neutral axis); when both arcs plus
      their separation stay under 180°, h̄' lies within (w₁+w₂)/2 of the midpoint of their centres and
      |h̄' − 275°| is at least its circular distance to 275°. Otherwise sin 60°.
    * a lower bound of the hue difference |Δh'| (degrees): the gap between the two arcs, 0 where the
      box holds the neutral axis.
    """
    qa, qb = q[:, 1], q[:, 2]
    h_q0 = np.degrees(np.arctan2(qb, qa))
    h_q1 = np.degrees(np.arctan2(qb, 1.5 * qa))
    half_q = np.abs(_wrap(h_q1 - h_q0)) / 2
    c_q = h_q0 + _wrap(h_q1 - h_q0) / 2
    a_lo = np.minimum(lo[..., 1], 1.5 * lo[..., 1])
    a_hi = np.maximum(hi[..., 1], 1.5 * hi[..., 1])
    b_lo, b_hi = lo[..., 2], hi[..., 2]
    holds_axis = (a_lo <= 0) & (a_hi >= 0) & (b_lo <= 0) & (b_hi >= 0)
    h_mid = np.degrees(np.arctan2((b_lo + b_hi) / 2, (a_lo + a_hi) / 2))
    rel = np.stack([_wrap(np.degrees(np.arctan2(b, a)) - h_mid) for a in (a_lo, a_hi) for b in (b_lo, b_hi)])
    r_lo, r_hi = rel.min(0), rel.max(0)
    c_b = h_mid + (r_lo + r_hi) / 2
    half_b = (r_hi - r_lo) / 2
    d = _wrap(c_b - c_q)
    half = (half_q + half_b) / 2 + 1e-6
    ok = ~holds_axis & (np.abs(d) + 2 * half < 179.0)
    dist = np.maximum(np.abs(_wrap(275.0 - (c_q + d / 2))) - half, 0.0)
    dtheta = 30.0 * np.exp(-((dist / 25.0) ** 2))
    bound = np.where(ok, np.sin(np.deg2rad(2.0 * dtheta)) + 1e-12, SIN60)
    achromatic_query = (qa == 0) & (qb == 0)  # C'1 = 0 makes ΔH' = 0: the cross term vanishes
    sin_bound = np.where(achromatic_query, 0.0, np.minimum(bound, SIN60))
    gap = np.where(holds_axis, 0.0, np.maximum(np.abs(d) - half_q - half_b - 1e-6, 0.0))
    return sin_bound, np.minimum(gap, 180.0)


def box_bounds(
    q: NDArray[np.float64],
    lo: NDArray,
    hi: NDArray,
    cmax: NDArray,
    method: str,
    hue: bool = True,
    alpha: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Lower bound of Σ_θ ΔE(q_θ, x_θ) over every x in the boxes [lo, hi] (…, A, 3) with chroma ≤ cmax (…, A).

    A box of one point (lo = hi = x, cmax = C*(x)) gives the point-level bound used as a prefilter.
    *alpha* (A,) is the |aspecular angle| of each column in degrees, required by ``din6175``.
    """
    d = np.maximum(np.maximum(lo - q, q - hi), 0.0)
    d2 = d * d
    dl2 = d2[..., 0]
    dab2 = d2[..., 1] + d2[..., 2]
    if method == "cie76":
        per = np.sqrt(dl2 + dab2)
    elif method == "din6175":
        per = _din6175_box(q, lo, hi, cmax, d2, _din_alpha(alpha, q.shape[0]))
    elif method == "cie2000":
        x = np.maximum(np.abs((q[:, 0] + lo[..., 0]) / 2 - 50.0), np.abs((q[:, 0] + hi[..., 0]) / 2 - 50.0))
        s_l = 1.0 + 0.015 * x * x / np.sqrt(20.0 + x * x)
        cbar = (np.hypot(q[:, 1], q[:, 2]) + cmax) / 2
        c7 = cbar**7
        cpbar = (1.0 + 0.5 * (1.0 - np.sqrt(c7 / (c7 + CIE2000_K7)))) * cbar * (1 + 1e-12) + 1e-12
        cp7 = cpbar**7
        r_c = 2.0 * np.sqrt(cp7 / (cp7 + CIE2000_K7))
        s_c = 1.0 + 0.045 * cpbar
        if not hue:  # the cheaper, looser form: global R_T bound, no hue-gap term
            per = np.sqrt(dl2 / s_l**2 + (1.0 - r_c * SIN60 / 2.0) * dab2 / s_c**2)
            return per.sum(-1) * SAFETY - 1e-12
        sin_2dt, gap = hue_geometry(q, lo, hi)
        kappa = 1.0 - r_c * sin_2dt / 2.0
        s_h = 1.0 + (0.015 * T_MAX) * cpbar
        # |ΔH'| = 2 √(C'1 C'2) |sin(Δh'/2)| ≥ 2 √(C*1 C*2,min) sin(gap/2)  (C' ≥ C*)
        c_min = np.hypot(
            np.maximum(np.maximum(lo[..., 1], -hi[..., 1]), 0.0),
            np.maximum(np.maximum(lo[..., 2], -hi[..., 2]), 0.0),
        )
        h_min = 2.0 * np.sqrt(np.hypot(q[:, 1], q[:, 2]) * c_min) * np.sin(np.deg2rad(gap / 2.0))
        h2 = h_min * h_min
        chroma_hue = np.maximum(dab2 - h2, 0.0) / s_c**2 + h2 / s_h**2
        per = np.sqrt(dl2 / s_l**2 + kappa * chroma_hue)
    else:
        raise FormulateInputError("de", f"one of {', '.join(METHODS)}", method)
    return per.sum(-1) * SAFETY - 1e-12


def _din_alpha(alpha: NDArray[np.float64] | None, n_angles: int) -> NDArray[np.float64]:
    """The DIN 6175-2 angles of a query: |α| (n_angles,), each > 0; a typed error otherwise."""
    a = None if alpha is None else np.abs(np.asarray(alpha, dtype=np.float64)).reshape(-1)
    if a is None or a.shape != (n_angles,) or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise FormulateInputError(
            "angles_deg", f"{n_angles} non-zero aspecular angles (din6175 weights hold 1/angle)", alpha
        )
    return a


def _din6175_box(
    q: NDArray[np.float64], lo: NDArray, hi: NDArray, cmax: NDArray, d2: NDArray, alpha: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Per-angle lower bound of DIN 6175-2 ΔE_eff (g = 1) between the standard *q* and a box (…, A).

    ΔE_eff = σ ΔE_ab,w + (1 − σ) ΔE_CH,w with σ ∈ (0, 1) is at least min(ΔE_ab,w, ΔE_CH,w). Over the box:

    * |ΔL*| ≥ d_L, |Δa*| ≥ d_a, |Δb*| ≥ d_b (distances from q to the box), and ΔC*² + ΔH*² = Δa*² + Δb*²;
    * S_L = 0.15 √L̄ + 31.5/α is increasing in L̄ = √|L*_q L*_x|, so S_L ≤ S_L(L̄_max) with
      L̄_max = √(|L*_q| max|L*_x|);
    * S_C and S_H are increasing in C̄ = √(C*_q C*_x) and decreasing in L̄ (then floored at 0.7, which
      keeps the order), so S_C ≤ S_C(C̄_max, L̄_min), S_H ≤ S_H(C̄_max, L̄_min), C̄_max = √(C*_q C*_max),
      L̄_min = √(|L*_q| min|L*_x|) (0 where the box's L range holds 0);
    * hence ΔE_ab,w² ≥ (d_L/S_L,max)² + (d_a² + d_b²)/0.7² and ΔE_CH,w² ≥ (d_L/S_L,max)² + (d_a² + d_b²)/W²
      with W = max(S_C,max, S_H,max); the bound is the root of the smaller.
    """
    k = DIN6175_COEFFICIENTS
    lq = np.abs(q[:, 0])
    cq = np.hypot(q[:, 1], q[:, 2])
    l_abs_max = np.maximum(np.abs(lo[..., 0]), np.abs(hi[..., 0]))
    straddle = (lo[..., 0] <= 0) & (hi[..., 0] >= 0)
    l_abs_min = np.where(straddle, 0.0, np.minimum(np.abs(lo[..., 0]), np.abs(hi[..., 0])))
    sq_l_max = np.sqrt(np.sqrt(lq * l_abs_max))
    sq_l_min = np.sqrt(np.sqrt(lq * l_abs_min))
    sq_c_max = np.sqrt(np.sqrt(cq * np.maximum(cmax, 0.0)))
    s_l = k["sl_sqrt_l"] * sq_l_max + k["sl_alpha"] / alpha
    s_c = np.maximum(
        k["s_floor"], k["sc_sqrt_c"] * sq_c_max - k["sc_sqrt_l"] * sq_l_min + k["sc_alpha"] / alpha
    )
    s_h = np.maximum(
        k["s_floor"],
        k["sh_sqrt_c"] * sq_c_max - k["sh_sqrt_l"] * sq_l_min + k["sh_alpha"] / alpha + k["sh_offset"],
    )
    w = np.maximum(np.maximum(s_c, s_h), k["s_ab"])  # W ≥ 0.7 also covers the a*b* form
    dab2 = d2[..., 1] + d2[..., 2]
    return np.sqrt(d2[..., 0] / (s_l * s_l) + dab2 / (w * w))


def cie2000_weight_tables() -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Tables of the two weights of the cheap CIEDE2000 box bound (:func:`box_bounds_cie2000_fast`).

    * w_L(x) = 1/S_L² with x = 2|L̄' − 50| (decreasing in x);
    * w_ab(c) = (1 − R_C(c̄') sin 60°/2)/S_C(c̄')² with c = 2C̄*_ab and c̄' = (1 + G(C̄))C̄ the largest C̄'
      (C̄' ≤ (1+G)C̄ by the triangle inequality; (1+G(C̄))C̄ increasing, R_C and S_C increasing in C̄', so
      w_ab is decreasing in c).

    Grids x_i = i h from 0 (h = 0.1); entry i holds the weight at x_{i+1} and the last entry is 0: for a
    decreasing w, entry ⌊x/h⌋ (clamped to the last) is ≤ w(x) for every x ≥ 0, a valid lower bound.
    """
    xl = np.arange(3001) * TABLE_STEP
    lb2 = (xl / 2.0) ** 2
    w_l = 1.0 / (1.0 + 0.015 * lb2 / np.sqrt(20.0 + lb2)) ** 2
    xc = np.arange(12001) * TABLE_STEP
    cbar = xc / 2.0
    c7 = cbar**7
    cpbar = (1.0 + 0.5 * (1.0 - np.sqrt(c7 / (c7 + CIE2000_K7)))) * cbar
    cp7 = cpbar**7
    r_c = 2.0 * np.sqrt(cp7 / (cp7 + CIE2000_K7))
    w_ab = (1.0 - r_c * SIN60 / 2.0) / (1.0 + 0.045 * cpbar) ** 2
    shift = lambda w: np.append(w[1:], 0.0)  # noqa: E731
    return xl, shift(w_l), xc, shift(w_ab)


X_L, W_L, X_C, W_AB = cie2000_weight_tables()
for _table in (X_L, W_L, X_C, W_AB):
    _table.flags.writeable = False  # shared by every query: read-only
del _table


def box_bounds_cie2000_fast(
    q: NDArray[np.float64], lo: NDArray, hi: NDArray, lo_l: NDArray, hi_l: NDArray, cmax: NDArray
) -> NDArray[np.float64]:
    """The cheap CIEDE2000 box bound of :func:`box_bounds` (``hue=False``) with its weights from tables.

    ΔE00² ≥ (ΔL'/S_L)² + (1 − |R_T|/2)(ΔC'² + ΔH'²)/S_C² (|xy| ≤ (x² + y²)/2, S_H ≤ S_C), ΔC'² + ΔH'² =
    Δa'² + Δb² ≥ d_a² + d_b² (the box distances), |R_T| ≤ R_C sin 60°; S_L, S_C and R_C are taken at their
    largest over the box (L̄' at the end of the box's L range farther from 50, C̄* ≤ (C*_q + C*_max)/2),
    through :func:`cie2000_weight_tables`. *lo_l*, *hi_l* are the boxes' L ranges (…, A) contiguous.
    """
    d = np.maximum(lo - q, q - hi)
    np.maximum(d, 0.0, out=d)
    d *= d
    ql = q[:, 0] - 100.0
    x = np.maximum(np.abs(lo_l + ql), np.abs(hi_l + ql))
    x *= 1.0 / TABLE_STEP
    np.minimum(x, W_L.size - 1, out=x)
    w_l = W_L[x.astype(np.intp)]
    c = cmax + np.hypot(q[:, 1], q[:, 2])
    c *= 1.0 / TABLE_STEP
    np.minimum(c, W_AB.size - 1, out=c)
    w_ab = W_AB[c.astype(np.intp)]
    per = d[..., 0] * w_l
    per += (d[..., 1] + d[..., 2]) * w_ab
    return np.sqrt(per).sum(-1) * SAFETY - 1e-12


@overload
def point_bounds_cie2000(
    q: NDArray[np.float64], p: NDArray[np.float64], upper: Literal[False] = False
) -> NDArray[np.float64]: ...


@overload
def point_bounds_cie2000(
    q: NDArray[np.float64], p: NDArray[np.float64], upper: Literal[True]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...


def point_bounds_cie2000(
    q: NDArray[np.float64], p: NDArray[np.float64], upper: bool = False
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per-paint lower (and with *upper* also upper) bound of Σ_θ ΔE00(q_θ, p_θ), shape (n,), trig-free.

    Follows the CIEDE2000 arithmetic up to the hue terms: ΔL', ΔC', S_L, S_C and R_C are computed as in
    the formula; ΔH'² = |Δ(a', b)|² − ΔC'² (ΔC'² + ΔH'² = C'₁² + C'₂² − 2C'₁C'₂ cos Δh' = |Δ(a', b)|²);
    only S_H and R_T are bounded. With y = |ΔC'|/S_C, z = |ΔH'|/S_H and r = R_C sin 60°:

    * S_H = 1 + 0.015 C̄' T with T(h̄') ∈ [0.36, 1.58] puts z in [z_lo, z_hi] = |ΔH'|/(1 + 0.015 C̄' T_max …
      T_min);
    * R_T = −R_C sin 2Δθ, Δθ ∈ [0°, 30°], so R_T ∈ [−r, 0] and the cross term R_T (ΔC'/S_C)(ΔH'/S_H)
      lies in [−r y z, r y z] whatever the signs of ΔC' and ΔH';
    * ΔE00² = (ΔL'/S_L)² + y² + z² + R_T(…) ≥ (ΔL'/S_L)² + y² + min_{z ∈ [z_lo, z_hi]} z (z − r y), the
      minimum at z = clip(r y / 2, z_lo, z_hi) (a parabola in z);
    * ΔE00² ≤ (ΔL'/S_L)² + y² + z_hi (z_hi + r y) (increasing in z ≥ 0).

    Rounding: ΔH'² = |Δ(a', b)|² − ΔC'² cancels when ΔH' ≈ 0, so the interval of |ΔH'| is widened by
    ±1e-12 |Δ(a', b)|² under the root (covering the kernel's own sin/atan2 rounding as well); x⁷ is computed
    by multiplication and the order of operations differs from the kernel's, a few ulps that the final
    factor 1 ∓ 1e-9 and the ∓ 1e-10 absorb (tests check both bounds
    against the exact kernel with hypothesis, near-neutral and blue-region colours included).
    """
    lower2, upper2 = pair_bounds_cie2000(
        q[:, 0],
        q[:, 1],
        q[:, 2],
        np.hypot(q[:, 1], q[:, 2]),
        p[..., 0],
        p[..., 1],
        p[..., 2],
        np.hypot(p[..., 1], p[..., 2]),
        upper,
    )
    lower = np.sqrt(lower2).sum(-1) * SAFETY - 1e-10
    if upper2 is None:  # upper=False
        return lower
    return lower, np.sqrt(upper2).sum(-1) * (2.0 - SAFETY) + 1e-10


def pair_bounds_cie2000(
    ql: NDArray,
    qa: NDArray,
    qb: NDArray,
    qc: NDArray,
    pl: NDArray,
    pa: NDArray,
    pb: NDArray,
    pc: NDArray,
    upper: bool = True,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Lower and upper bounds of ΔE00² per pair (see :func:`point_bounds_cie2000`), from the columns L*,
    a*, b*, C*_ab of the reference (q…) and the sample (p…), which broadcast. No margin applied here;
    the upper bound is None with ``upper=False``. The arithmetic is :func:`pair_bounds2`'s."""
    lower2, upper2 = pair_bounds2(ql, qa, qb, qc, pl, pa, pb, pc)
    return lower2, (upper2 if upper else None)


def pair_bounds2(ql: Any, qa: Any, qb: Any, qc: Any, pl: Any, pa: Any, pb: Any, pc: Any) -> tuple[Any, Any]:
    """(lower, upper) bounds of ΔE00² for the reference L*, a*, b*, C*_ab (*ql* … *qc*) and the sample
    (*pl* … *pc*): arrays that broadcast (NumPy) or floats (the numba walk of
    :mod:`station.formulate.snap.kernel` compiles this same function inline, so the two paths share
    one copy of the arithmetic). Only ufuncs that numba compiles on scalars are used."""
    cbar = (qc + pc) * 0.5
    c7 = cbar * cbar
    c7 = c7 * c7 * c7 * cbar
    g1 = 1.5 - 0.5 * np.sqrt(c7 / (c7 + CIE2000_K7))
    a1 = g1 * qa
    a2 = g1 * pa
    cp1 = np.sqrt(a1 * a1 + qb * qb)
    cp2 = np.sqrt(a2 * a2 + pb * pb)
    dc = cp2 - cp1
    da = a2 - a1
    db = pb - qb
    dab2 = da * da + db * db
    dh2 = dab2 - dc * dc  # cancels when ΔH' ≈ 0: widened by ±1e-12 |Δ(a', b)|² (rounding, both sides)
    eta = 1e-12 * dab2 + 1e-30
    dh_lo = np.sqrt(np.maximum(dh2 - eta, 0.0))
    cpbar = (cp1 + cp2) * 0.5
    cp7 = cpbar * cpbar
    cp7 = cp7 * cp7 * cp7 * cpbar
    r = (2.0 * SIN60) * np.sqrt(cp7 / (cp7 + CIE2000_K7))
    lbar2 = (ql + pl) * 0.5 - 50.0
    lbar2 = lbar2 * lbar2
    s_l = 1.0 + 0.015 * lbar2 / np.sqrt(20.0 + lbar2)
    y = np.abs(dc) / (1.0 + 0.045 * cpbar)
    ry = r * y
    dl = (pl - ql) / s_l
    base = dl * dl + y * y
    z_hi = np.sqrt(np.maximum(dh2, 0.0) + eta) / (1.0 + (0.015 * T_MIN) * cpbar)
    z = np.minimum(np.maximum(ry * 0.5, dh_lo / (1.0 + (0.015 * T_MAX) * cpbar)), z_hi)
    return np.maximum(base + z * (z - ry), 0.0), base + z_hi * (z_hi + ry)


def median_leaves(x: NDArray[np.float64], leaf: int) -> tuple[NDArray[np.intp], list[tuple[int, int]]]:
    """Recursive median split of the rows of *x* (largest-spread coordinate); returns (perm, buckets)."""
    perm = np.arange(x.shape[0])
    buckets: list[tuple[int, int]] = []
    stack = [(0, x.shape[0])]
    while stack:
        lo, hi = stack.pop()
        n = hi - lo
        if n <= leaf:
            buckets.append((lo, hi))
            continue
        sub = x[perm[lo:hi]]
        dim = int(np.argmax(sub.max(0) - sub.min(0)))
        half = n // 2
        part = np.argpartition(sub[:, dim], half)
        perm[lo:hi] = perm[lo:hi][part]
        stack.append((lo + half, hi))
        stack.append((lo, lo + half))
    buckets.sort()
    return perm, buckets
