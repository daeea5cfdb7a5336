"""The gloss lobe every shader uses: 60° gloss (GU) → normalised Phong lobe (n, ρ_s), and its value.

The lobe is the model's energy-conserving first-surface reflection (:mod:`station.model.gloss`): the
reflected flux is distributed about the mirror direction R as (n + 1)/(2π) cosⁿψ per steradian and
carries the fraction ρ_s = F(60°; 1.567) of the incident energy. As a BRDF × cos term it is exactly the
gloss lobe of the thesis's basis (eq 2.3.2, not scaled by L·N), with K_G = ρ_s (n + 1)/(2π):

    gloss(α) = ρ_s (n + 1)/(2π) · max(cos α, 0)ⁿ        (sr⁻¹; α = aspecular angle = ∠(R, V))

and, compared with a white diffuser (BRDF 1/π) under the same light, the reflectance factor

    π · gloss(α) = ρ_s (n + 1)/2 · max(cos α, 0)ⁿ        (dimensionless).

GU → (n, ρ_s) is :func:`station.model.gloss.lobe_from_gloss` (the exponent whose simulated gloss meter
reads the gloss), read from a table of the *forward* meter simulation on 2048 exponents spaced evenly
in ln n from 1 to :data:`~station.model.gloss.PHONG_MAX`, interpolated linearly in ln n; it agrees
with ``lobe_from_gloss`` to better than 1e-4 in n over 1–99 GU (tests/model/test_lobe.py), and a
call costs microseconds instead of ~0.1 s. Below the widest lobe's reading (n = 1, about 0.5 GU) the
exponent stays 1 and ρ_s is scaled down so the meter still reads the gloss; at and above the meter's
saturation (a mirror, 100 GU) the exponent is PHONG_MAX.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.errors import ModelInputError
from station.model.gloss import (
    PHONG_MAX,
    PHONG_MIN,
    STANDARD_INDEX,
    fresnel_unpolarised,
    max_gloss_gu,
    phong_gloss_readings,
)

__all__ = ["TABLE_EXPONENTS", "lobe_brdf_cos", "lobe_reflectance", "phong_lobe"]

#: Exponents (evenly spaced in ln n) of the forward-meter table behind :func:`phong_lobe`.
TABLE_EXPONENTS = 2048


@cache
def _table() -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """(GU, ln n) of the forward meter on TABLE_EXPONENTS exponents, strictly increasing in GU; ρ_s."""
    albedo = fresnel_unpolarised(60.0, STANDARD_INDEX)
    ln_n = np.linspace(np.log(PHONG_MIN), np.log(PHONG_MAX), TABLE_EXPONENTS)
    gu = phong_gloss_readings(np.exp(ln_n))
    # the meter saturates at 100 GU near a mirror: keep the strictly increasing head of the curve
    keep = np.logical_and.accumulate(np.concatenate([[True], np.diff(gu) > 1e-9]))
    gu, ln_n = gu[keep], ln_n[keep]
    gu.flags.writeable = ln_n.flags.writeable = False  # cached for the process: read-only
    return gu, ln_n, albedo


def phong_lobe(gloss_gu: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Phong exponent n and specular albedo ρ_s of 60° gloss, elementwise (module docstring).

    Parameters
    ----------
    gloss_gu
        60° specular gloss in GU (ISO 2813), 0 ≤ g ≤ 100, any shape.

    Returns
    -------
    (n, ρ_s)
        Exponent (dimensionless, 1 … PHONG_MAX) and albedo (fraction of incident energy), each of
        the shape of *gloss_gu* (0-d arrays for a scalar).

    Raises
    ------
    ModelInputError
        ``gloss_gu`` non-finite or outside 0–100 GU.
    """
    top = max_gloss_gu(STANDARD_INDEX)
    try:
        g = np.asarray(gloss_gu, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelInputError("gloss_gu", f"0 <= gloss_gu <= {top:g} GU", gloss_gu) from exc
    if not np.all(np.isfinite(g)) or np.any(g < 0.0) or np.any(g > top):
        raise ModelInputError("gloss_gu", f"0 <= gloss_gu <= {top:g} GU", gloss_gu)
    gu, ln_n, albedo = _table()
    n = np.where(g >= gu[-1], PHONG_MAX, np.exp(np.interp(g, gu, ln_n)))
    rho_s = np.where(g <= gu[0], albedo * g / gu[0], albedo)
    return n, rho_s


def lobe_brdf_cos(
    phong_exponent: ArrayLike, specular_albedo: ArrayLike, cos_alpha: ArrayLike
) -> NDArray[np.float64]:
    """Gloss term of BRDF × cos, ρ_s (n + 1)/(2π) · max(cos α, 0)ⁿ, in sr⁻¹ (eq 2.3.2, K_G form).

    All arguments broadcast; *cos_alpha* is the cosine of the aspecular angle (R·V).
    """
    n = np.asarray(phong_exponent, dtype=float)
    c = np.clip(np.asarray(cos_alpha, dtype=float), 0.0, 1.0)
    return np.asarray(specular_albedo, dtype=float) * (n + 1.0) / (2.0 * np.pi) * c**n


def lobe_reflectance(gloss_gu: float, aspecular_deg: ArrayLike) -> NDArray[np.float64]:
    """Reflectance factor of the gloss lobe of *gloss_gu* (GU) at aspecular angles (degrees).

    π × :func:`lobe_brdf_cos`: ρ_s (n + 1)/2 · max(cos α, 0)ⁿ, 0 at and beyond 90°; same shape as
    *aspecular_deg*. A reflectance factor of 1 is the radiance of a white diffuser under the same light.
    """
    n, rho_s = phong_lobe(float(gloss_gu))
    c = np.cos(np.radians(np.asarray(aspecular_deg, dtype=float)))
    return np.asarray(np.pi * lobe_brdf_cos(n, rho_s, c), dtype=float)
