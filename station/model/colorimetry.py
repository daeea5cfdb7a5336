"""Colorimetric conversions used across the product (thin wrappers over colour-science).

Lab is CIE L*a*b* relative to D65 and the CIE 1964 10° observer unless a field says otherwise
(docs/design.md §8). "Linear sRGB" is scene-linear sRGB (IEC 61966-2-1 primaries, D65), no tone mapping
and no transfer function: a reflectance factor of 1 on every channel is the perfect white.

Chromatic adaptation: sRGB's white is D65 for the 2° observer; our Lab white is D65 for the 10°
observer. The conversion maps the 10° white to the sRGB white with a von Kries (CAT02) adaptation,
so L* = 100, a* = b* = 0 is exactly linear sRGB (1, 1, 1).
"""

from __future__ import annotations

import colour
import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Observer of every Lab value unless stated: the CIE 1964 10° standard observer.
OBSERVER_10 = "CIE 1964 10 Degree Standard Observer"
#: Chromaticity (x, y) of D65 for the 10° observer, the white of our Lab.
WHITEPOINT: NDArray[np.float64] = np.asarray(colour.CCS_ILLUMINANTS[OBSERVER_10]["D65"], dtype=float)
_SRGB = colour.RGB_COLOURSPACES["sRGB"]


def lab_to_xyz(lab: ArrayLike, whitepoint: ArrayLike = WHITEPOINT) -> NDArray[np.float64]:
    """Convert Lab (L* 0–100) to XYZ scaled so the white has Y = 1.

    Parameters
    ----------
    lab
        CIE L*a*b*, shape (..., 3).
    whitepoint
        Reference white chromaticity (x, y); default D65 / 10°.

    Returns
    -------
    ndarray
        XYZ, shape (..., 3), Y of the white = 1.
    """
    return np.asarray(colour.Lab_to_XYZ(np.asarray(lab, dtype=float), whitepoint), dtype=float)


def xyz_to_lab(xyz: ArrayLike, whitepoint: ArrayLike = WHITEPOINT) -> NDArray[np.float64]:
    """Convert XYZ (white Y = 1) to Lab relative to *whitepoint* (default D65 / 10°)."""
    return np.asarray(colour.XYZ_to_Lab(np.asarray(xyz, dtype=float), whitepoint), dtype=float)


def _adaptation(source_xy: ArrayLike, target_xy: ArrayLike) -> NDArray[np.float64]:
    src = colour.xy_to_XYZ(source_xy)
    dst = colour.xy_to_XYZ(target_xy)
    return np.asarray(colour.adaptation.matrix_chromatic_adaptation_VonKries(src, dst, "CAT02"), dtype=float)


_M = _SRGB.matrix_XYZ_to_RGB @ _adaptation(WHITEPOINT, _SRGB.whitepoint)
# colour's sRGB matrix is rounded to 4 decimals (IEC 61966-2-1); rescale its rows so the Lab white
# maps to exactly (1, 1, 1) rather than to within 2e-4 of it.
_XYZ10_TO_LINEAR_SRGB = _M / (_M @ colour.xy_to_XYZ(WHITEPOINT))[:, None]
_LINEAR_SRGB_TO_XYZ10 = np.linalg.inv(_XYZ10_TO_LINEAR_SRGB)


def lab_to_linear_srgb(lab: ArrayLike) -> NDArray[np.float64]:
    """Convert Lab (D65/10°) to scene-linear sRGB reflectance factors (white = 1, 1, 1).

    Out-of-gamut colours give channel values below 0 or above 1; they are returned as they are so
    the caller decides (the renderer reports them, never clamps silently).
    """
    return lab_to_xyz(lab) @ _XYZ10_TO_LINEAR_SRGB.T


def linear_srgb_to_lab(rgb: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`lab_to_linear_srgb`."""
    return xyz_to_lab(np.asarray(rgb, dtype=float) @ _LINEAR_SRGB_TO_XYZ10.T)


def srgb_encode(rgb_linear: ArrayLike) -> NDArray[np.float64]:
    """Apply the IEC 61966-2-1 sRGB transfer function (inverse EOTF) to linear values in [0, 1]."""
    return np.asarray(colour.models.eotf_inverse_sRGB(np.asarray(rgb_linear, dtype=float)), dtype=float)


def srgb_decode(rgb_encoded: ArrayLike) -> NDArray[np.float64]:
    """Decode sRGB-encoded values in [0, 1] to linear (the sRGB EOTF)."""
    return np.asarray(colour.models.eotf_sRGB(np.asarray(rgb_encoded, dtype=float)), dtype=float)
