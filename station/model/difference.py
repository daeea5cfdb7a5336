"""Colour differences per aspecular angle and aggregated over an angle set (docs/design.md §3).

Methods (dispatched from :data:`DELTA_E_METHODS`):

=========  ==========================================================================================
cie76      ΔE*ab, CIE 1976 (colour-science)
cie94      CIE 1994, graphic-arts weights (colour-science)
cie2000    CIEDE2000 (colour-science); parametric k_L:k_C (the "l:c" of tolerance sets) through
           :func:`delta_e_cie2000_lc`
din6175    DIN 6175-2 effect-paint difference ΔE_eff, per aspecular angle — :func:`delta_e_din6175`;
           needs the aspecular angles
audi2000   a slot: refuses with :class:`FormulaUnavailableError` until its coefficients are supplied
=========  ==========================================================================================

The first argument of every function is the reference (standard, design), the second the sample.

DIN 6175-2 source
-----------------
The formula is the one published in a public implementation of DIN 6175-2 (Fortran subroutines
``SLCHAB`` and ``CALDEEFF``, K. Unterforsthuber, 2004–2021, commented "mdE und maxdE nach DIN6175-2"),
the only complete statement of the formula found. The text of DIN 6175-2:2001 itself was not
available, so the coefficients below **await a check against the standard's text**; note also that
DIN 6175:2019 merged parts 1 and 2. Per pair, at aspecular angle α (degrees, taken as |α|), with
L̄ = √(L*_1 L*_2) and C̄ = √(C*_1 C*_2) the geometric means of standard and sample:

    S_L = 0.15 √L̄ + 31.5/α
    S_C = max(0.7, 0.48 √C̄ − 0.35 √L̄ + 42/α)
    S_H = max(0.7, 0.14 √C̄ − 0.20 √L̄ + 21/α + 0.7)
    S_a = S_b = 0.7
    ΔE_ab,w = √((ΔL*/(g_L S_L))² + (Δa*/(g_a S_a))² + (Δb*/(g_b S_b))²)
    ΔE_CH,w = √((ΔL*/(g_L S_L))² + (ΔC*/(g_C S_C))² + (ΔH*/(g_H S_H))²)
    C₀ = 10 + 8/(1 + e^(27 − L̄)),  σ = 1/(1 + e^(C̄ − C₀))
    ΔE_eff = σ ΔE_ab,w + (1 − σ) ΔE_CH,w

so near-achromatic pairs (C̄ ≪ C₀, σ → 1) are judged in the a*b* form and chromatic ones (σ → 0) in the
C*H* form; every weight falls with α, so the far-from-specular angles are judged more strictly.
mdE is the mean of ΔE_eff over the angles, maxdE the largest with its angle (:func:`din6175_summary`).
The parametric factors g default to 1 (:class:`DinFactors`). One guard of the Fortran is left out: it
blends only when both forms exceed 1e-4, otherwise it returns the larger-than-1e-4 form alone (or 0
when neither is). That changes ΔE_eff only where one form is below 1e-4, far under any tolerance; here
the blend is evaluated everywhere, which keeps ΔE_eff continuous. (Its other guard, a weight below
1e-4, cannot occur with the 0.7 floors and S_L > 0.17.)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.cie2000 import cie2000_columns
from station.model.domain import ANGLE_MAX_DEG, DELTA_E_COMPUTED
from station.model.errors import ModelInputError

Aggregate = Literal["mean", "max", "rms", "sum"]

#: Coefficients of DIN 6175-2 as published in the public implementation (module docstring): the
#: weighting functions S_L, S_C, S_H, the constant S_a = S_b, and the blend's C₀(L̄). Read-only.
DIN6175_COEFFICIENTS: Mapping[str, float] = MappingProxyType(
    {
        "sl_sqrt_l": 0.15,
        "sl_alpha": 31.5,
        "sc_sqrt_c": 0.48,
        "sc_sqrt_l": 0.35,
        "sc_alpha": 42.0,
        "sh_sqrt_c": 0.14,
        "sh_sqrt_l": 0.20,
        "sh_alpha": 21.0,
        "sh_offset": 0.7,
        "s_floor": 0.7,
        "s_ab": 0.7,
        "c0_base": 10.0,
        "c0_step": 8.0,
        "c0_l_mid": 27.0,
    }
)


class FormulaUnavailableError(ModelInputError):
    """A colour-difference formula that has a name here but whose coefficients are not supplied."""


@dataclass(frozen=True)
class DinFactors:
    """Parametric factors g of DIN 6175-2 (dimensionless, each finite and > 0; default 1).

    A factor divides its weight: ΔL*/(g_L S_L), ΔC*/(g_C S_C), ΔH*/(g_H S_H), Δa*/(g_a S_a), Δb*/(g_b S_b).
    """

    g_l: float = 1.0
    g_c: float = 1.0
    g_h: float = 1.0
    g_a: float = 1.0
    g_b: float = 1.0

    def __post_init__(self) -> None:
        for name in ("g_l", "g_c", "g_h", "g_a", "g_b"):
            v = getattr(self, name)
            ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0
            if not ok:
                raise ModelInputError(f"din6175.{name}", "a finite number > 0", v)
            object.__setattr__(self, name, float(v))


DIN_DEFAULT_FACTORS = DinFactors()


@dataclass(frozen=True)
class Din6175Terms:
    """Every intermediate of :func:`din6175_terms`, arrays of the pair shape (…) (module docstring's formula).

    Attributes
    ----------
    l_mean, c_mean
        L̄ = √(L*₁L*₂) and C̄ = √(C*₁C*₂), the geometric means of the pair (CIELAB units).
    s_l, s_c, s_h
        The weighting functions S_L, S_C, S_H at the pair's aspecular angle (CIELAB units: ΔL*, ΔC*, ΔH*
        are divided by them, with the parametric factors g).
    sigma
        σ = 1/(1 + e^(C̄ − C₀)) in (0, 1): the share of the a*b* form in ΔE_eff.
    de_ab_w, de_ch_w, de_eff
        ΔE_ab,w (a*b* form), ΔE_CH,w (C*H* form) and ΔE_eff = σ ΔE_ab,w + (1 − σ) ΔE_CH,w.
    """

    l_mean: NDArray[np.float64]
    c_mean: NDArray[np.float64]
    s_l: NDArray[np.float64]
    s_c: NDArray[np.float64]
    s_h: NDArray[np.float64]
    sigma: NDArray[np.float64]
    de_ab_w: NDArray[np.float64]
    de_ch_w: NDArray[np.float64]
    de_eff: NDArray[np.float64]


@dataclass(frozen=True)
class Din6175Summary:
    """DIN 6175-2 aggregates over an angle set: mdE (mean ΔE_eff), maxdE and its aspecular angle (°)."""

    per_angle: tuple[float, ...]
    angles_deg: tuple[float, ...]
    mde: float
    maxde: float
    maxde_angle_deg: float


def _as_lab_pair(lab_ref: ArrayLike, lab_sample: ArrayLike) -> tuple[NDArray, NDArray]:
    a = np.asarray(lab_ref, dtype=float)
    b = np.asarray(lab_sample, dtype=float)
    if a.shape[-1:] != (3,) or b.shape[-1:] != (3,):
        raise ModelInputError("lab", "arrays of shape (..., 3)", (a.shape, b.shape))
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ModelInputError("lab", "finite L*, a*, b* values", "non-finite values")
    a, b = np.broadcast_arrays(a, b)
    return a, b


def din6175_alpha(aspecular_deg: ArrayLike | None, shape: tuple[int, ...]) -> NDArray[np.float64]:
    """|α| broadcast to the pair shape; raises :class:`ModelInputError` naming ``aspecular_deg``.

    Accepted: finite, 0 < |α| <= ANGLE_MAX_DEG degrees (the weights hold 1/α), broadcastable to *shape*.
    """
    accepted = f"aspecular angles in degrees, 0 < |angle| <= {ANGLE_MAX_DEG:g}, one per Lab pair"
    if aspecular_deg is None:
        raise ModelInputError("aspecular_deg", accepted + " (din6175 weights depend on the angle)", None)
    try:
        alpha = np.abs(np.asarray(aspecular_deg, dtype=float))
        out = np.broadcast_to(alpha, shape)
    except (TypeError, ValueError) as exc:
        raise ModelInputError("aspecular_deg", accepted, aspecular_deg) from exc
    if not np.all(np.isfinite(out)) or np.any(out <= 0) or np.any(out > ANGLE_MAX_DEG):
        raise ModelInputError("aspecular_deg", accepted, np.asarray(aspecular_deg).tolist())
    return np.asarray(out, dtype=np.float64)


def din6175_unchecked(
    ref: NDArray[np.float64], smp: NDArray[np.float64], alpha: NDArray[np.float64], g: DinFactors
) -> Din6175Terms:
    """The DIN 6175-2 arithmetic without input checks (ColorSnap's kernel calls it directly)."""
    k = DIN6175_COEFFICIENTS
    l_1, a_1, b_1 = ref[..., 0], ref[..., 1], ref[..., 2]
    l_2, a_2, b_2 = smp[..., 0], smp[..., 1], smp[..., 2]
    c_1 = np.hypot(a_1, b_1)
    c_2 = np.hypot(a_2, b_2)
    d_l = l_2 - l_1
    d_a = a_2 - a_1
    d_b = b_2 - b_1
    d_c = c_2 - c_1
    d_h2 = np.maximum(d_a * d_a + d_b * d_b - d_c * d_c, 0.0)  # ΔH*² = Δa*² + Δb*² − ΔC*²
    l_m = np.sqrt(np.abs(l_1 * l_2))
    c_m = np.sqrt(c_1 * c_2)
    sq_l = np.sqrt(l_m)
    sq_c = np.sqrt(c_m)
    s_l = k["sl_sqrt_l"] * sq_l + k["sl_alpha"] / alpha
    s_c = np.maximum(k["s_floor"], k["sc_sqrt_c"] * sq_c - k["sc_sqrt_l"] * sq_l + k["sc_alpha"] / alpha)
    s_h = np.maximum(
        k["s_floor"], k["sh_sqrt_c"] * sq_c - k["sh_sqrt_l"] * sq_l + k["sh_alpha"] / alpha + k["sh_offset"]
    )
    t_l = d_l / (g.g_l * s_l)
    t_l2 = t_l * t_l
    t_a = d_a / (g.g_a * k["s_ab"])
    t_b = d_b / (g.g_b * k["s_ab"])
    t_c = d_c / (g.g_c * s_c)
    w_h = g.g_h * s_h
    de_ab = np.sqrt(t_l2 + t_a * t_a + t_b * t_b)
    de_ch = np.sqrt(t_l2 + t_c * t_c + d_h2 / (w_h * w_h))
    c_0 = k["c0_base"] + k["c0_step"] / (1.0 + np.exp(k["c0_l_mid"] - l_m))
    sigma = 1.0 / (1.0 + np.exp(c_m - c_0))
    de = sigma * de_ab + (1.0 - sigma) * de_ch
    return Din6175Terms(l_m, c_m, s_l, s_c, s_h, sigma, de_ab, de_ch, de)


def din6175_terms(
    lab_ref: ArrayLike,
    lab_sample: ArrayLike,
    aspecular_deg: ArrayLike | None,
    g: DinFactors = DIN_DEFAULT_FACTORS,
) -> Din6175Terms:
    """DIN 6175-2 intermediates per pair: L̄, C̄, S_L, S_C, S_H, σ, ΔE_ab,w, ΔE_CH,w and ΔE_eff.

    Parameters
    ----------
    lab_ref, lab_sample
        Lab of standard and sample, shape (..., 3), broadcast together.
    aspecular_deg
        Aspecular angle α of each pair in degrees (broadcast to the pair shape, e.g. shape (n_angles,)
        for (n_angles, 3) Lab); |α| is used, 0 < |α| <= 180.
    g
        Parametric factors (default all 1).
    """
    ref, smp = _as_lab_pair(lab_ref, lab_sample)
    if not isinstance(g, DinFactors):
        raise ModelInputError("din6175.g", "a DinFactors", g)
    alpha = din6175_alpha(aspecular_deg, ref.shape[:-1])
    return din6175_unchecked(ref, smp, alpha, g)


def delta_e_din6175(
    lab_ref: ArrayLike,
    lab_sample: ArrayLike,
    aspecular_deg: ArrayLike | None,
    g: DinFactors = DIN_DEFAULT_FACTORS,
) -> NDArray[np.float64]:
    """DIN 6175-2 ΔE_eff per pair (module docstring for the formula and its source).

    Parameters
    ----------
    lab_ref, lab_sample
        Lab of standard and sample, shape (..., 3).
    aspecular_deg
        Aspecular angle of each pair, degrees (see :func:`din6175_terms`).
    g
        Parametric factors (default all 1).

    Returns
    -------
    ndarray
        ΔE_eff per pair, shape (...).

    Examples
    --------
    Greys at L* 36 and 64 at α = 45°: L̄ = √(36·64) = 48, S_L = 0.15√48 + 31.5/45, and with ΔC = ΔH = 0
    both forms give ΔL/S_L = 28/1.7392 whatever σ:

    >>> round(float(delta_e_din6175([36, 0, 0], [64, 0, 0], 45.0)), 6)
    16.099074
    """
    return din6175_terms(lab_ref, lab_sample, aspecular_deg, g).de_eff


def din6175_summary(
    lab_ref: ArrayLike,
    lab_sample: ArrayLike,
    aspecular_deg: ArrayLike,
    g: DinFactors = DIN_DEFAULT_FACTORS,
) -> Din6175Summary:
    """mdE (mean ΔE_eff over the angles), maxdE and the angle of maxdE for one standard/sample pair.

    *lab_ref*, *lab_sample* are (n_angles, 3), *aspecular_deg* (n_angles,); the first of equal maxima wins.
    """
    ref, smp = _as_lab_pair(lab_ref, lab_sample)
    if ref.ndim != 2 or ref.shape[0] == 0:
        raise ModelInputError("lab", "one Lab triple per angle, shape (n_angles >= 1, 3)", ref.shape)
    angles = np.asarray(aspecular_deg, dtype=float).reshape(-1)
    if angles.shape != (ref.shape[0],):
        raise ModelInputError("aspecular_deg", f"{ref.shape[0]} angles (one per Lab triple)", angles.size)
    per = delta_e_din6175(ref, smp, angles, g)
    worst = int(np.argmax(per))
    return Din6175Summary(
        tuple(float(v) for v in per),
        tuple(float(a) for a in angles),
        float(per.mean()),
        float(per[worst]),
        float(angles[worst]),
    )


def delta_e_cie2000_lc(
    lab_ref: ArrayLike, lab_sample: ArrayLike, k_l: float = 1.0, k_c: float = 1.0, k_h: float = 1.0
) -> NDArray[np.float64]:
    """CIEDE2000 with parametric factors k_L, k_C, k_H (Sharma, Wu & Dalal 2005, eqs 1–22).

    ΔE00 = √((ΔL'/(k_L S_L))² + (ΔC'/(k_C S_C))² + (ΔH'/(k_H S_H))² + R_T (ΔC'/(k_C S_C))(ΔH'/(k_H S_H))).
    Tolerance sets name the ratio "l:c" (2:1 for textiles, 1:1 by default); each factor must be finite
    and > 0. With k_L = k_C = k_H = 1 this is :func:`delta_e` ``"cie2000"`` bit for bit
    (:func:`station.model.cie2000.cie2000_columns`).

    Examples
    --------
    Greys at L* 49 and 51: L̄' = 50, so S_L = 1 and ΔE00 = ΔL'/k_L:

    >>> grey_49, grey_51 = [49, 0, 0], [51, 0, 0]
    >>> float(delta_e_cie2000_lc(grey_49, grey_51)), float(delta_e_cie2000_lc(grey_49, grey_51, k_l=2.0))
    (2.0, 1.0)
    """
    for name, v in (("k_l", k_l), ("k_c", k_c), ("k_h", k_h)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise ModelInputError(f"cie2000.{name}", "a finite number > 0", v)
    ref, smp = _as_lab_pair(lab_ref, lab_sample)
    return cie2000_columns(
        ref[..., 0], ref[..., 1], ref[..., 2], smp[..., 0], smp[..., 1], smp[..., 2], k_l, k_c, k_h
    )


def _colour_method(name: str) -> Callable[[NDArray, NDArray, NDArray | None, DinFactors], NDArray]:
    def fn(a: NDArray, b: NDArray, _alpha: NDArray | None, _g: DinFactors) -> NDArray:
        import colour  # loaded by the first difference it computes (about a second), not by this module

        return np.asarray(colour.delta_E(a, b, method=name), dtype=float)

    return fn


def _din_method(a: NDArray, b: NDArray, aspecular_deg: NDArray | None, g: DinFactors) -> NDArray:
    return delta_e_din6175(a, b, aspecular_deg, g)


def audi2000_unavailable() -> FormulaUnavailableError:
    """The error every use of ``audi2000`` raises until the AUDI2000 coefficients are supplied."""
    return FormulaUnavailableError(
        "de",
        f"{', '.join(DELTA_E_COMPUTED[:-1])} or {DELTA_E_COMPUTED[-1]}: the AUDI2000 coefficients are not "
        "supplied to this build (audi2000 is reserved until they are)",
        "audi2000",
    )


def _audi2000(a: NDArray, b: NDArray, _alpha: NDArray | None, _g: DinFactors) -> NDArray:
    raise audi2000_unavailable()


#: Formula name → ``fn(lab_ref, lab_sample, aspecular_deg, din_factors)`` (read-only); the names are
#: :data:`station.model.domain.DELTA_E_METHOD_NAMES` (tests/model/test_difference_indices.py ties them).
DELTA_E_METHODS: Mapping[str, Callable[[NDArray, NDArray, NDArray | None, DinFactors], NDArray]] = (
    MappingProxyType(
        {
            "cie76": _colour_method("CIE 1976"),
            "cie94": _colour_method("CIE 1994"),
            "cie2000": _colour_method("CIE 2000"),
            "din6175": _din_method,
            "audi2000": _audi2000,
        }
    )
)
#: Formulas that need the aspecular angle of each pair.
ANGLE_DEPENDENT_METHODS = ("din6175", "audi2000")

_ALIASES: Mapping[str, str] = MappingProxyType(
    {
        "cie1976": "cie76",
        "deltaeab": "cie76",
        "ab": "cie76",
        "cie1994": "cie94",
        "de2000": "cie2000",
        "ciede2000": "cie2000",
        "de00": "cie2000",
        "din61752": "din6175",
        "din": "din6175",
        "audi": "audi2000",
    }
)


def validate_method(method: str) -> str:
    """Return the canonical method name or raise :class:`ModelInputError` listing the valid ones.

    Examples
    --------
    >>> validate_method("CIEDE2000"), validate_method("cie76")
    ('cie2000', 'cie76')
    >>> validate_method("cmc9")
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: de: expected one of cie76, cie94, cie2000, din6175, audi2000, got 'cmc9'
    """
    key = str(method).lower().replace(" ", "").replace("-", "").replace("_", "")
    key = _ALIASES.get(key, key)
    if key not in DELTA_E_METHODS:
        raise ModelInputError("de", f"one of {', '.join(DELTA_E_METHODS)}", method)
    return key


def delta_e(
    lab_ref: ArrayLike,
    lab_sample: ArrayLike,
    method: str = "cie2000",
    *,
    aspecular_deg: ArrayLike | None = None,
    din_factors: DinFactors = DIN_DEFAULT_FACTORS,
) -> NDArray[np.float64]:
    """Colour difference between reference and sample Lab, element-wise over the last axis.

    Parameters
    ----------
    lab_ref, lab_sample
        Lab arrays of shape (..., 3) (broadcast together), e.g. (n_angles, 3) per angle set.
    method
        ``"cie76"``, ``"cie94"``, ``"cie2000"``, ``"din6175"`` (or ``"audi2000"``, which refuses).
    aspecular_deg
        Aspecular angle of each pair in degrees, broadcast to the pair shape (…); required by
        ``din6175``, ignored by the others.
    din_factors
        DIN 6175-2 parametric factors (default all 1).

    Returns
    -------
    ndarray
        ΔE of shape (...).

    Examples
    --------
    A 3-4-5 triangle in ΔE*ab, Sharma et al. (2005) Table 1 pairs 1 and 7 in CIEDE2000 (published 2.0425
    and 2.3669), and per angle over a (3, 3) array:

    >>> float(delta_e([50, 0, 0], [53, 4, 0], "cie76"))
    5.0
    >>> round(float(delta_e([50, 2.6772, -79.7751], [50, 0, -82.7485])), 4)
    2.0425
    >>> round(float(delta_e([50, 0, 0], [50, -1, 2], "cie2000")), 4)
    2.3669
    >>> delta_e([[90, 1, 1], [50, 1, 1], [30, 1, 1]], [[93, 5, 1], [50, 1, 1], [30, 1, 2]], "cie76").tolist()
    [5.0, 0.0, 1.0]
    """
    fn = DELTA_E_METHODS[validate_method(method)]
    ref, smp = _as_lab_pair(lab_ref, lab_sample)
    alpha = None if aspecular_deg is None else np.asarray(aspecular_deg, dtype=float)
    return np.asarray(fn(ref, smp, alpha, din_factors), dtype=float)


def delta_e_aggregate(
    lab_ref: ArrayLike,
    lab_sample: ArrayLike,
    method: str = "cie2000",
    aggregate: Aggregate = "mean",
    *,
    aspecular_deg: ArrayLike | None = None,
) -> float:
    """ΔE aggregated over an angle set: ``mean``, ``max``, ``rms`` or ``sum`` of the per-angle values.

    Examples
    --------
    >>> ref = [[90, 1, 1], [50, 1, 1], [30, 1, 1]]
    >>> smp = [[93, 5, 1], [50, 1, 1], [30, 1, 2]]
    >>> [round(delta_e_aggregate(ref, smp, "cie76", a), 6) for a in ("mean", "max", "sum")]
    [2.0, 5.0, 6.0]
    """
    per_angle = delta_e(lab_ref, lab_sample, method, aspecular_deg=aspecular_deg).reshape(-1)
    ops: dict[str, Callable[[NDArray], float | np.floating]] = {
        "mean": np.mean,
        "max": np.max,
        "sum": np.sum,
        "rms": lambda x: np.sqrt(np.mean(x * x)),
    }
    if aggregate not in ops:
        raise ModelInputError("aggregate", f"one of {', '.join(ops)}", aggregate)
    return float(ops[aggregate](per_angle))
