"""Display transform: exposure, tone curve, sRGB encoding (the same formulas as ``tonemap.glsl``).

1. Exposure: linear sRGB radiance × 2^EV.
2. Tone curve, per channel (the thesis's "simple characteristic curve", §2.5.2):
   * ``aces`` (default) — Narkowicz's 2015 fit of the ACES filmic reference rendering transform,
     f(x) = x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14), clipped to [0, 1]; an S-shaped film curve
     that rolls off specular highlights instead of clipping them;
   * ``reinhard`` — x / (1 + x) (Reinhard et al. 2002, eq 3);
   * ``clip`` — no curve, values clipped to [0, 1] (for colorimetric views where nothing exceeds 1).
3. Encoding: the exact piecewise sRGB OETF (IEC 61966-2-1), 12.92x for x ≤ 0.0031308, else
   1.055x^(1/2.4) − 0.055 (:func:`station.model.display.encode_display`, re-exported here as
   ``srgb_encode`` with its inverse ``srgb_decode``), then 8 bits by rounding. The GL shader evaluates
   the power segment as a polynomial within 2.6e-4 of an 8-bit level of it (:data:`SRGB_POLY`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from station.model.display import decode_display as srgb_decode
from station.model.display import encode_display as srgb_encode
from station.render.errors import RenderInputError
from station.render.options import CURVES

__all__ = [
    "CURVES",
    "SRGB_POLY",
    "SRGB_T_OFFSET",
    "SRGB_T_SCALE",
    "check_curve",
    "display_lut",
    "save_png",
    "srgb_decode",
    "srgb_encode",
    "to_display",
    "tone_curve",
]


#: How the GL display transform (``shaders/tonemap.glsl``, ``srgb_encode``) evaluates the OETF's power
#: segment without a power function (llvmpipe pays for ``pow`` with a log2 and an exp2 per channel of
#: every pixel, about 4 % of an orbit frame): x^(1/2.4) = √x · t^(−4/3) with t = x^(1/16) (four square
#: roots), and t^(−4/3) the degree-6 least-squares Chebyshev fit over the segment (x in [0.0031308, 1]),
#: written in powers of u = SRGB_T_SCALE · t + SRGB_T_OFFSET (u in [−1, 1]), lowest first. In float32 it
#: is within 2.6e-4 of an 8-bit level of the exact OETF (``tests/render/test_tonemap_gl.py``, against
#: colour-science). The NumPy display keeps the exact formula.
SRGB_T_SCALE = 6.6092630881104775
SRGB_T_OFFSET = -5.6092630881104775
SRGB_POLY = (
    1.2445040102,
    -0.29582252459,
    0.061528246293,
    -0.012175490833,
    0.0023505028294,
    -0.0004741108415,
    8.9941033508e-05,
)


def check_curve(curve: str) -> str:
    """Validate a tone-curve name."""
    if curve not in CURVES:
        raise RenderInputError("tone_curve", " | ".join(CURVES), curve)
    return curve


def tone_curve(x: np.ndarray, curve: str = "aces") -> np.ndarray:
    """Apply the tone curve to exposed linear values (any shape); result in [0, 1]."""
    check_curve(curve)
    x = np.maximum(x, 0.0)
    if curve == "aces":
        y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
    elif curve == "reinhard":
        y = x / (1.0 + x)
    else:
        y = x
    return np.clip(y, 0.0, 1.0)


def to_display(linear: np.ndarray, exposure_ev: float = 0.0, curve: str = "aces") -> np.ndarray:
    """Linear radiance (..., 3) → 8-bit sRGB (..., 3) uint8: exposure, tone curve, OETF, rounding."""
    if not np.isfinite(exposure_ev) or abs(exposure_ev) > 30:
        raise RenderInputError("exposure_ev", "-30 <= exposure_ev <= 30", exposure_ev)
    y = srgb_encode(tone_curve(np.asarray(linear, dtype=np.float64) * 2.0**exposure_ev, curve))
    return np.round(y * 255.0).astype(np.uint8)


def display_lut(
    exposure_ev: float, curve: str, size: int = 65536, top: float = 16.0
) -> tuple[np.ndarray, float]:
    """(LUT uint8 of `size` entries over exposed values [0, top], index scale) for fast encoding."""
    x = np.linspace(0.0, top, size)
    lut = np.round(srgb_encode(tone_curve(x, curve)) * 255.0).astype(np.uint8)
    return lut, (size - 1) / top * 2.0**exposure_ev


def save_png(path: str | Path, image8: np.ndarray) -> None:
    """Write an (H, W, 3) uint8 image as PNG (Pillow)."""
    from PIL import Image

    Image.fromarray(np.ascontiguousarray(image8)).save(path)
