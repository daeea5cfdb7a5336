"""Aspecular measurements → face/flop/travel/gloss (thesis §3.3.3–§3.3.4; docs/design.md erratum 5).

Three-angle sets (15/45/110 and 25/45/75) are solved in closed form: L passes exactly through the
three values wherever a monotone clamped quadratic does, and a*, b* are least-squares fits with the
shared θ_clamp (the thesis calls the mapping exact; it is exact for L only). Sets of four or more
angles are fitted by least squares over all parameters, θ_clamp included (variable projection: for a
given θ_clamp the model is linear in face and flop). The residual ΔE*ab per angle is always reported.

Model: X(θ) = flop + (face − flop) s(θ)², s(θ) = (θ_c − min(θ, θ_c)) / (θ_c − 15°).

Search for θ_clamp: the projected cost f(θ_c) = min over face, flop of Σ_θ Σ_c (X_c(θ) − Lab_c(θ))² is
evaluated on a fixed grid, and the grid's best point is refined inside its two neighbours by a
bracketed root search (Illinois regula falsi) on the exact slope
f'(θ_c) = 2 Σ_θ Σ_c r_c(θ) (face_c − flop_c) ∂s²/∂θ_c (the envelope theorem: face and flop are
optimal, so only the explicit dependence counts), down to the last bits of θ_c. The refined point is
kept only when it costs no more than the grid's best.

Constrained vertex: when the unconstrained fit puts face or flop outside the Lab bound
(:data:`station.model.domain.LAB_RANGES`, e.g. a flop L* below 0 from an extrapolated vertex), the
fit solves instead

    min over θ_c, face, flop of  Σ_θ Σ_c (X_c(θ) − Lab_c(θ))²   subject to  LAB_LO <= face, flop <= LAB_HI,

with θ_c in (15°, TRAVEL_MAX_DEG]. For a fixed θ_c this is a box-constrained linear least squares in
(face_c, flop_c) per channel, solved exactly (the interior optimum, else the best point on an edge of
the box); θ_c is searched as above (the envelope theorem holds for the box-constrained optimum too).
The residual per angle is reported and a warning says the constraint was active.

Every paint of a library is fitted at once by :func:`fit_fftg_batch` (the arrays carry one row per
paint; sums over the angles are written out term by term, so a paint's result does not depend on
which other paints share the batch); :func:`fit_fftg` is the same fit for one set of measurements.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.angles import validate_angle_set
from station.model.domain import LAB_HI, LAB_LO, check_gloss, check_lab, lab_accepted
from station.model.errors import FitError, ModelInputError
from station.model.representations import (
    DEFAULT_GLOSS_GU,
    FACE_ANGLE_DEG,
    TRAVEL_MAX_DEG,
    AspecularMeasurements,
    FaceFlopTravelGloss,
    shape_factor,
)
from station.model.travel_search import (
    TC_LOW as _TC_LOW,
)
from station.model.travel_search import (
    box_project as _box_project,
)
from station.model.travel_search import (
    constrained_grid as _constrained_grid,
)
from station.model.travel_search import (
    free_grid as _free_grid,
)
from station.model.travel_search import (
    free_grid_costs as _free_grid_costs,
)
from station.model.travel_search import (
    grid_costs as _grid_costs,
)
from station.model.travel_search import (
    project as _project,
)
from station.model.travel_search import (
    search_travel as _search_travel,
)
from station.model.travel_search import (
    three_angle_travel as _three_angle_travel,
)

#: Residual (ΔE*ab, per angle) under which a fit counts as exact.
EXACT_TOLERANCE_DE = 1e-6
#: Max ΔE*ab between any two angles under which a sample is reported as near-solid.
NEAR_SOLID_DE = 0.5

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class FitResult:
    """Result of fitting the face/flop/travel/gloss model to aspecular measurements.

    Attributes
    ----------
    design
        The fitted design (gloss from the measurements, or the default when not measured, in which case
        ``design.gloss_measured`` is False and a warning says so).
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


@dataclass(frozen=True, eq=False)
class FitBatch:
    """Fits of many paints measured at the same angles (:func:`fit_fftg_batch`), one row per paint.

    Attributes
    ----------
    angles_deg
        The measured aspecular angles, degrees.
    face, flop
        (N, 3) Lab; NaN in the rows of paints that could not be fitted (see *errors*).
    travel_deg
        (N,) θ_clamp in degrees; NaN for a solid (and for a paint that could not be fitted).
    gloss_gu
        (N,) gloss in GU (the default where not measured).
    residual_de
        (N, k) ΔE*ab between measured and modelled Lab per angle (NaN where not fitted).
    exact
        (N,) every residual below :data:`EXACT_TOLERANCE_DE`.
    method, warnings
        Per paint, as :class:`FitResult`.
    errors
        Per paint: None, or why it could not be fitted (the :class:`FitError` message).
    gloss_measured
        False when no gloss was given: *gloss_gu* then holds the default, and every design says so
        (:attr:`FaceFlopTravelGloss.gloss_measured`).
    """

    angles_deg: tuple[float, ...]
    face: F64
    flop: F64
    travel_deg: F64
    gloss_gu: F64
    residual_de: F64
    exact: NDArray[np.bool_]
    method: tuple[str, ...]
    warnings: tuple[tuple[str, ...], ...]
    errors: tuple[str | None, ...]
    gloss_measured: bool = True

    def __len__(self) -> int:
        return len(self.method)

    def result(self, i: int) -> FitResult:
        """The :class:`FitResult` of paint *i* (row order of the input).

        Raises
        ------
        FitError
            The paint could not be fitted (the message of :attr:`errors`).
        """
        error = self.errors[i]
        if error is not None:
            raise FitError(error)
        tc = float(self.travel_deg[i])
        face, flop = self.face[i], self.flop[i]
        design = FaceFlopTravelGloss(
            (float(face[0]), float(face[1]), float(face[2])),
            (float(flop[0]), float(flop[1]), float(flop[2])),
            None if np.isnan(tc) else tc,
            float(self.gloss_gu[i]),
            gloss_measured=self.gloss_measured,
        )
        return FitResult(
            design,
            tuple(float(r) for r in self.residual_de[i]),
            bool(self.exact[i]),
            self.method[i],
            self.warnings[i],
        )


# ------------------------------------------------------------------------------ the fit


def _validated(
    angles_deg: Sequence[float], lab: ArrayLike, gloss_gu: ArrayLike | None
) -> tuple[tuple[float, ...], F64, F64 | None]:
    angles = validate_angle_set(angles_deg)
    try:
        arr = np.asarray(lab, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelInputError("lab", "one L*, a*, b* triple per paint and angle", lab) from exc
    if arr.ndim != 3 or arr.shape[1:] != (len(angles), 3):
        raise ModelInputError("lab", f"shape (paints, {len(angles)}, 3): L*, a*, b* per angle", arr.shape)
    bad = ~(np.isfinite(arr) & (arr >= np.asarray(LAB_LO)) & (arr <= np.asarray(LAB_HI))).all(axis=-1)
    if bad.any():
        n, j = np.argwhere(bad)[0]
        check_lab(arr[n, j], f"lab[{n}][{j}]")  # raises, naming the channel and its range
    if gloss_gu is None:
        return angles, arr, None
    try:
        gloss = np.asarray(gloss_gu, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ModelInputError("gloss_gu", "one gloss value (GU) per paint", gloss_gu) from exc
    if gloss.size != arr.shape[0]:
        raise ModelInputError("gloss_gu", f"{arr.shape[0]} gloss values (one per paint)", gloss.size)
    for n, g in enumerate(gloss):
        check_gloss(float(g), f"gloss_gu[{n}]")
    return angles, arr, gloss


def fit_fftg_batch(
    angles_deg: Sequence[float], lab: ArrayLike, gloss_gu: ArrayLike | None = None
) -> FitBatch:
    """Fit face/flop/travel/gloss to many paints measured at the same aspecular angles (thesis §3.3.3).

    Parameters
    ----------
    angles_deg
        At least three aspecular angles in degrees, strictly increasing (shared by every paint).
    lab
        (N, k, 3): Lab per paint and angle, inside the Lab bound.
    gloss_gu
        (N,) gloss per paint in GU (60°), or None when not measured (the default is used, with a
        warning on every paint).

    Returns
    -------
    FitBatch
        Per paint: the fit :func:`fit_fftg` gives, or why there is none (:attr:`FitBatch.errors`).

    Raises
    ------
    ModelInputError
        Bad angles, a Lab or gloss value outside its range (the error names the paint and angle).
    FitError
        Fewer than three angles.
    """
    angles, y, gloss = _validated(angles_deg, lab, gloss_gu)
    return _fit(angles, y, gloss)


def _gloss_or_default(n: int, gloss: F64 | None, notes: list[list[str]]) -> tuple[F64, bool]:
    """The gloss per paint and whether it was measured; the default (with a note) when it was not."""
    if gloss is not None:
        return gloss, True
    for w in notes:
        w.append(f"gloss not measured: default {DEFAULT_GLOSS_GU:g} GU used")
    return np.full(n, DEFAULT_GLOSS_GU), False


def _solid_rows(y: F64, notes: list[list[str]]) -> NDArray[np.bool_]:
    """Rows whose Lab is identical at every angle (solids); near-solids get a note."""
    diff = y[:, :, None, :] - y[:, None, :, :]  # every pair of angles
    spread = np.sqrt(diff[..., 0] ** 2 + diff[..., 1] ** 2 + diff[..., 2] ** 2).max(axis=(1, 2), initial=0.0)
    solid: NDArray[np.bool_] = spread == 0.0
    for r in np.flatnonzero(~solid & (spread < NEAR_SOLID_DE)):
        notes[r].append(f"near-solid (max ΔE*ab between angles {spread[r]:.3g}): travel is poorly determined")
    return solid


def _initial_travel(
    ang: F64, theta: F64, y: F64, live: NDArray[np.bool_], method: list[str], notes: list[list[str]]
) -> F64:
    """θ_clamp per live row: closed form through three angles where it exists, else the grid search."""
    n, k = y.shape[0], ang.size
    tc = np.full(n, np.nan)
    if k == 3:
        tc = np.where(live, _three_angle_travel(ang, y[:, :, 0]), np.nan)
        for r in np.flatnonzero(live & np.isfinite(tc)):
            method[r] = "closed-form"
        flat_l = np.ptp(y[:, :, 0], axis=1) == 0.0
        for r in np.flatnonzero(live & np.isnan(tc)):
            notes[r].append(
                "L* identical at every angle: travel fitted from a*, b* alone"
                if flat_l[r]
                else "no monotone clamped quadratic passes through L*: least-squares fit, see residual"
            )
    search = np.flatnonzero(live & np.isnan(tc))
    if search.size:
        grid = _free_grid()
        ys = y[search]
        tc[search] = _search_travel(theta, ys, grid, _free_grid_costs(theta, ys, grid), _project)
    return tc


def _identifiable_travel(
    angles: tuple[float, ...],
    theta: F64,
    tc: F64,
    live: NDArray[np.bool_],
    notes: list[list[str]],
    errors: list[str | None],
) -> NDArray[np.bool_]:
    """Report unidentifiable travel at its upper end (in place); the live rows left after a low vertex."""
    n = tc.size
    distinct = np.unique(theta)  # the model sees the unsigned angle from specular
    if distinct.size > 1 and distinct[1] > FACE_ANGLE_DEG:
        upper = float(distinct[1])
        below = np.zeros(n, dtype=int)
        for d in distinct:
            below += d < tc
        for r in np.flatnonzero(live & (below < 2) & (upper > tc)):
            notes[r].append(
                f"travel not identifiable from angles {list(angles)}: any value in "
                f"({FACE_ANGLE_DEG:g}, {upper:g}] fits; the upper end is reported"
            )
            tc[r] = upper
    low_vertex = live & (tc - _TC_LOW < 1e-2)
    for r in np.flatnonzero(low_vertex):
        errors[r] = (
            f"travel_deg: the best fit puts the vertex at or below {FACE_ANGLE_DEG:g}° "
            f"(accepted {FACE_ANGLE_DEG:g} < travel_deg <= {TRAVEL_MAX_DEG:g})"
        )
    out: NDArray[np.bool_] = live & ~low_vertex
    return out


def _outside_bound(x: F64) -> NDArray[np.bool_]:
    """Rows of Lab outside the domain's Lab bound."""
    lo, hi = np.asarray(LAB_LO), np.asarray(LAB_HI)
    out: NDArray[np.bool_] = np.logical_not(np.all((x >= lo) & (x <= hi), axis=-1))
    return out


def _face_flop(
    theta: F64,
    y: F64,
    tc: F64,
    solid: NDArray[np.bool_],
    live: NDArray[np.bool_],
    method: list[str],
    notes: list[list[str]],
) -> tuple[F64, F64, F64, NDArray[np.bool_]]:
    """Face, flop and model Lab per row (in place on *tc*), constrained to the Lab bound where needed.

    Returns face (N, 3), flop (N, 3), model (N, k, 3) and the rows still outside the bound.
    """
    n, k = y.shape[0], theta.size
    face, flop = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
    model = np.full((n, k, 3), np.nan)
    face[solid] = flop[solid] = y[solid, 0]
    model[solid] = y[solid]
    rows = np.flatnonzero(live)
    if rows.size:
        face[rows], flop[rows], model[rows] = _project(shape_factor(theta, tc[rows, None]), y[rows])
    out_of_bound = live & (_outside_bound(face) | _outside_bound(flop))
    bounded = np.flatnonzero(out_of_bound)
    if bounded.size:
        tc_free = tc[bounded].copy()
        grid, yb = _constrained_grid(), y[bounded]
        costs = _grid_costs(theta, yb, grid, _box_project)
        tc[bounded] = _search_travel(theta, yb, grid, costs, _box_project)
        face[bounded], flop[bounded], model[bounded] = _box_project(
            shape_factor(theta, tc[bounded, None]), y[bounded]
        )
        miss = model[bounded] - y[bounded]
        worst = np.sqrt(miss[..., 0] ** 2 + miss[..., 1] ** 2 + miss[..., 2] ** 2).max(axis=1)
        for r, t_free, t, wst in zip(bounded, tc_free, tc[bounded], worst, strict=True):
            method[r] = "constrained"
            notes[r].append(
                f"unconstrained vertex at {t_free:.3g}° puts face or flop outside {lab_accepted('L')}, "
                f"{lab_accepted('a')}, {lab_accepted('b')}: constrained fit (travel {t:.3g}°), "
                f"max residual ΔE*ab {wst:.3g}"
            )
    for r in np.flatnonzero(live & (face[:, 0] < flop[:, 0])):
        notes[r].append("flop brighter than face (L*): retroreflective or inverted travel")
    if bounded.size:
        out_of_bound[bounded] = _outside_bound(face[bounded]) | _outside_bound(flop[bounded])
    return face, flop, model, out_of_bound


def _fit(angles: tuple[float, ...], y: F64, gloss: F64 | None) -> FitBatch:
    """The fit of :func:`fit_fftg_batch` on validated input (module notes)."""
    n, k = y.shape[0], len(angles)
    if k < 3:
        raise FitError(f"angles_deg: need at least 3 aspecular angles to fit the model, got {k}")
    ang = np.asarray(angles, dtype=float)
    theta = np.abs(ang)
    notes: list[list[str]] = [[] for _ in range(n)]
    errors: list[str | None] = [None] * n
    gloss_gu, measured = _gloss_or_default(n, gloss, notes)
    solid = _solid_rows(y, notes)
    method = ["closed-form" if s else "least-squares" for s in solid]
    tc = _initial_travel(ang, theta, y, ~solid, method, notes)
    live = _identifiable_travel(angles, theta, tc, ~solid, notes, errors)
    face, flop, model, out_of_bound = _face_flop(theta, y, tc, solid, live, method, notes)
    for r in np.flatnonzero(out_of_bound):
        errors[r] = (
            f"lab: the fitted face or flop falls outside {lab_accepted('L')}, {lab_accepted('a')}, "
            f"{lab_accepted('b')}; "
            f"face={np.round(face[r], 3).tolist()}, flop={np.round(flop[r], 3).tolist()}"
        )
    miss = model - y
    residual = np.sqrt(miss[..., 0] ** 2 + miss[..., 1] ** 2 + miss[..., 2] ** 2)
    exact = np.all(residual < EXACT_TOLERANCE_DE, axis=1)  # NaN (not fitted) compares False
    for r in np.flatnonzero(solid):
        notes[r].append("solid")
    failed = np.array([e is not None for e in errors], dtype=bool)
    face[failed] = flop[failed] = np.nan
    tc[failed | solid] = np.nan
    residual[failed] = np.nan
    exact &= ~failed
    return FitBatch(
        angles,
        face,
        flop,
        tc,
        gloss_gu,
        residual,
        exact,
        tuple(method),
        tuple(tuple(w) for w in notes),
        tuple(errors),
        measured,
    )


def fit_fftg(measurements: AspecularMeasurements) -> FitResult:
    """Fit face/flop/travel/gloss to aspecular measurements (thesis §3.3.3, docs/design.md erratum 5).

    The one-paint case of :func:`fit_fftg_batch` (the same rule, the same numbers).

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
    gloss = None if measurements.gloss_gu is None else np.array([measurements.gloss_gu], dtype=float)
    lab = np.asarray(measurements.lab, dtype=float)[None]  # validated by AspecularMeasurements
    return _fit(measurements.angles_deg, lab, gloss).result(0)
