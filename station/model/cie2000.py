"""CIEDE2000 arithmetic in NumPy (Sharma, Wu & Dalal 2005), the one copy the product computes with.

colour-science's ``delta_E_CIE2000`` validates and converts on every call (about 150 µs), which would
dominate ColorSnap's sub-millisecond search and the tolerance checks. :func:`cie2000_columns` performs
the same floating-point operations in the same order without the checks, so its results are
bit-identical to colour's (tests/model/test_cie2000_reference.py asserts ``==`` on random pairs and
Sharma et al.'s published pairs to their 4 decimals; docs/adr/0006-numpy-ciede2000.md says why).
:func:`station.model.difference.delta_e_cie2000_lc` validates its input and calls it with parametric
factors; ``station.formulate.de_kernels`` uses it as ColorSnap's kernel.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["CIE2000_K7", "cie2000_columns"]

#: 25⁷, the chroma constant of G and R_C (Sharma, Wu & Dalal 2005, eqs 2 and 21); exact in float64.
CIE2000_K7 = 25.0**7


def cie2000_columns(
    L_1: NDArray[np.float64],
    a_1: NDArray[np.float64],
    b_1: NDArray[np.float64],
    L_2: NDArray[np.float64],
    a_2: NDArray[np.float64],
    b_2: NDArray[np.float64],
    k_l: float = 1.0,
    k_c: float = 1.0,
    k_h: float = 1.0,
) -> NDArray[np.float64]:
    """CIEDE2000 from the L*, a*, b* columns (which broadcast), *L_1* … the reference; no input checks.

    Parametric factors k_L, k_C, k_H divide S_L, S_C, S_H (Sharma, Wu & Dalal 2005, eq 22); with the
    default 1 each product k·S is S exactly, so the result is bit-identical to colour's. The same operations as colour's ``delta_E_CIE2000`` on every element, with the redundant ones
    dropped (each drop leaves every value unchanged): k_L = k_C = k_H = 1 multiplications (1·x = x);
    ΔC'/S_C and ΔH'/S_H computed once and reused; 1 + G computed once; |h'₁ − h'₂| taken as |h'₂ − h'₁|
    (IEEE subtraction is sign-symmetric); the last condition of each np.select chain folded into an
    else (for finite Lab the conditions cover every case; only a NaN input, whose ΔE00 is NaN either
    way, would reach np.select's default); the achromatic hue
    test skipped for a side with no a* = b* = 0 element (there (1+G)a* = 0 ⇔ a* = 0, so the test is
    all false and np.where returns its second argument unchanged).

    Examples
    --------
    Sharma et al. (2005) Table 1 pairs 7 and 17 (published 2.3669 and 27.1492), as columns:

    >>> import numpy as np
    >>> L1, a1, b1 = np.array([[50.0, 0.0, 0.0], [50.0, 2.5, 0.0]]).T
    >>> L2, a2, b2 = np.array([[50.0, -1.0, 2.0], [73.0, 25.0, -18.0]]).T
    >>> cie2000_columns(L1, a1, b1, L2, a2, b2).round(4).tolist()
    [2.3669, 27.1492]
    """
    C_p_1, C_p_2, h_p_1, h_p_2 = _primed(a_1, b_1, a_2, b_2)
    delta_L_p = L_2 - L_1
    delta_C_p = C_p_2 - C_p_1
    delta_H_p, h_bar_p = _hue_terms(C_p_1, C_p_2, h_p_1, h_p_2)
    S_L, S_C, S_H, R_T = _weights((L_1 + L_2) / 2, (C_p_1 + C_p_2) / 2, h_bar_p)
    x = delta_C_p / (k_c * S_C)
    y = delta_H_p / (k_h * S_H)
    return np.sqrt((delta_L_p / (k_l * S_L)) ** 2 + x**2 + y**2 + R_T * x * y)


Array = NDArray[np.float64]


def _primed(a_1: Array, b_1: Array, a_2: Array, b_2: Array) -> tuple[Array, Array, Array, Array]:
    """C'₁, C'₂ and h'₁, h'₂ (degrees in [0, 360)): a* scaled by 1 + G (Sharma et al. 2005, eqs 1–7)."""
    C_1_ab = np.hypot(a_1, b_1)
    C_2_ab = np.hypot(a_2, b_2)
    C_bar_ab = (C_1_ab + C_2_ab) / 2
    C_bar_ab_7 = C_bar_ab**7
    G = 0.5 * (1 - np.sqrt(C_bar_ab_7 / (C_bar_ab_7 + CIE2000_K7)))
    one_G = 1 + G
    a_p_1 = one_G * a_1
    a_p_2 = one_G * a_2
    C_p_1 = np.hypot(a_p_1, b_1)
    C_p_2 = np.hypot(a_p_2, b_2)
    h_p_1 = np.degrees(np.arctan2(b_1, a_p_1)) % 360
    if np.logical_and(b_1 == 0, a_1 == 0).any():
        h_p_1 = np.where(np.logical_and(b_1 == 0, a_p_1 == 0), 0, h_p_1)
    h_p_2 = np.degrees(np.arctan2(b_2, a_p_2)) % 360
    if np.logical_and(b_2 == 0, a_2 == 0).any():
        h_p_2 = np.where(np.logical_and(b_2 == 0, a_p_2 == 0), 0, h_p_2)
    return C_p_1, C_p_2, h_p_1, h_p_2


def _hue_terms(C_p_1: Array, C_p_2: Array, h_p_1: Array, h_p_2: Array) -> tuple[Array, Array]:
    """ΔH' and the mean hue h̄' (degrees) (Sharma et al. 2005, eqs 10–11 and 14)."""
    h_p_2_s_1 = h_p_2 - h_p_1
    C_p_1_m_2 = C_p_1 * C_p_2
    zero = C_p_1_m_2 == 0
    a_h_p_1_s_2 = np.fabs(h_p_2_s_1)
    # colour: np.select([C=0, |Δ| ≤ 180, Δ > 180, Δ < −180], [0, Δ, Δ − 360, Δ + 360]); for a non-NaN Δ
    # in (−360, 360) the last two conditions are exclusive, and NaN gives NaN either way
    delta_h_p = np.where(
        zero,
        0,
        np.where(a_h_p_1_s_2 <= 180, h_p_2_s_1, np.where(h_p_2_s_1 > 180, h_p_2_s_1 - 360, h_p_2_s_1 + 360)),
    )
    delta_H_p = 2 * np.sqrt(C_p_1_m_2) * np.sin(np.deg2rad(delta_h_p / 2))
    h_p_1_a_2 = h_p_1 + h_p_2
    h_bar_p = np.where(
        zero,
        h_p_1_a_2,
        np.where(
            a_h_p_1_s_2 <= 180,
            h_p_1_a_2 / 2,
            np.where(h_p_1_a_2 < 360, (h_p_1_a_2 + 360) / 2, (h_p_1_a_2 - 360) / 2),
        ),
    )
    return delta_H_p, h_bar_p


def _weights(L_bar_p: Array, C_bar_p: Array, h_bar_p: Array) -> tuple[Array, Array, Array, Array]:
    """S_L, S_C, S_H and R_T from the means L̄', C̄', h̄' (Sharma et al. 2005, eqs 15–21)."""
    T = (
        1
        - 0.17 * np.cos(np.deg2rad(h_bar_p - 30))
        + 0.24 * np.cos(np.deg2rad(2 * h_bar_p))
        + 0.32 * np.cos(np.deg2rad(3 * h_bar_p + 6))
        - 0.20 * np.cos(np.deg2rad(4 * h_bar_p - 63))
    )
    delta_theta = 30 * np.exp(-(((h_bar_p - 275) / 25) ** 2))
    C_bar_p_7 = C_bar_p**7
    R_C = 2 * np.sqrt(C_bar_p_7 / (C_bar_p_7 + CIE2000_K7))
    L_bar_p_2 = (L_bar_p - 50) ** 2
    S_L = 1 + ((0.015 * L_bar_p_2) / np.sqrt(20 + L_bar_p_2))
    S_C = 1 + 0.045 * C_bar_p
    S_H = 1 + 0.015 * C_bar_p * T
    R_T = -np.sin(np.deg2rad(2 * delta_theta)) * R_C
    return S_L, S_C, S_H, R_T
