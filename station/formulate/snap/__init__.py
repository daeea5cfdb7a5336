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
* DIN 6175-2 (ΔE_eff = σ ΔE_ab,w + (1 − σ) ΔE_CH,w, weights on the geometric means L̄, C̄ of design and
  paint at each angle α): ΔE_eff ≥ min(ΔE_ab,w, ΔE_CH,w) (σ ∈ (0, 1)), and both forms are
  ≥ √((d_L/S_L,max)² + d_ab²/W²) with ΔC*² + ΔH*² = Δa*² + Δb*², S_L,max at the box's largest L̄,
  W = max(0.7, S_C,max, S_H,max) at the largest C̄ and smallest L̄ (S_C, S_H rise with C̄ and fall with
  L̄; :func:`.bounds._din6175_box`).
* CIEDE2000: ΔE00² ≥ (ΔL'/S_L)² + (1 − |R_T|/2) (ΔC'² + ΔH'²)/S_C² (|xy| ≤ (x²+y²)/2, S_H < S_C since
  T ≤ 1.93), ΔC'² + ΔH'² = Δa'² + Δb² ≥ Δa² + Δb² (a' = (1+G)a, one G per pair), with S_L, S_C and
  R_C replaced by their largest values over the box: S_L is increasing in |L̄ − 50|, C̄' ≤ (1+G(C̄))C̄
  is increasing in C̄ (checked numerically: slope ≥ 0.52 on 0–1000) and |R_T| ≤ R_C(C̄'_max)·sin 2Δθ_max,
  where Δθ_max comes from the arc of hues the pair's mean hue can take (:func:`.bounds.hue_geometry`; the
  global sin 60° where the box holds the neutral axis); the part of the a*b* distance that must be a hue
  difference (the gap between the hue arcs) is weighted by 1/S_H,max instead of 1/S_C,max. Per paint, a trigonometry-free bound
  (:func:`.bounds.point_bounds_cie2000`) filters the gathered paints before the exact formula runs.

Buckets are visited in order of their bound; the search stops when the next bound exceeds the k-th
best exact S found so far. Every paint whose S could tie or beat the k-th is evaluated exactly, so
the top-k equals brute force (tests/formulate/test_snap.py proves it with hypothesis).

CIEDE2000 (:meth:`.index.SnapIndex._query_cie2000_compiled`): a numba-compiled best-first walk
(:func:`.kernel.best_first_cie2000`) bounds every visited paint from below and above
(:func:`.bounds.point_bounds_cie2000`), keeps u = the k-th smallest upper bound, stops at the first box whose
bound exceeds u, and returns the paints whose lower bound is ≤ u; the exact kernel runs once, on those
(:func:`station.formulate.de_kernels.cie2000_columns`). Without numba, :meth:`.index.SnapIndex._query_cie2000_flat`
(NumPy) does the same with table bounds. tests/formulate/test_snap_cie2000.py checks the bounds and both
paths against brute force.

Modules: :mod:`.results` (matches, per-query statistics, Fig. 5.10 warnings), :mod:`.validation` (the
accepted design Lab), :mod:`.bounds` (the lower and upper bounds above), :mod:`.kernel` (the compiled
CIEDE2000 walk), :mod:`.index` (the index, the search, :func:`color_snap`, the brute-force reference),
:mod:`.view` (3D view data). Every query's statistics travel with its result (``SnapResult.stats``,
:meth:`.index.SnapIndex.search`); the index holds no per-query state and no switch: the NumPy CIEDE2000
path is chosen per call (``use_numba=False``).
"""

from __future__ import annotations

from station.formulate.snap.bounds import METHODS
from station.formulate.snap.index import SnapHits, SnapIndex, brute_force, color_snap, type_rows
from station.formulate.snap.results import (
    FAR_THRESHOLD,
    HUE_SHIFT_THRESHOLD,
    TRAVEL_ANGLE_THRESHOLD_DEG,
    SnapMatch,
    SnapResult,
    SnapStats,
    snap_warnings,
)
from station.formulate.snap.validation import LAB_QUERY_RANGE, validate_design_lab
from station.formulate.snap.view import view_data

__all__ = [
    "FAR_THRESHOLD",
    "HUE_SHIFT_THRESHOLD",
    "LAB_QUERY_RANGE",
    "METHODS",
    "TRAVEL_ANGLE_THRESHOLD_DEG",
    "SnapHits",
    "SnapIndex",
    "SnapMatch",
    "SnapResult",
    "SnapStats",
    "brute_force",
    "color_snap",
    "snap_warnings",
    "type_rows",
    "validate_design_lab",
    "view_data",
]
