"""Colour-difference kernels for ColorSnap's hot loop, bit-identical to :func:`station.model.difference.delta_e`.

:func:`station.model.difference.delta_e` validates and dispatches on every call (about 150 µs for
CIEDE2000 through colour-science), which would dominate a sub-millisecond search. These kernels
repeat the same floating-point operations in the same order, without the checks:

* ``cie76``   — ``np.linalg.norm(lab2 - lab1, axis=-1)``, as colour's ``euclidean_distance``.
* ``cie2000`` — the arithmetic of colour's ``intermediate_attributes_CIE2000`` / ``delta_E_CIE2000``
  (Sharma, Wu & Dalal 2005), kL = kC = kH = 1.
* ``din6175`` — the arithmetic of :func:`station.model.difference.delta_e_din6175` (DIN 6175-2 as
  published in a public implementation), which needs the aspecular angle of each pair.

tests/formulate/test_de_kernels.py asserts exact equality (``==``, not a tolerance) against
:func:`~station.model.difference.delta_e` on random and edge-case inputs, which is what makes the
ColorSnap ranking identical to a brute-force scan through the public function.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray

from station.model.difference import DIN6175_COEFFICIENTS

#: ``kernel(lab_standard, lab_sample, alpha)``: *alpha* the |aspecular angle| per pair (degrees), read by
#: din6175 only.
Kernel = Callable[[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def cie76(
    lab1: NDArray[np.float64], lab2: NDArray[np.float64], alpha: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """ΔE*ab (CIE 1976), shape (...); *alpha* is not read."""
    return np.linalg.norm(lab1 - lab2, axis=-1)


def cie2000(
    lab1: NDArray[np.float64], lab2: NDArray[np.float64], alpha: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """CIEDE2000 with kL = kC = kH = 1, shape (...); *lab1* is the reference; *alpha* is not read."""
    return cie2000_columns(lab1[..., 0], lab1[..., 1], lab1[..., 2], lab2[..., 0], lab2[..., 1], lab2[..., 2])


def cie2000_columns(
    L_1: NDArray[np.float64],
    a_1: NDArray[np.float64],
    b_1: NDArray[np.float64],
    L_2: NDArray[np.float64],
    a_2: NDArray[np.float64],
    b_2: NDArray[np.float64],
) -> NDArray[np.float64]:
    """:func:`cie2000` from the L*, a*, b* columns (which broadcast); contiguous columns are fastest.

    The same operations as colour's ``delta_E_CIE2000`` on every element, with the redundant ones
    dropped (each drop leaves every value unchanged): k_L = k_C = k_H = 1 multiplications (1·x = x);
    ΔC'/S_C and ΔH'/S_H computed once and reused; 1 + G computed once; |h'₁ − h'₂| taken as |h'₂ − h'₁|
    (IEEE subtraction is sign-symmetric); the last condition of each np.select chain folded into an
    else (for finite Lab the conditions cover every case; only a NaN input, whose ΔE00 is NaN either
    way, would reach np.select's default); the achromatic hue
    test skipped for a side with no a* = b* = 0 element (there (1+G)a* = 0 ⇔ a* = 0, so the test is
    all false and np.where returns its second argument unchanged).
    """
    C_1_ab = np.hypot(a_1, b_1)
    C_2_ab = np.hypot(a_2, b_2)
    C_bar_ab = (C_1_ab + C_2_ab) / 2
    C_bar_ab_7 = C_bar_ab**7
    G = 0.5 * (1 - np.sqrt(C_bar_ab_7 / (C_bar_ab_7 + 25**7)))
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
    delta_L_p = L_2 - L_1
    delta_C_p = C_p_2 - C_p_1
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
    L_bar_p = (L_1 + L_2) / 2
    C_bar_p = (C_p_1 + C_p_2) / 2
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
    T = (
        1
        - 0.17 * np.cos(np.deg2rad(h_bar_p - 30))
        + 0.24 * np.cos(np.deg2rad(2 * h_bar_p))
        + 0.32 * np.cos(np.deg2rad(3 * h_bar_p + 6))
        - 0.20 * np.cos(np.deg2rad(4 * h_bar_p - 63))
    )
    delta_theta = 30 * np.exp(-(((h_bar_p - 275) / 25) ** 2))
    C_bar_p_7 = C_bar_p**7
    R_C = 2 * np.sqrt(C_bar_p_7 / (C_bar_p_7 + 25**7))
    L_bar_p_2 = (L_bar_p - 50) ** 2
    S_L = 1 + ((0.015 * L_bar_p_2) / np.sqrt(20 + L_bar_p_2))
    S_C = 1 + 0.045 * C_bar_p
    S_H = 1 + 0.015 * C_bar_p * T
    R_T = -np.sin(np.deg2rad(2 * delta_theta)) * R_C
    x = delta_C_p / S_C
    y = delta_H_p / S_H
    return np.sqrt((delta_L_p / S_L) ** 2 + x**2 + y**2 + R_T * x * y)


def din6175(
    lab1: NDArray[np.float64], lab2: NDArray[np.float64], alpha: NDArray[np.float64]
) -> NDArray[np.float64]:
    """DIN 6175-2 ΔE_eff with g = 1, *lab1* the standard, *alpha* the |aspecular angle| (°) of each pair.

    The arithmetic of :func:`station.model.difference.delta_e_din6175` without its input checks (a
    test asserts bit-identity, so a change of the model's coefficients or form shows up at once). The
    g-factor products of the model are left out: with g = 1 they are exact (1·x = x). *alpha* must
    broadcast to the pair shape and be > 0 (e.g. shape (n_angles,) for (…, n_angles, 3) Lab).
    """
    k = DIN6175_COEFFICIENTS
    l_1, a_1, b_1 = lab1[..., 0], lab1[..., 1], lab1[..., 2]
    l_2, a_2, b_2 = lab2[..., 0], lab2[..., 1], lab2[..., 2]
    c_1 = np.hypot(a_1, b_1)
    c_2 = np.hypot(a_2, b_2)
    d_l = l_2 - l_1
    d_a = a_2 - a_1
    d_b = b_2 - b_1
    d_c = c_2 - c_1
    d_h2 = np.maximum(d_a * d_a + d_b * d_b - d_c * d_c, 0.0)
    l_m = np.sqrt(np.abs(l_1 * l_2))
    c_m = np.sqrt(c_1 * c_2)
    sq_l = np.sqrt(l_m)
    sq_c = np.sqrt(c_m)
    s_l = k["sl_sqrt_l"] * sq_l + k["sl_alpha"] / alpha
    s_c = np.maximum(k["s_floor"], k["sc_sqrt_c"] * sq_c - k["sc_sqrt_l"] * sq_l + k["sc_alpha"] / alpha)
    s_h = np.maximum(
        k["s_floor"], k["sh_sqrt_c"] * sq_c - k["sh_sqrt_l"] * sq_l + k["sh_alpha"] / alpha + k["sh_offset"]
    )
    t_l = d_l / s_l
    t_l2 = t_l * t_l
    t_a = d_a / k["s_ab"]
    t_b = d_b / k["s_ab"]
    t_c = d_c / s_c
    de_ab = np.sqrt(t_l2 + t_a * t_a + t_b * t_b)
    de_ch = np.sqrt(t_l2 + t_c * t_c + d_h2 / (s_h * s_h))
    c_0 = k["c0_base"] + k["c0_step"] / (1.0 + np.exp(k["c0_l_mid"] - l_m))
    sigma = 1.0 / (1.0 + np.exp(c_m - c_0))
    return sigma * de_ab + (1.0 - sigma) * de_ch


KERNELS: Mapping[str, Kernel] = MappingProxyType({"cie76": cie76, "cie2000": cie2000, "din6175": din6175})
