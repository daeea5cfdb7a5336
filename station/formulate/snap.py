"""ColorSnap: the nearest library paints to a design by summed ΔE over the standard angles (thesis §5.3.5).

Ranking: paints are ordered by S = Σ_θ ΔE(design_θ, paint_θ) over the angles (15°, 45°, 110° by
default), ties broken by library row, exactly as a brute-force scan would order them
(:func:`brute_force`). The metric is ΔE*ab (the thesis's), CIEDE2000 or the DIN 6175-2 form, all through
kernels bit-identical to :func:`station.model.difference.delta_e` (:mod:`station.formulate.de_kernels`).

Search (exact branch and bound). The library is split once, by recursive median cuts of the
concatenated 9-D Lab vector, into buckets of equal size; each bucket keeps, per angle, its box
[L_min, L_max] × [a_min, a_max] × [b_min, b_max] and its largest chroma C_max. For a query, a lower
bound of S over every paint in a bucket is the sum over angles of a lower bound of ΔE between the
design and the box:

* ΔE*ab:    the Euclidean distance from the design to the box (d_L, d_ab: per-axis distances).
* DIN 6175: weights are computed on the reference (the design), so ΔE ≥ √((d_L/S_L)² + d_ab²/S_C²),
  using ΔC*² + ΔH*² = Δa*² + Δb*² and S_H ≤ S_C.
* CIEDE2000: ΔE00² ≥ (ΔL'/S_L)² + (1 − |R_T|/2) (ΔC'² + ΔH'²)/S_C² (|xy| ≤ (x²+y²)/2, S_H < S_C since
  T ≤ 1.93), ΔC'² + ΔH'² = Δa'² + Δb² ≥ Δa² + Δb² (a' = (1+G)a, one G per pair), with S_L, S_C and
  R_C replaced by their largest values over the box: S_L is increasing in |L̄ − 50|, C̄' ≤ (1+G(C̄))C̄
  is increasing in C̄ (checked numerically: slope ≥ 0.52 on 0–1000) and |R_T| ≤ R_C(C̄'_max)·sin 2Δθ_max,
  where Δθ_max comes from the arc of hues the pair's mean hue can take (:func:`_hue_geometry`; the
  global sin 60° where the box holds the neutral axis); the part of the a*b* distance that must be a hue
  difference (the gap between the hue arcs) is weighted by 1/S_H,max instead of 1/S_C,max. Per paint, a trigonometry-free bound
  (:func:`_point_bounds_cie2000`) filters the gathered paints before the exact formula runs.

Buckets are visited in order of their bound; the search stops when the next bound exceeds the k-th
best exact S found so far. Every paint whose S could tie or beat the k-th is evaluated exactly, so
the top-k equals brute force (tests/formulate/test_snap.py proves it with hypothesis).

CIEDE2000 (:meth:`SnapIndex._query_cie2000_compiled`): a numba-compiled best-first walk
(:func:`_best_first_cie2000`) bounds every visited paint from below and above
(:func:`_point_bounds_cie2000`), keeps u = the k-th smallest upper bound, stops at the first box whose
bound exceeds u, and returns the paints whose lower bound is ≤ u; the exact kernel runs once, on those
(:func:`station.formulate.de_kernels.cie2000_columns`). Without numba, :meth:`SnapIndex._query_cie2000_flat`
(NumPy) does the same with table bounds. tests/formulate/test_snap_cie2000.py checks the bounds and both
paths against brute force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.de_kernels import KERNELS, cie2000_columns
from station.formulate.errors import FormulateInputError
from station.formulate.library import STANDARD_ANGLES, Library
from station.model.domain import LAB_RANGES, lab_accepted

METHODS = ("cie76", "cie2000", "din6175")
#: Mean ΔE per angle of the best match above which the design is "far outside the library".
FAR_THRESHOLD = {"cie76": 5.0, "cie2000": 3.0, "din6175": 3.0}
#: Hue Shift Index difference (ΔE*ab units) above which the match does not capture the design's travel.
HUE_SHIFT_THRESHOLD = 5.0
#: Angle between design and match a*b* travel vectors (degrees) above which travel is "not captured".
TRAVEL_ANGLE_THRESHOLD_DEG = 45.0
_SIN60 = math.sin(math.pi / 3) + 1e-12
_SAFETY = 1.0 - 1e-9
_SENTINEL = 1.0e6
#: Leaves evaluated per batch once a k-th best is known (each batch tightens it for the rest).
_BATCH_LEAVES = 40
#: Use the numba-compiled CIEDE2000 search where numba is installed (tests switch it off for the NumPy path).
_USE_COMPILED = True
#: Libraries up to this size get a finer partition for the compiled CIEDE2000 walk.
_FINE_MAX = 50_000
#: Leaves whose paints give the first k-th smallest upper bound (CIEDE2000, flat index).
_FIRST_LEAVES = 8
#: Above this many candidates the sharper per-paint CIEDE2000 bound filters them before the exact kernel.
_REFINE_ABOVE = 64
#: Accepted query Lab: the domain's effect-paint bound (station.model.domain.LAB_RANGES).
LAB_QUERY_RANGE = LAB_RANGES
_Q_LO = np.array([v[0] for v in LAB_QUERY_RANGE.values()])
_Q_HI = np.array([v[1] for v in LAB_QUERY_RANGE.values()])


@dataclass(frozen=True)
class SnapMatch:
    """One ColorSnap match: library row, code, summed ΔE and ΔE per angle (same order as the angles)."""

    index: int
    code: str
    sum_de: float
    de_per_angle: tuple[float, ...]


@dataclass(frozen=True)
class SnapResult:
    """Top-k matches (best first), the metric, the angles and the Fig. 5.10 warnings."""

    matches: tuple[SnapMatch, ...]
    method: str
    angles_deg: tuple[float, ...]
    design_lab: tuple[tuple[float, float, float], ...]
    warnings: tuple[str, ...] = ()
    stats: dict[str, int] = field(default_factory=dict, compare=False)

    def to_dict(self) -> dict[str, object]:
        """JSON-able form used by the CLI and the service."""
        return {
            "matches": [
                {"code": m.code, "sum_de": m.sum_de, "de_per_angle": list(m.de_per_angle), "index": m.index}
                for m in self.matches
            ],
            "warnings": list(self.warnings),
            "method": self.method,
            "angles_deg": list(self.angles_deg),
        }


def validate_design_lab(lab: ArrayLike, n_angles: int = 3, field_name: str = "lab") -> NDArray[np.float64]:
    """Return *lab* as an (n_angles, 3) float array, or raise :class:`FormulateInputError`."""
    try:
        q = np.asarray(lab, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise FormulateInputError(field_name, f"{n_angles} Lab triples", lab) from exc
    if q.shape != (n_angles, 3):
        raise FormulateInputError(field_name, f"{n_angles} Lab triples (one per angle)", q.shape)
    if bool(((q >= _Q_LO) & (q <= _Q_HI)).all()):  # fast path; NaN fails both comparisons
        return q
    for j, (name, (lo, hi)) in enumerate(LAB_QUERY_RANGE.items()):
        col = q[:, j]
        if not np.all(np.isfinite(col)) or np.any(col < lo) or np.any(col > hi):
            raise FormulateInputError(f"{field_name}.{name}", f"finite {lab_accepted(name)}", col.tolist())
    return q


def _partition(x: NDArray[np.float64], leaf: int) -> tuple[NDArray[np.intp], list[tuple[int, int]]]:
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


def _wrap(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle difference wrapped to [-180, 180) degrees."""
    return (x + 180.0) % 360.0 - 180.0


def _hue_geometry(
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
    bound = np.where(ok, np.sin(np.deg2rad(2.0 * dtheta)) + 1e-12, _SIN60)
    achromatic_query = (qa == 0) & (qb == 0)  # C'1 = 0 makes ΔH' = 0: the cross term vanishes
    sin_bound = np.where(achromatic_query, 0.0, np.minimum(bound, _SIN60))
    gap = np.where(holds_axis, 0.0, np.maximum(np.abs(d) - half_q - half_b - 1e-6, 0.0))
    return sin_bound, np.minimum(gap, 180.0)


def _box_bounds(
    q: NDArray[np.float64], lo: NDArray, hi: NDArray, cmax: NDArray, method: str, hue: bool = True
) -> NDArray[np.float64]:
    """Lower bound of Σ_θ ΔE(q_θ, x_θ) over every x in the boxes [lo, hi] (…, A, 3) with chroma ≤ cmax (…, A).

    A box of one point (lo = hi = x, cmax = C*(x)) gives the point-level bound used as a prefilter.
    """
    d = np.maximum(np.maximum(lo - q, q - hi), 0.0)
    d2 = d * d
    dl2 = d2[..., 0]
    dab2 = d2[..., 1] + d2[..., 2]
    if method == "cie76":
        per = np.sqrt(dl2 + dab2)
    elif method == "din6175":
        cq = np.hypot(q[:, 1], q[:, 2])
        dl50 = (q[:, 0] - 50.0) ** 2
        s_l = 1.0 + 0.015 * dl50 / np.sqrt(20.0 + dl50)
        s_c = 1.0 + 0.045 * cq
        per = np.sqrt(dl2 / s_l**2 + dab2 / s_c**2)
    elif method == "cie2000":
        x = np.maximum(np.abs((q[:, 0] + lo[..., 0]) / 2 - 50.0), np.abs((q[:, 0] + hi[..., 0]) / 2 - 50.0))
        s_l = 1.0 + 0.015 * x * x / np.sqrt(20.0 + x * x)
        cbar = (np.hypot(q[:, 1], q[:, 2]) + cmax) / 2
        c7 = cbar**7
        cpbar = (1.0 + 0.5 * (1.0 - np.sqrt(c7 / (c7 + 25.0**7)))) * cbar * (1 + 1e-12) + 1e-12
        cp7 = cpbar**7
        r_c = 2.0 * np.sqrt(cp7 / (cp7 + 25.0**7))
        s_c = 1.0 + 0.045 * cpbar
        if not hue:  # the cheaper, looser form: global R_T bound, no hue-gap term
            per = np.sqrt(dl2 / s_l**2 + (1.0 - r_c * _SIN60 / 2.0) * dab2 / s_c**2)
            return per.sum(-1) * _SAFETY - 1e-12
        sin_2dt, gap = _hue_geometry(q, lo, hi)
        kappa = 1.0 - r_c * sin_2dt / 2.0
        s_h = 1.0 + (0.015 * _T_MAX) * cpbar
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
    return per.sum(-1) * _SAFETY - 1e-12


_TABLE_STEP = 0.1


def _cie2000_weight_tables() -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Tables of the two weights of the cheap CIEDE2000 box bound (:func:`_box_bounds_cie2000_fast`).

    * w_L(x) = 1/S_L² with x = 2|L̄' − 50| (decreasing in x);
    * w_ab(c) = (1 − R_C(c̄') sin 60°/2)/S_C(c̄')² with c = 2C̄*_ab and c̄' = (1 + G(C̄))C̄ the largest C̄'
      (C̄' ≤ (1+G)C̄ by the triangle inequality; (1+G(C̄))C̄ increasing, R_C and S_C increasing in C̄', so
      w_ab is decreasing in c).

    Grids x_i = i h from 0 (h = 0.1); entry i holds the weight at x_{i+1} and the last entry is 0: for a
    decreasing w, entry ⌊x/h⌋ (clamped to the last) is ≤ w(x) for every x ≥ 0, a valid lower bound.
    """
    xl = np.arange(3001) * _TABLE_STEP
    lb2 = (xl / 2.0) ** 2
    w_l = 1.0 / (1.0 + 0.015 * lb2 / np.sqrt(20.0 + lb2)) ** 2
    xc = np.arange(12001) * _TABLE_STEP
    cbar = xc / 2.0
    c7 = cbar**7
    cpbar = (1.0 + 0.5 * (1.0 - np.sqrt(c7 / (c7 + 25.0**7)))) * cbar
    cp7 = cpbar**7
    r_c = 2.0 * np.sqrt(cp7 / (cp7 + 25.0**7))
    w_ab = (1.0 - r_c * _SIN60 / 2.0) / (1.0 + 0.045 * cpbar) ** 2
    shift = lambda w: np.append(w[1:], 0.0)  # noqa: E731
    return xl, shift(w_l), xc, shift(w_ab)


_XL, _WL, _XC, _WAB = _cie2000_weight_tables()


def _box_bounds_cie2000_fast(
    q: NDArray[np.float64], lo: NDArray, hi: NDArray, lo_l: NDArray, hi_l: NDArray, cmax: NDArray
) -> NDArray[np.float64]:
    """The cheap CIEDE2000 box bound of :func:`_box_bounds` (``hue=False``) with its weights from tables.

    ΔE00² ≥ (ΔL'/S_L)² + (1 − |R_T|/2)(ΔC'² + ΔH'²)/S_C² (|xy| ≤ (x² + y²)/2, S_H ≤ S_C), ΔC'² + ΔH'² =
    Δa'² + Δb² ≥ d_a² + d_b² (the box distances), |R_T| ≤ R_C sin 60°; S_L, S_C and R_C are taken at their
    largest over the box (L̄' at the end of the box's L range farther from 50, C̄* ≤ (C*_q + C*_max)/2),
    through :func:`_cie2000_weight_tables`. *lo_l*, *hi_l* are the boxes' L ranges (…, A) contiguous.
    """
    d = np.maximum(lo - q, q - hi)
    np.maximum(d, 0.0, out=d)
    d *= d
    ql = q[:, 0] - 100.0
    x = np.maximum(np.abs(lo_l + ql), np.abs(hi_l + ql))
    x *= 1.0 / _TABLE_STEP
    np.minimum(x, _WL.size - 1, out=x)
    w_l = _WL[x.astype(np.intp)]
    c = cmax + np.hypot(q[:, 1], q[:, 2])
    c *= 1.0 / _TABLE_STEP
    np.minimum(c, _WAB.size - 1, out=c)
    w_ab = _WAB[c.astype(np.intp)]
    per = d[..., 0] * w_l
    per += (d[..., 1] + d[..., 2]) * w_ab
    return np.sqrt(per).sum(-1) * _SAFETY - 1e-12


_T_MIN, _T_MAX = 0.36, 1.58  # range of CIEDE2000's T(h) (0.3621 … 1.5725 on a 1e-4° grid)


def _point_bounds_cie2000(
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
    lower2, upper2 = _pair_bounds_cie2000(
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
    lower = np.sqrt(lower2).sum(-1) * _SAFETY - 1e-10
    if not upper:
        return lower
    return lower, np.sqrt(upper2).sum(-1) * (2.0 - _SAFETY) + 1e-10


def _pair_bounds_cie2000(
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
    """Lower and upper bounds of ΔE00² per pair (see :func:`_point_bounds_cie2000`), from the columns L*,
    a*, b*, C*_ab of the reference (q…) and the sample (p…), which broadcast. No margin applied here."""
    cbar = (qc + pc) * 0.5
    c7 = cbar * cbar
    c7 = c7 * c7 * c7 * cbar
    g1 = 1.5 - 0.5 * np.sqrt(c7 / (c7 + 25.0**7))
    a1 = g1 * qa
    a2 = g1 * pa
    cp1 = np.sqrt(a1 * a1 + qb * qb)
    cp2 = np.sqrt(a2 * a2 + pb * pb)
    dc = cp2 - cp1
    da = a2 - a1
    db = pb - qb
    dab2 = da * da + db * db
    dc2 = dc * dc
    dh2 = dab2 - dc2  # cancels when ΔH' ≈ 0: widened by ±1e-12 |Δ(a', b)|² (rounding, both sides)
    eta = 1e-12 * dab2 + 1e-30
    dh_lo = np.sqrt(np.maximum(dh2 - eta, 0.0))
    cpbar = (cp1 + cp2) * 0.5
    cp7 = cpbar * cpbar
    cp7 = cp7 * cp7 * cp7 * cpbar
    r = (2.0 * _SIN60) * np.sqrt(cp7 / (cp7 + 25.0**7))
    lbar2 = (ql + pl) * 0.5 - 50.0
    lbar2 *= lbar2
    s_l = 1.0 + 0.015 * lbar2 / np.sqrt(20.0 + lbar2)
    y = np.abs(dc) / (1.0 + 0.045 * cpbar)
    ry = r * y
    dl = (pl - ql) / s_l
    base = dl * dl + y * y
    z_hi = np.sqrt(np.maximum(dh2, 0.0) + eta) / (1.0 + (0.015 * _T_MIN) * cpbar)
    z = np.minimum(np.maximum(ry * 0.5, dh_lo / (1.0 + (0.015 * _T_MAX) * cpbar)), z_hi)
    lower2 = np.maximum(base + z * (z - ry), 0.0)
    return lower2, (base + z_hi * (z_hi + ry) if upper else None)


def _box_bound_one(q: NDArray, cq: NDArray, lo: NDArray, hi: NDArray, cmax: NDArray, i: int) -> float:
    """The ``hue=False`` CIEDE2000 box bound of :func:`_box_bounds` for box *i* (scalar form, compiled)."""
    k7 = 25.0**7
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
            d0 * d0 / (s_l * s_l) + (1.0 - r_c * _SIN60 / 2.0) * (d1 * d1 + d2 * d2) / (s_c * s_c)
        )
    return total * _SAFETY - 1e-12


def _best_first_cie2000(
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

    Compiled with numba where it is installed (:func:`_compiled_search`); plain Python otherwise (tests).
    Leaves are visited in order of their box bound (the ``hue=False`` form of :func:`_box_bounds`); in
    each, every paint gets the lower and upper bounds of :func:`_point_bounds_cie2000` (the same
    arithmetic, per element, with the same margins); u is the k-th smallest upper bound so far (≥ S_k,
    the true k-th best sum). The walk stops at the first leaf whose bound exceeds u: every later leaf's
    bound is larger. A paint with S ≤ S_k has lower bound ≤ S ≤ S_k ≤ u and its leaf's bound ≤ S_k ≤ u
    at every moment, so it was visited and kept; the result is the paints with lower bound ≤ the final u.
    Returns (candidate rows, leaves visited). Only +, −, ×, ÷, √, min, max and abs (correctly rounded or
    exact IEEE operations, as in NumPy) are used, so the margins of :func:`_point_bounds_cie2000` hold.
    """
    nb, width, na = rows.shape[0], rows.shape[1], q.shape[0]
    k7 = 25.0**7
    cq = np.empty(na)
    for t in range(na):
        cq[t] = math.sqrt(q[t, 1] * q[t, 1] + q[t, 2] * q[t, 2])
    ng = glo.shape[0]
    glb = np.empty(ng)
    for g in range(ng):
        glb[g] = _box_bound_one(q, cq, glo, ghi, gcmax, g)
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
                lb[m] = _box_bound_one(q, cq, lo, hi, cmax, g * group + m)
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
                lower = 0.0
                upper = 0.0
                for t in range(na):
                    pl, pa, pb = blab[i, w, t, 0], blab[i, w, t, 1], blab[i, w, t, 2]
                    ql, qa, qb = q[t, 0], q[t, 1], q[t, 2]
                    cbar = (cq[t] + math.sqrt(pa * pa + pb * pb)) * 0.5
                    c7 = cbar * cbar
                    c7 = c7 * c7 * c7 * cbar
                    g1 = 1.5 - 0.5 * math.sqrt(c7 / (c7 + k7))
                    a1 = g1 * qa
                    a2 = g1 * pa
                    cp1 = math.sqrt(a1 * a1 + qb * qb)
                    cp2 = math.sqrt(a2 * a2 + pb * pb)
                    dc = cp2 - cp1
                    da = a2 - a1
                    db = pb - qb
                    dab2 = da * da + db * db
                    dh2 = dab2 - dc * dc
                    eta = 1e-12 * dab2 + 1e-30
                    dh_lo = math.sqrt(max(dh2 - eta, 0.0))
                    dh_hi = math.sqrt(max(dh2, 0.0) + eta)
                    cpbar = (cp1 + cp2) * 0.5
                    cp7 = cpbar * cpbar
                    cp7 = cp7 * cp7 * cp7 * cpbar
                    r = (2.0 * _SIN60) * math.sqrt(cp7 / (cp7 + k7))
                    lbar2 = (ql + pl) * 0.5 - 50.0
                    lbar2 = lbar2 * lbar2
                    s_l = 1.0 + 0.015 * lbar2 / math.sqrt(20.0 + lbar2)
                    y = abs(dc) / (1.0 + 0.045 * cpbar)
                    ry = r * y
                    dl = (pl - ql) / s_l
                    base = dl * dl + y * y
                    z_hi = dh_hi / (1.0 + (0.015 * _T_MIN) * cpbar)
                    z = min(max(ry * 0.5, dh_lo / (1.0 + (0.015 * _T_MAX) * cpbar)), z_hi)
                    lower += math.sqrt(max(base + z * (z - ry), 0.0))
                    upper += math.sqrt(base + z_hi * (z_hi + ry))
                lower = lower * _SAFETY - 1e-10
                upper = upper * (2.0 - _SAFETY) + 1e-10
                if lower <= best[k - 1]:
                    cand[nc] = row
                    cand_lb[nc] = lower
                    nc += 1
                if upper < best[k - 1]:
                    m = k - 1
                    while m > 0 and best[m - 1] > upper:
                        best[m] = best[m - 1]
                        m -= 1
                    best[m] = upper
    u = best[k - 1]
    keep = cand_lb[:nc] <= u
    return cand[:nc][keep], visited


_COMPILED: dict[str, object] = {}


def _compiled_search() -> object | None:
    """:func:`_best_first_cie2000` compiled by numba (cached on disk), or None where numba is missing."""
    if "search" not in _COMPILED:
        try:
            import numba
        except ImportError:  # pragma: no cover - numba is a declared dependency; the NumPy path remains
            _COMPILED["search"] = None
        else:
            global _box_bound_one
            try:
                if not hasattr(_box_bound_one, "py_func"):  # the walk calls the compiled bound
                    _box_bound_one = numba.njit(cache=True, nogil=True)(_box_bound_one)
                search = numba.njit(cache=True, nogil=True)(_best_first_cie2000)
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
                )  # compile (or load from the cache) now, not mid-query
            except Exception:  # pragma: no cover - a numba that cannot compile here: the NumPy path runs
                search = None
            _COMPILED["search"] = search
    return _COMPILED["search"]


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
        self.lab = np.ascontiguousarray(lab)
        n, na = lab.shape[0], lab.shape[1]
        self.size = n
        if leaf_size is None:
            leaf_size = 32 if n <= 20_000 else 64
        perm, buckets = _partition(lab.reshape(n, -1), leaf_size)
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
        self.n_groups = ng
        self.last_visited = 0

    def bucket_bounds(self, q: NDArray[np.float64], method: str) -> NDArray[np.float64]:
        """Lower bound of the summed ΔE over each leaf, shape (n_buckets,) (see module docstring)."""
        return _box_bounds(q, self._lo, self._hi, self._cmax, method)

    # -- search -------------------------------------------------------------------------------------
    def query(
        self, lab: ArrayLike, k: int = 5, method: str = "cie76"
    ) -> tuple[NDArray[np.intp], NDArray, NDArray]:
        """Return (rows, summed ΔE, ΔE per angle) of the *k* best paints, best first (exact).

        Ties in the sum are broken by the lower library row, as :func:`brute_force` does.
        """
        if method not in METHODS:
            raise FormulateInputError("de", f"one of {', '.join(METHODS)}", method)
        if not isinstance(k, (int, np.integer)) or isinstance(k, bool) or k < 1:
            raise FormulateInputError("k", "an integer >= 1", k)
        k = min(int(k), self.size)
        q = validate_design_lab(lab, len(self.angles_deg))
        kernel = KERNELS[method]
        g = self.group
        first = max(1, -(-k // self._rows.shape[1])) + 1
        flat = self.n_groups == 1 or g == 1
        if method == "cie2000" and _USE_COMPILED and (search := _compiled_search()) is not None:
            fine = self._cie2000_index()
            out = fine._query_cie2000_compiled(q, k, search)
            self.last_visited = fine.last_visited
            return out
        if flat and method == "cie2000":
            return self._query_cie2000_flat(q, k, kernel)
        if flat:  # (for CIEDE2000 the cheap bound first; the hue-aware one on the survivors below)
            lb = _box_bounds(q, self._lo, self._hi, self._cmax, method, hue=method != "cie2000")
            leaves = np.arange(lb.size)
        else:  # open the best group(s) first: enough leaves for a k-th best
            glb = _box_bounds(q, self._glo, self._ghi, self._gcmax, method)
            ng_first = min(self.n_groups, -(-first // g))
            gsel = (
                np.argpartition(glb, ng_first - 1)[:ng_first]
                if ng_first < self.n_groups
                else np.arange(self.n_groups)
            )
            leaves = (gsel[:, None] * g + np.arange(g)).ravel()
            lb = _box_bounds(q, self._lo[leaves], self._hi[leaves], self._cmax[leaves], method)
        first = min(first, lb.size)
        pick = np.argpartition(lb, first - 1)[:first] if first < lb.size else np.arange(lb.size)
        sel = leaves[pick]
        rows, s, per = self._evaluate(kernel, q, sel, math.inf, k, method)
        kth = np.partition(s, k - 1)[k - 1] if s.size >= k else math.inf
        if flat:
            rest = lb <= kth
            rest[pick] = False
            more, more_lb = leaves[rest], lb[rest]
            if method == "cie2000" and more.size:
                more_lb = _box_bounds(q, self._lo[more], self._hi[more], self._cmax[more], method)
                keep = more_lb <= kth
                more, more_lb = more[keep], more_lb[keep]
        else:
            gmore = np.flatnonzero(glb <= kth)
            cand = (gmore[:, None] * g + np.arange(g)).ravel()
            keep = ~np.isin(cand, sel)
            if method == "cie2000":  # cheap bound first, the hue-aware one on the survivors
                cand = cand[keep]
                keep = (
                    _box_bounds(q, self._lo[cand], self._hi[cand], self._cmax[cand], method, hue=False) <= kth
                )
            cand = cand[keep]
            clb = _box_bounds(q, self._lo[cand], self._hi[cand], self._cmax[cand], method)
            keep = clb <= kth
            more, more_lb = cand[keep], clb[keep]
        visited = sel.size
        while more.size:  # best-bounded leaves first: each batch tightens the k-th best for the rest
            if more.size > 2 * _BATCH_LEAVES:
                part = np.argpartition(more_lb, _BATCH_LEAVES)
                now, later = part[:_BATCH_LEAVES], part[_BATCH_LEAVES:]
            else:
                now, later = np.arange(more.size), np.empty(0, dtype=np.intp)
            visited += now.size
            rows2, s2, per2 = self._evaluate(kernel, q, more[now], float(kth), k, method)
            rows = np.concatenate([rows, rows2])
            s = np.concatenate([s, s2])
            per = np.concatenate([per, per2])
            if s.size >= k:
                kth = np.partition(s, k - 1)[k - 1]
            still = more_lb[later] <= kth
            more, more_lb = more[later][still], more_lb[later][still]
        if s.size > k:
            keep_k = s <= np.partition(s, k - 1)[k - 1]
            rows, s, per = rows[keep_k], s[keep_k], per[keep_k]
        top = np.lexsort((rows, s))[:k]
        self.last_visited = int(visited)
        return rows[top], s[top], per[top]

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
        lower2, upper2 = _pair_bounds_cie2000(
            qt[0], qt[1], qt[2], qt[3], cols[:, 0], cols[:, 1], cols[:, 2], cols[:, 3]
        )
        na = q.shape[0]
        lower = np.sqrt(lower2).reshape(-1, na).sum(-1) * _SAFETY - 1e-10
        upper = np.sqrt(upper2).reshape(-1, na).sum(-1) * (2.0 - _SAFETY) + 1e-10  # type: ignore[arg-type]
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
        if self._fine is None:
            self._fine = SnapIndex(self.lab, self.angles_deg, leaf_size=8, group=8)
        return self._fine

    def _query_cie2000_compiled(
        self, q: NDArray[np.float64], k: int, search: object
    ) -> tuple[NDArray[np.intp], NDArray, NDArray]:
        """Exact CIEDE2000 top-k: candidates from the compiled best-first walk (:func:`_best_first_cie2000`),
        then the exact kernel on them and the (sum, row) order of a brute-force scan."""
        rows, visited = search(  # type: ignore[operator]
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
        self.last_visited = int(visited)
        return rows[top], s[top], per[top]

    def _cheap_bounds(
        self, q: NDArray[np.float64], qt: NDArray[np.float64], leaves: NDArray[np.intp]
    ) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
        """Real paints of *leaves*: (rows, lower bound of the summed ΔE00), the bound of
        :func:`_box_bounds_cie2000_fast` for single points (boxes of one paint); *qt* is :meth:`_tile` of *q*."""
        cols = self._cols[leaves]
        ql = qt[0]
        dl = cols[:, 0] - ql
        x = np.abs(cols[:, 0] + (ql - 100.0))
        x *= 1.0 / _TABLE_STEP
        np.minimum(x, _WL.size - 1, out=x)
        xi = x.astype(np.intp)
        da = cols[:, 1] - qt[1]
        db = cols[:, 2] - qt[2]
        c = cols[:, 3] + qt[3]
        c *= 1.0 / _TABLE_STEP
        np.minimum(c, _WAB.size - 1, out=c)
        ci = c.astype(np.intp)
        dl *= dl
        da *= da
        db *= db
        da += db
        na = q.shape[0]
        lower = np.sqrt(dl * _WL[xi] + da * _WAB[ci]).reshape(-1, na).sum(-1) * _SAFETY - 1e-12
        rows = self._rows[leaves].ravel()
        real = rows < self.size
        if not real.all():
            rows, lower = rows[real], lower[real]
        return rows, lower

    def _query_cie2000_flat(
        self, q: NDArray[np.float64], k: int, kernel: object
    ) -> tuple[NDArray[np.intp], NDArray, NDArray]:
        """Exact CIEDE2000 top-k with one call of the exact kernel (libraries of a few thousand paints).

        The NumPy path (no numba):

        1. Box bound of every leaf (:func:`_box_bounds_cie2000_fast`).
        2. The :data:`_FIRST_LEAVES` best leaves: per-paint lower and upper bounds
           (:func:`_pair_bounds_cie2000`); u = k-th smallest upper bound ≥ S_k (the true k-th best sum),
           since k real paints have sums ≤ their upper bounds.
        3. Every other leaf whose bound is ≤ u: the table per-paint lower bound (:meth:`_cheap_bounds`);
           above :data:`_REFINE_ABOVE` candidates the sharp per-paint lower bound filters them again.
        4. The exact kernel on the paints whose lower bound is ≤ u, then (sum, row) order. A paint with
           S ≤ S_k has every lower bound ≤ S ≤ u and its leaf's bound ≤ S ≤ u, so it is among them: the
           top-k, ties included, is the brute-force one.
        """
        lb = _box_bounds_cie2000_fast(q, self._lo, self._hi, self._lo_l, self._hi_l, self._cmax)
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
            lower2, _ = _pair_bounds_cie2000(
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
            rows = rows[np.sqrt(lower2).sum(-1) * _SAFETY - 1e-10 <= u]
        n, na = rows.size, q.shape[0]
        pc = self._lab_t[:, rows].reshape(3, -1)
        qc = np.broadcast_to(q.T[:, None, :], (3, n, na)).reshape(3, -1)
        per = cie2000_columns(qc[0], qc[1], qc[2], pc[0], pc[1], pc[2]).reshape(n, na)
        s = per.sum(-1)
        top = np.lexsort((rows, s))[:k]
        self.last_visited = int(sel.size + more.size)
        return rows[top], s[top], per[top]

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
            plb = _point_bounds_cie2000(q, pts)
            if kth == math.inf:  # the best few by bound give a k-th best to filter the rest with
                m = 4 * k
                head = np.argpartition(plb, m - 1)[:m]
                per_h = kernel(q, pts[head])  # type: ignore[operator]
                s_h = per_h.sum(-1)
                kth = float(np.partition(s_h, k - 1)[k - 1])
                keep = plb <= kth
                keep[head] = False
                per_r = kernel(q, pts[keep])  # type: ignore[operator]
                per = np.concatenate([per_h, per_r])
                return np.concatenate([rows[head], rows[keep]]), per.sum(-1), per
            keep = plb <= kth
            rows, pts = rows[keep], pts[keep]
        per = kernel(q, pts)  # type: ignore[operator]
        return rows, per.sum(-1), per

    def snap(self, lab: ArrayLike, k: int = 5, method: str = "cie76") -> SnapResult:
        """Run :meth:`query` and wrap it with codes (when built from a library); no warnings."""
        rows, s, per = self.query(lab, k, method)
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
            tuple(tuple(float(v) for v in row) for row in q),
            stats={"leaves_visited": self.last_visited, "leaves": self.n_buckets},
        )


def brute_force(
    lib_lab: ArrayLike, lab: ArrayLike, k: int = 5, method: str = "cie76"
) -> tuple[NDArray[np.intp], NDArray, NDArray]:
    """Reference scan through :func:`station.model.difference.delta_e`: (rows, sums, per-angle), best first."""
    from station.model.difference import delta_e

    lib_lab = np.asarray(lib_lab, dtype=np.float64)
    per = delta_e(np.asarray(lab, dtype=np.float64)[None], lib_lab, method)
    s = per.sum(-1)
    top = np.lexsort((np.arange(s.size), s))[: min(k, s.size)]
    return top, s[top], per[top]


def snap_warnings(
    library: Library,
    result: SnapResult,
    far_threshold: float | None = None,
    hue_shift_threshold: float = HUE_SHIFT_THRESHOLD,
    travel_angle_threshold_deg: float = TRAVEL_ANGLE_THRESHOLD_DEG,
) -> tuple[str, ...]:
    """The two problems ColorSnap's view exposes (thesis Fig. 5.10), as sentences.

    1. *Far outside the library*: the best match's mean ΔE per angle exceeds *far_threshold*
       (default :data:`FAR_THRESHOLD` for the metric); says whether the design is more chromatic than
       every library paint of similar hue (the "too deep in saturation" case).
    2. *Travel not captured*: the design's a*b* travel (110° − 15°) points in a direction more than
       *travel_angle_threshold_deg* away from the match's, or their Hue Shift Indices (eq 5.3.3)
       differ by more than *hue_shift_threshold* (the "off-radial travel" case).
    """
    from station.model.indices import library_indices

    out: list[str] = []
    if not result.matches:
        return ()
    best = result.matches[0]
    threshold = FAR_THRESHOLD[result.method] if far_threshold is None else far_threshold
    design = np.asarray(result.design_lab)
    mean_de = best.sum_de / len(result.angles_deg)
    if mean_de > threshold:
        msg = (
            f"design lies far outside the library: nearest paint {best.code} differs by mean "
            f"{mean_de:.2f} {result.method} per angle (threshold {threshold:g})"
        )
        c_design = float(np.hypot(design[:, 1], design[:, 2]).max())
        std = library.angle_columns(result.angles_deg)
        c_lib = np.hypot(std[..., 1], std[..., 2]).max(1)
        h_design = math.degrees(math.atan2(design[0, 2], design[0, 1])) % 360
        h_lib = np.degrees(np.arctan2(std[:, 0, 2], std[:, 0, 1])) % 360
        near = np.abs((h_lib - h_design + 180) % 360 - 180) < 20
        if c_design > 10 and near.any() and c_design > float(c_lib[near].max()):
            msg += (
                f"; the design is more chromatic (C* {c_design:.1f}) than every library paint of its hue "
                f"(max C* {float(c_lib[near].max()):.1f})"
            )
        out.append(msg)
    try:
        i15, i110 = result.angles_deg.index(15.0), result.angles_deg.index(110.0)
        i45 = result.angles_deg.index(45.0)
    except ValueError:
        return tuple(out)
    match = library.angle_columns(result.angles_deg)[best.index]
    t_design = design[i110, 1:] - design[i15, 1:]
    t_match = match[i110, 1:] - match[i15, 1:]
    n_d, n_m = float(np.hypot(*t_design)), float(np.hypot(*t_match))
    if n_d > 3.0:
        cosang = float(t_design @ t_match) / (n_d * n_m) if n_m > 1e-9 else -1.0
        ang = math.degrees(math.acos(max(-1.0, min(1.0, cosang))))
        hsi_d = library_indices(design[i15], design[i45], design[i110]).hue_shift_index
        hsi_m = library_indices(match[i15], match[i45], match[i110]).hue_shift_index
        hsi_gap = abs(hsi_d - hsi_m) if hsi_d is not None and hsi_m is not None else 0.0
        if ang > travel_angle_threshold_deg or hsi_gap > hue_shift_threshold:
            out.append(
                f"the match {best.code} does not capture the design's travel direction: a*b* travel "
                f"15°→110° differs by {ang:.0f}° (threshold {travel_angle_threshold_deg:g}°)"
                + (f", Hue Shift Index differs by {hsi_gap:.1f}" if hsi_gap else "")
            )
    return tuple(out)


def color_snap(
    library: Library,
    lab: ArrayLike,
    k: int = 5,
    method: str = "cie76",
    index: SnapIndex | None = None,
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
    """
    index = index or SnapIndex(library)
    result = index.snap(lab, k, method)
    return SnapResult(
        result.matches,
        result.method,
        result.angles_deg,
        result.design_lab,
        snap_warnings(library, result),
        result.stats,
    )


def view_data(
    library: Library, result: SnapResult, max_cloud: int = 3000, seed: int = 0
) -> dict[str, object]:
    """Data of the 3D Lab-space view (thesis Figs 5.9–5.11): design, matches and a library cloud.

    Returns ``{"angles_deg", "design": [[L,a,b] per angle], "matches": [{"code", "lab"}],
    "cloud": {"lab": [[L,a,b]] at 45°, "codes": [...], "sampled": bool}, "synthetic": bool}``.
    """
    std = library.angle_columns(result.angles_deg)
    rng = np.random.default_rng(seed)
    n = len(library)
    rows = np.sort(rng.choice(n, size=max_cloud, replace=False)) if n > max_cloud else np.arange(n)
    i45 = result.angles_deg.index(45.0) if 45.0 in result.angles_deg else 0
    return {
        "angles_deg": list(result.angles_deg),
        "design": [list(r) for r in result.design_lab],
        "matches": [{"code": m.code, "lab": std[m.index].tolist()} for m in result.matches],
        "cloud": {
            "lab": std[rows, i45].tolist(),
            "codes": library.codes[rows].tolist(),
            "sampled": n > max_cloud,
        },
        "synthetic": library.synthetic,
    }
