"""Lab ⇄ display sRGB: what a screen shows of a colour (colour-science underneath).

Display sRGB is the IEC 61966-2-1 encoding of linear sRGB clipped to [0, 1] (the display's clip; the
linear data is never clipped): V = 12.92 x for x ≤ 0.0031308, else 1.055 x^(1/2.4) − 0.055 (the
thesis's "gamma", §3.7.3). Linear sRGB is :func:`station.model.colorimetry.lab_to_linear_srgb`
(Lab D65 / 10°, CAT02 to the sRGB white, L* = 100 → (1, 1, 1)).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.colorimetry import lab_to_linear_srgb, linear_srgb_to_lab, srgb_decode, srgb_encode

__all__ = ["decode_display", "display_to_lab", "encode_display", "lab_to_display", "to_uint8"]


def encode_display(linear: ArrayLike) -> NDArray[np.float64]:
    """Display sRGB values in [0, 1] of linear sRGB (clipped to [0, 1], then the sRGB encoding)."""
    return srgb_encode(np.clip(np.asarray(linear, dtype=float), 0.0, 1.0))


def decode_display(encoded: ArrayLike) -> NDArray[np.float64]:
    """Linear sRGB of display values in [0, 1] (the sRGB EOTF, "inverse gamma", thesis §3.7.3)."""
    return srgb_decode(np.asarray(encoded, dtype=float))


def lab_to_display(lab: ArrayLike) -> NDArray[np.float64]:
    """Display sRGB in [0, 1] of Lab (D65 / 10°), shape (..., 3); out-of-gamut channels are clipped."""
    return encode_display(lab_to_linear_srgb(lab))


def display_to_lab(encoded: ArrayLike) -> NDArray[np.float64]:
    """Lab (D65 / 10°) of display sRGB values in [0, 1], shape (..., 3)."""
    return linear_srgb_to_lab(decode_display(encoded))


def to_uint8(encoded: ArrayLike) -> NDArray[np.uint8]:
    """Quantise display values in [0, 1] to 8 bits (round half up; values outside are clipped)."""
    return np.floor(np.clip(np.asarray(encoded, dtype=float), 0, 1) * 255.0 + 0.5).astype(np.uint8)
