"""Aspecular measurements → face/flop/travel/gloss (thesis §3.3.3–§3.3.4; docs/design.md erratum 5).

Three-angle sets (15/45/110 and 25/45/75) are solved in closed form: L passes exactly through the
three values wherever a monotone clamped quadratic does, and a*, b* are least-squares fits with the
shared θ_clamp (the thesis calls the mapping exact; it is exact for L only). Sets of four or more
angles are fitted by least squares over all parameters, θ_clamp included (variable projection: for a
given θ_clamp the model is linear in face and flop). The residual ΔE*ab per angle is always reported.

Model: X(θ) = flop + (face − flop) s(θ)², s(θ) = (θ_c − min(θ, θ_c)) / (θ_c − 15°).

Constrained vertex: when the unconstrained fit puts face or flop outside the Lab bound
(:data:`station.model.domain.LAB_RANGES`, e.g. a flop L* below 0 from an extrapolated vertex), the
fit solves instead

    min over θ_c, face, flop of  Σ_θ Σ_c (X_c(θ) − Lab_c(θ))²   subject to  LAB_LO <= face, flop <= LAB_HI,

with θ_c in (15°, TRAVEL_MAX_DEG]. For a fixed θ_c this is a box-constrained linear least squares in
(face_c, flop_c) per channel, solved exactly (the interior optimum, else the best point on an edge of
the box); θ_c is found on a grid and refined with a bounded scalar search. The residual per angle is
reported and a warning says the constraint was active.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares, minimize_scalar

from station.model.domain import LAB_HI, LAB_LO, lab_accepted, lab_within
from station.model.errors import FitError
from station.model.representations import (
    DEFAULT_GLOSS_GU,
    FACE_ANGLE_DEG,
    TRAVEL_MAX_DEG,
    AspecularMeasurements,
    FaceFlopTravelGloss,
    shape_factor,
)

#: Residual (ΔE*ab, per angle) under which a fit counts as exact.
EXACT_TOLERANCE_DE = 1e-6
#: Lower end of the θ_clamp search: just above the face angle (a vertex at or below 15° is refused).
_TC_LOW = FACE_ANGLE_DEG + 1e-3
#: Max ΔE*ab between any two angles under which a sample is reported as near-solid.
NEAR_SOLID_DE = 0.5


@dataclass(frozen=True)
class FitResult:
    """Result of fitting the face/flop/travel/gloss model to aspecular measurements.

    Attributes
    ----------
    design
        The fitted design (gloss from the measurements, or the default when not measured).
    residual_de
        ΔE*ab between measured and modelled Lab, per measured angle.
    exact
        True when every residual is below :data:`EXACT_TOLERANCE_DE`.
    method
        ``"closed-form"`` (3 angles, L exact), ``"least-squares"``, or ``"constrained"`` (face and
        flop held inside the Lab bound; see the module notes).
    warnings
        Human-readable notes: gloss defaulted, flop brighter than face, travel not identifiable, …
    """

    design: FaceFlopTravelGloss
    residual_de: tuple[float, ...]
    exact: bool
    method: str
    warnings: tuple[str, ...] = ()


def _linear_fit(u: NDArray[np.float64], lab: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
    """For fixed s² = u per angle, least-squares face and flop per channel; return (face, flop, model)."""
    a = np.stack([u, 1.0 - u], axis=1)  # X = face·u + flop·(1 − u)
    coef, *_ = np.linalg.lstsq(a, lab, rcond=None)
    return coef[0], coef[1], a @ coef


def _solve_for_travel(angles: NDArray, lab: NDArray, tc: float) -> tuple[NDArray, NDArray, NDArray]:
    return _linear_fit(shape_factor(angles, tc), lab)


def _three_angle_travel(angles: NDArray, lum: NDArray) -> float | None:
    """θ_clamp that makes L pass exactly through three values (closed form), or None.

    Case A, θ_c >= θ3: the unclamped parabola through the three points has its vertex at θ_c (eq 3.3.4).
    Case B, θ2 < θ_c < θ3: flop = L3 and (L2 − flop)/(L1 − flop) = ((θ_c − θ2)/(θ_c − θ1))².
    """
    t1, t2, t3 = angles
    l1, l2, l3 = lum
    vander = np.vander(angles, 3)
    xa, xb, _ = np.linalg.solve(vander, lum)
    if xa != 0.0:
        vertex = -xb / (2.0 * xa)
        if t3 <= vertex <= TRAVEL_MAX_DEG and vertex > FACE_ANGLE_DEG:
            return float(vertex)
    d1, d2 = l1 - l3, l2 - l3
    if d1 != 0.0:
        rho = d2 / d1
        if 0.0 < rho < 1.0:
            r = np.sqrt(rho)
            tc = (t2 - t1 * r) / (1.0 - r)
            if t2 < tc < t3 and tc > FACE_ANGLE_DEG:
                return float(tc)
    return None


def _least_squares_travel(angles: NDArray, lab: NDArray) -> float:
    """θ_clamp minimising the summed squared residual of all channels (variable projection)."""
    grid = np.concatenate([np.linspace(_TC_LOW, 30.0, 60), np.arange(30.0, TRAVEL_MAX_DEG + 1e-9, 0.5)])
    cost = np.array([np.sum((_solve_for_travel(angles, lab, tc)[2] - lab) ** 2) for tc in grid])
    tc0 = float(grid[int(np.argmin(cost))])

    def residual(p: NDArray) -> NDArray:
        return (_solve_for_travel(angles, lab, float(p[0]))[2] - lab).ravel()

    sol = least_squares(
        residual, [tc0], bounds=([_TC_LOW], [TRAVEL_MAX_DEG]), xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    tc = float(sol.x[0])
    if np.sum(residual(sol.x) ** 2) > cost.min():
        tc = tc0
    return tc


def _box_lstsq(a: NDArray[np.float64], y: NDArray[np.float64], lo: float, hi: float) -> NDArray:
    """Exact minimiser of |a·x − y|² over lo <= x_0, x_1 <= hi for a (n, 2) design matrix.

    The problem is a convex quadratic in two variables: the optimum is the unconstrained solution when
    it lies in the box, otherwise on one of the four edges, where it is the clipped 1-D minimiser.
    """
    x, *_ = np.linalg.lstsq(a, y, rcond=None)
    if np.all((x >= lo) & (x <= hi)):
        return np.asarray(x, dtype=float)
    best, best_cost = np.array([lo, lo]), np.inf
    for j in (0, 1):
        k = 1 - j
        col_k = a[:, k]
        norm = float(col_k @ col_k)
        for bound in (lo, hi):
            r = y - a[:, j] * bound
            xk = float(np.clip((col_k @ r) / norm, lo, hi)) if norm > 0.0 else lo
            cand = np.empty(2)
            cand[j], cand[k] = bound, xk
            cost = float(np.sum((a @ cand - y) ** 2))
            if cost < best_cost:
                best, best_cost = cand, cost
    return best


def _constrained_solve(angles: NDArray, lab: NDArray, tc: float) -> tuple[NDArray, NDArray, NDArray]:
    """For fixed θ_clamp, face and flop per channel inside the Lab bound; return (face, flop, model)."""
    u = shape_factor(angles, tc)
    a = np.stack([u, 1.0 - u], axis=1)
    coef = np.stack(
        [_box_lstsq(a, lab[:, c], LAB_LO[c], LAB_HI[c]) for c in range(3)], axis=1
    )  # (2, 3): rows face, flop
    return coef[0], coef[1], a @ coef


def _constrained_travel(angles: NDArray, lab: NDArray) -> float:
    """θ_clamp minimising the summed squared residual with face and flop inside the Lab bound."""
    low = _TC_LOW + 2e-2  # stay clear of the refused vertex at the face angle
    grid = np.concatenate([np.linspace(low, 30.0, 80), np.arange(30.0, TRAVEL_MAX_DEG + 1e-9, 0.25)])

    def cost(tc: float) -> float:
        return float(np.sum((_constrained_solve(angles, lab, tc)[2] - lab) ** 2))

    costs = np.array([cost(float(tc)) for tc in grid])
    i = int(np.argmin(costs))
    lo, hi = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, grid.size - 1)])
    sol = minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-10})
    tc = float(sol.x)
    return tc if cost(tc) <= costs[i] else float(grid[i])


def fit_fftg(measurements: AspecularMeasurements) -> FitResult:
    """Fit face/flop/travel/gloss to aspecular measurements (thesis §3.3.3, docs/design.md erratum 5).

    Parameters
    ----------
    measurements
        At least three aspecular angles with Lab each, plus an optional gloss (GU).

    Returns
    -------
    FitResult
        The design, ΔE*ab residual per angle, whether the fit is exact, and warnings.

    Raises
    ------
    FitError
        Fewer than three angles, or a best-fitting vertex at or below 15° (outside the model).

    Notes
    -----
    Defined answers for degenerate input:

    * identical Lab at every angle → a solid (``travel_deg = None``);
    * L monotone through three angles → L exact (closed form), a*, b* least squares;
    * flop brighter than face (retroreflective) → fitted, with a warning;
    * non-monotone L → least squares over θ_clamp, with the residual and a warning;
    * fewer than two angles below θ_clamp → θ_clamp is not identifiable: every value between the
      face angle and the second measured angle fits equally; the upper end is reported, with a warning;
    * unconstrained face or flop outside the Lab bound (a vertex extrapolated beyond the measured
      range) → the constrained fit of the module notes, with its residual and a warning.
    """
    angles = np.asarray(measurements.angles_deg, dtype=float)
    lab = np.asarray(measurements.lab, dtype=float)
    warnings: list[str] = []
    if angles.size < 3:
        raise FitError(f"angles_deg: need at least 3 aspecular angles to fit the model, got {angles.size}")
    gloss = measurements.gloss_gu
    if gloss is None:
        gloss = DEFAULT_GLOSS_GU
        warnings.append(f"gloss not measured: default {DEFAULT_GLOSS_GU:g} GU used")

    spread = np.max(np.linalg.norm(lab[:, None, :] - lab[None, :, :], axis=-1))
    if spread == 0.0:
        design = FaceFlopTravelGloss(tuple(lab[0]), tuple(lab[0]), None, gloss)
        return FitResult(design, tuple(0.0 for _ in angles), True, "closed-form", tuple([*warnings, "solid"]))
    if spread < NEAR_SOLID_DE:
        warnings.append(f"near-solid (max ΔE*ab between angles {spread:.3g}): travel is poorly determined")

    method = "least-squares"
    tc: float | None = None
    if angles.size == 3:
        tc = _three_angle_travel(angles, lab[:, 0])
        if tc is not None:
            method = "closed-form"
        elif np.ptp(lab[:, 0]) == 0.0:
            warnings.append("L* identical at every angle: travel fitted from a*, b* alone")
        else:
            warnings.append(
                "no monotone clamped quadratic passes through L*: least-squares fit, see residual"
            )
    if tc is None:
        tc = _least_squares_travel(angles, lab)
    distinct = np.unique(np.abs(angles))  # the model sees the unsigned angle from specular
    below = int(np.sum(distinct < tc))
    if below < 2:
        upper = float(distinct[1]) if distinct.size > 1 and distinct[1] > FACE_ANGLE_DEG else tc
        if upper > tc:
            warnings.append(
                f"travel not identifiable from angles {angles.tolist()}: any value in "
                f"({FACE_ANGLE_DEG:g}, {upper:g}] fits; the upper end is reported"
            )
            tc = upper
    if tc - _TC_LOW < 1e-2:
        raise FitError(
            f"travel_deg: the best fit puts the vertex at or below {FACE_ANGLE_DEG:g}° "
            f"(accepted {FACE_ANGLE_DEG:g} < travel_deg <= {TRAVEL_MAX_DEG:g})"
        )
    face, flop, model = _solve_for_travel(angles, lab, tc)
    if not lab_within(np.stack([face, flop])) and lab_within(lab):
        tc_free = tc
        tc = _constrained_travel(angles, lab)
        face, flop, model = _constrained_solve(angles, lab, tc)
        method = "constrained"
        worst = float(np.max(np.linalg.norm(model - lab, axis=1)))
        warnings.append(
            f"unconstrained vertex at {tc_free:.3g}° puts face or flop outside {lab_accepted('L')}, "
            f"{lab_accepted('a')}, {lab_accepted('b')}: constrained fit (travel {tc:.3g}°), "
            f"max residual ΔE*ab {worst:.3g}"
        )
    if face[0] < flop[0]:
        warnings.append("flop brighter than face (L*): retroreflective or inverted travel")
    residual = np.linalg.norm(model - lab, axis=1)
    if not lab_within(np.stack([face, flop])):
        raise FitError(
            f"lab: the fitted face or flop falls outside {lab_accepted('L')}, {lab_accepted('a')}, "
            f"{lab_accepted('b')}; "
            f"face={np.round(face, 3).tolist()}, flop={np.round(flop, 3).tolist()}"
        )
    design = FaceFlopTravelGloss(tuple(face), tuple(flop), tc, gloss)
    exact = bool(np.all(residual < EXACT_TOLERANCE_DE))
    return FitResult(design, tuple(float(r) for r in residual), exact, method, tuple(warnings))
