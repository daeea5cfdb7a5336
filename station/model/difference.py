"""Colour differences per aspecular angle and aggregated over an angle set (docs/design.md §3).

Methods (dispatched from :data:`DELTA_E_METHODS`):

=========  ==========================================================================================
cie76      ΔE*ab, CIE 1976 (colour-science)
cie94      CIE 1994, graphic-arts weights (colour-science)
cie2000    CIEDE2000 (colour-science)
din6175    effect-paint difference in the DIN 6175-2 form — see :func:`delta_e_din6175`
=========  ==========================================================================================

The first argument of every function is the reference (standard, design), the second the sample.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

import colour
import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.errors import ModelInputError

DeltaEMethod = Literal["cie76", "cie94", "cie2000", "din6175"]
Aggregate = Literal["mean", "max", "rms", "sum"]

#: Weights of :func:`delta_e_din6175`. PROVISIONAL: DIN 6175-2:2001's own coefficients could not be
#: obtained for this build (shared/research/instruments.md §3 records the same); these reproduce the
#: standard's structure with published weights: CIE94's reference-chroma weights for ΔC*, ΔH* and
#: CIEDE2000's lightness weight for ΔL*, evaluated on the reference at each angle.
DIN6175_WEIGHTS = {"k_C": 0.045, "k_H": 0.015, "k_L": 0.015}


def _as_lab_pair(lab_ref: ArrayLike, lab_sample: ArrayLike) -> tuple[NDArray, NDArray]:
    a = np.asarray(lab_ref, dtype=float)
    b = np.asarray(lab_sample, dtype=float)
    if a.shape[-1:] != (3,) or b.shape[-1:] != (3,):
        raise ModelInputError("lab", "arrays of shape (..., 3)", (a.shape, b.shape))
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ModelInputError("lab", "finite L*, a*, b* values", "non-finite values")
    a, b = np.broadcast_arrays(a, b)
    return a, b


def delta_e_din6175(lab_ref: ArrayLike, lab_sample: ArrayLike) -> NDArray[np.float64]:
    """Effect-paint colour difference in the DIN 6175-2 form, per angle.

    ΔE = sqrt((ΔL*/S_L)² + (ΔC*/S_C)² + (ΔH*/S_H)²), with, on the reference at each angle,
    S_L = 1 + k_L (L* − 50)² / sqrt(20 + (L* − 50)²), S_C = 1 + k_C C*, S_H = 1 + k_H C*.

    The lightness weight grows away from mid grey, so the bright near-specular angles of a metallic
    (L*15 of 100–140) tolerate more ΔL* than the dark flop, as DIN 6175-2 intends. The weights in
    :data:`DIN6175_WEIGHTS` are provisional (see there).

    Parameters
    ----------
    lab_ref, lab_sample
        Lab of reference and sample, shape (..., 3).

    Returns
    -------
    ndarray
        ΔE per element, shape (...).
    """
    ref, smp = _as_lab_pair(lab_ref, lab_sample)
    c_ref = np.hypot(ref[..., 1], ref[..., 2])
    c_smp = np.hypot(smp[..., 1], smp[..., 2])
    d_l = smp[..., 0] - ref[..., 0]
    d_c = c_smp - c_ref
    d_ab2 = (smp[..., 1] - ref[..., 1]) ** 2 + (smp[..., 2] - ref[..., 2]) ** 2
    d_h2 = np.maximum(d_ab2 - d_c**2, 0.0)  # ΔH*² = Δa*² + Δb*² − ΔC*²
    w = DIN6175_WEIGHTS
    dl50 = (ref[..., 0] - 50.0) ** 2
    s_l = 1.0 + w["k_L"] * dl50 / np.sqrt(20.0 + dl50)
    s_c = 1.0 + w["k_C"] * c_ref
    s_h = 1.0 + w["k_H"] * c_ref
    return np.sqrt((d_l / s_l) ** 2 + (d_c / s_c) ** 2 + d_h2 / s_h**2)


def _colour_method(name: str) -> Callable[[NDArray, NDArray], NDArray]:
    def fn(a: NDArray, b: NDArray) -> NDArray:
        return np.asarray(colour.delta_E(a, b, method=name), dtype=float)

    return fn


DELTA_E_METHODS: dict[str, Callable[[NDArray, NDArray], NDArray]] = {
    "cie76": _colour_method("CIE 1976"),
    "cie94": _colour_method("CIE 1994"),
    "cie2000": _colour_method("CIE 2000"),
    "din6175": delta_e_din6175,
}


def validate_method(method: str) -> str:
    """Return the canonical method name or raise :class:`ModelInputError` listing the valid ones."""
    key = str(method).lower().replace(" ", "").replace("-", "").replace("_", "")
    aliases = {
        "cie1976": "cie76",
        "deltaeab": "cie76",
        "ab": "cie76",
        "cie1994": "cie94",
        "de2000": "cie2000",
        "ciede2000": "cie2000",
        "de00": "cie2000",
        "din61752": "din6175",
    }
    key = aliases.get(key, key)
    if key not in DELTA_E_METHODS:
        raise ModelInputError("de", f"one of {', '.join(DELTA_E_METHODS)}", method)
    return key


def delta_e(lab_ref: ArrayLike, lab_sample: ArrayLike, method: str = "cie2000") -> NDArray[np.float64]:
    """Colour difference between reference and sample Lab, element-wise over the last axis.

    Parameters
    ----------
    lab_ref, lab_sample
        Lab arrays of shape (..., 3) (broadcast together), e.g. (n_angles, 3) per angle set.
    method
        ``"cie76"``, ``"cie94"``, ``"cie2000"`` or ``"din6175"``.

    Returns
    -------
    ndarray
        ΔE of shape (...).
    """
    fn = DELTA_E_METHODS[validate_method(method)]
    ref, smp = _as_lab_pair(lab_ref, lab_sample)
    return np.asarray(fn(ref, smp), dtype=float)


def delta_e_aggregate(
    lab_ref: ArrayLike, lab_sample: ArrayLike, method: str = "cie2000", aggregate: Aggregate = "mean"
) -> float:
    """ΔE aggregated over an angle set: ``mean``, ``max``, ``rms`` or ``sum`` of the per-angle values."""
    per_angle = delta_e(lab_ref, lab_sample, method).reshape(-1)
    ops: dict[str, Callable[[NDArray], float | np.floating]] = {
        "mean": np.mean,
        "max": np.max,
        "sum": np.sum,
        "rms": lambda x: np.sqrt(np.mean(x * x)),
    }
    if aggregate not in ops:
        raise ModelInputError("aggregate", f"one of {', '.join(ops)}", aggregate)
    return float(ops[aggregate](per_angle))
