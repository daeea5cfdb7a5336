"""Colorimetric conversions used across the product (the CIE Lab and sRGB formulae in NumPy).

Lab is CIE L*a*b* relative to D65 and the CIE 1964 10° observer unless a field says otherwise
(docs/design.md §8). "Linear sRGB" is scene-linear sRGB (IEC 61966-2-1 primaries, D65), no tone mapping
and no transfer function: a reflectance factor of 1 on every channel is the perfect white.

Chromatic adaptation: sRGB's white is D65 for the 2° observer; our Lab white is D65 for the 10°
observer. The conversion maps the 10° white to the sRGB white with a von Kries (CAT02) adaptation,
so L* = 100, a* = b* = 0 is exactly linear sRGB (1, 1, 1).

The white point, the sRGB matrix and the sRGB transfer function are colour-science's, written out or
written in NumPy with the same operations (``tests/model/test_colorimetry.py`` holds them equal to the
last bit; the matrix, whose derivation runs in the CPU's BLAS kernels, to 1e-14 relative), so that this
module costs no more than NumPy: colour-science takes about a second to import, and only
:func:`derive_xyz10_to_linear_srgb` loads it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Observer of every Lab value unless stated: the CIE 1964 10° standard observer.
OBSERVER_10 = "CIE 1964 10 Degree Standard Observer"
#: Chromaticity (x, y) of D65 for the 10° observer, the white of our Lab: colour-science's
#: ``CCS_ILLUMINANTS[OBSERVER_10]["D65"]`` (CIE 15:2004 table T.3), written out so that the Lab formulae
#: load without colour-science; ``tests/model/test_colorimetry.py`` holds the two equal.
WHITEPOINT: NDArray[np.float64] = np.array([0.31382, 0.33100])

#: Rec. 709 luminance weights (ITU-R BT.709-6 item 3.2; the Y row of sRGB's RGB→XYZ, IEC 61966-2-1):
#: Y = 0.2126 R + 0.7152 G + 0.0722 B on linear sRGB; on encoded values the same weights give luma Y′.
#: Read-only.
REC709_LUMINANCE: NDArray[np.float64] = np.array([0.2126, 0.7152, 0.0722])
REC709_LUMINANCE.setflags(write=False)


#: CIE 1976 constants (CIE 15:2004 §8.2.1, exact rationals): ε = (6/29)³, κ = (29/3)³.
_CIE_EPSILON = 216.0 / 24389.0
_CIE_KAPPA = 24389.0 / 27.0


def _white_xyz(whitepoint: ArrayLike) -> NDArray[np.float64]:
    """XYZ of a white of chromaticity (x, y) with Y = 1: (x / y, 1, (1 − x − y) / y)."""
    if whitepoint is WHITEPOINT:
        return _WHITE_XYZ10
    xy = np.asarray(whitepoint, dtype=float)
    x, y = xy[..., 0], xy[..., 1]
    return np.stack([x / y, np.ones_like(x), (1.0 - x - y) / y], axis=-1)


_WHITE_XYZ10 = np.array(
    [WHITEPOINT[0] / WHITEPOINT[1], 1.0, (1.0 - WHITEPOINT[0] - WHITEPOINT[1]) / WHITEPOINT[1]]
)
_WHITE_XYZ10.flags.writeable = False


def lab_to_xyz(lab: ArrayLike, whitepoint: ArrayLike = WHITEPOINT) -> NDArray[np.float64]:
    """Convert Lab to XYZ scaled so the white has Y = 1 (CIE 15:2004 eqs 8.5–8.7, inverted).

    f_y = (L* + 16) / 116, f_x = f_y + a* / 500, f_z = f_y − b* / 200, and each tristimulus ratio is
    f³ where f > 6/29, else (116 f − 16) / κ. Written in NumPy rather than calling
    ``colour.Lab_to_XYZ`` because the formulation solver, the shading of eq 4.3.2 and the booth call
    it in inner loops, where colour-science's per-call overhead (≈ 0.3 ms) dominated
    (docs/adr/0007-numpy-cie-lab.md); ``tests/model/test_colorimetry.py`` holds it to colour-science's
    result to 1e-12.

    Parameters
    ----------
    lab
        CIE L*a*b*, shape (..., 3); L* above 100 (effect paints near specular) is valid.
    whitepoint
        Reference white chromaticity (x, y); default D65 / 10°.

    Returns
    -------
    ndarray
        XYZ, shape (..., 3), Y of the white = 1.

    Examples
    --------
    >>> xyz = lab_to_xyz([[100, 0, 0], [50, 0, 0], [4, 0, 0]])
    >>> round(float(xyz[1, 1]), 12) == round((66 / 116) ** 3, 12), round(float(xyz[2, 1] * 24389 / 27), 12)
    (True, 4.0)
    >>> x, y = WHITEPOINT
    >>> bool(np.allclose(xyz[0], [x / y, 1.0, (1 - x - y) / y], rtol=0, atol=1e-15))
    True
    """
    lab = np.asarray(lab, dtype=float)
    f = np.empty(lab.shape, dtype=float)
    f[..., 1] = (lab[..., 0] + 16.0) / 116.0
    f[..., 0] = f[..., 1] + lab[..., 1] / 500.0
    f[..., 2] = f[..., 1] - lab[..., 2] / 200.0
    ratio = f * f * f
    linear = f <= 6.0 / 29.0
    if linear.any():
        ratio[linear] = (116.0 * f[linear] - 16.0) / _CIE_KAPPA
    ratio *= _white_xyz(whitepoint)
    return ratio


def xyz_to_lab(xyz: ArrayLike, whitepoint: ArrayLike = WHITEPOINT) -> NDArray[np.float64]:
    """Convert XYZ (white Y = 1) to Lab relative to *whitepoint* (CIE 15:2004 eqs 8.5–8.7).

    With t = X / X_n etc., f(t) = t^(1/3) where t > ε, else (κ t + 16) / 116; L* = 116 f_y − 16,
    a* = 500 (f_x − f_y), b* = 200 (f_y − f_z). NumPy for the reason given in :func:`lab_to_xyz`.

    Examples
    --------
    >>> xyz_to_lab(lab_to_xyz([62.0, -4.0, -38.0])).round(9).tolist()
    [62.0, -4.0, -38.0]
    """
    t = np.asarray(xyz, dtype=float) / _white_xyz(whitepoint)
    f = np.where(t > _CIE_EPSILON, np.cbrt(t), (_CIE_KAPPA * t + 16.0) / 116.0)
    return np.stack(
        [116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])], axis=-1
    )


def _adaptation(source_xy: ArrayLike, target_xy: ArrayLike) -> NDArray[np.float64]:
    import colour

    src = colour.xy_to_XYZ(source_xy)
    dst = colour.xy_to_XYZ(target_xy)
    return np.asarray(colour.adaptation.matrix_chromatic_adaptation_VonKries(src, dst, "CAT02"), dtype=float)


def derive_xyz10_to_linear_srgb() -> NDArray[np.float64]:
    """XYZ (D65 / 10°) → linear sRGB from colour-science: its sRGB matrix after a CAT02 von Kries
    adaptation of our white to sRGB's, each row rescaled so that the Lab white maps to exactly (1, 1, 1)
    (colour's sRGB matrix is rounded to 4 decimals, IEC 61966-2-1, which leaves it within 2e-4 of it).

    The product uses this matrix written out (:data:`_XYZ10_TO_LINEAR_SRGB`), so that the display
    pipeline loads without colour-science; ``tests/model/test_colorimetry.py`` holds the two equal to
    1e-14 relative (the last bits of the products and the inverse follow the CPU's BLAS kernel).
    """
    import colour

    srgb = colour.RGB_COLOURSPACES["sRGB"]
    m = srgb.matrix_XYZ_to_RGB @ _adaptation(WHITEPOINT, srgb.whitepoint)
    return np.asarray(m / (m @ colour.xy_to_XYZ(WHITEPOINT))[:, None], dtype=float)


#: :func:`derive_xyz10_to_linear_srgb`, written out (``repr`` of each float: the same bits).
_XYZ10_TO_LINEAR_SRGB = np.array(
    [
        [3.237460306701929, -1.5344050194668877, -0.4985971394945081],
        [-0.9674351850826578, 1.8727349497622694, 0.04145853204383278],
        [0.05564579047013679, -0.20345264096271268, 1.0723578529008377],
    ]
)
_LINEAR_SRGB_TO_XYZ10 = np.linalg.inv(_XYZ10_TO_LINEAR_SRGB)


def lab_to_linear_srgb(lab: ArrayLike) -> NDArray[np.float64]:
    """Convert Lab (D65/10°) to scene-linear sRGB reflectance factors (white = 1, 1, 1).

    Out-of-gamut colours give channel values below 0 or above 1; they are returned as they are so
    the caller decides (the renderer reports them, never clamps silently).

    Examples
    --------
    >>> lab_to_linear_srgb([100, 0, 0]).round(12).tolist()
    [1.0, 1.0, 1.0]
    """
    return lab_to_xyz(lab) @ _XYZ10_TO_LINEAR_SRGB.T


def linear_srgb_to_lab(rgb: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`lab_to_linear_srgb`."""
    return xyz_to_lab(np.asarray(rgb, dtype=float) @ _LINEAR_SRGB_TO_XYZ10.T)


def _spow(a: NDArray[np.float64], p: float) -> NDArray[np.float64]:
    """colour-science's safe power ``spow``: sign(a) |a|^p (a 0-d NaN gives 0), the same operations."""
    a_p = np.sign(a) * np.abs(a) ** p
    return np.zeros_like(a_p) if a_p.ndim == 0 and np.isnan(a_p) else a_p


#: Where the sRGB EOTF leaves its linear segment: colour-science's ``eotf_inverse_sRGB(0.0031308)``.
_SRGB_KNEE_ENCODED = 0.0031308 * 12.92


def srgb_encode(rgb_linear: ArrayLike) -> NDArray[np.float64]:
    """Apply the IEC 61966-2-1 sRGB transfer function (inverse EOTF) to linear values in [0, 1].

    The operations of colour-science's ``eotf_inverse_sRGB``, in NumPy (the same bits:
    ``tests/model/test_colorimetry.py``), so that writing an image does not load colour-science.

    Examples
    --------
    Above the linear segment, 1.055 x^(1/2.4) − 0.055:

    >>> round(float(srgb_encode(0.5)), 6), round(float(srgb_encode(1.0)), 12)
    (0.735357, 1.0)
    """
    lin = np.array(rgb_linear, dtype=float)
    return np.asarray(
        np.where(lin <= 0.0031308, lin * 12.92, 1.055 * _spow(lin, 1 / 2.4) - 0.055), dtype=float
    )


def srgb_decode(rgb_encoded: ArrayLike) -> NDArray[np.float64]:
    """Decode sRGB-encoded values in [0, 1] to linear (the sRGB EOTF; colour-science's ``eotf_sRGB``,
    in NumPy as :func:`srgb_encode` is)."""
    enc = np.array(rgb_encoded, dtype=float)
    return np.asarray(
        np.where(_SRGB_KNEE_ENCODED >= enc, enc / 12.92, _spow((enc + 0.055) / 1.055, 2.4)), dtype=float
    )
