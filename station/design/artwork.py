"""Synthetic concept-art edits and perturbations (thesis §3.7.2, §3.7.4), for tests and benchmarks.

All functions take and return sRGB-encoded images in [0, 1], ``(H, W, 3)``, and are deterministic for
a given ``numpy.random.Generator``. Results are clipped to [0, 1], as an 8-bit paint program would.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import gaussian_filter
from scipy.ndimage import shift as nd_shift

from station.design.errors import DesignInputError


def _img(image: ArrayLike) -> NDArray[np.float64]:
    a = np.asarray(image, dtype=float)
    if a.ndim != 3 or a.shape[-1] != 3:
        raise DesignInputError("image", "an (H, W, 3) image", a.shape)
    return a


def rgb_to_hsv(rgb: ArrayLike) -> NDArray[np.float64]:
    """HSV (hue in [0, 1)) of RGB in [0, 1], vectorised over ``(..., 3)``."""
    rgb = np.asarray(rgb, dtype=float)
    mx, mn = rgb.max(-1), rgb.min(-1)
    d = mx - mn
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    safe = np.where(d > 0, d, 1.0)
    h = (
        np.select(
            [d == 0, mx == r, mx == g],
            [0.0, ((g - b) / safe) % 6.0, (b - r) / safe + 2.0],
            (r - g) / safe + 4.0,
        )
        / 6.0
    )
    s = np.where(mx > 0, d / np.where(mx > 0, mx, 1.0), 0.0)
    return np.stack([h % 1.0, s, mx], axis=-1)


def hsv_to_rgb(hsv: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`rgb_to_hsv`."""
    hsv = np.asarray(hsv, dtype=float)
    h, s, v = hsv[..., 0] * 6.0, hsv[..., 1], hsv[..., 2]
    i = np.floor(h).astype(int) % 6
    f = h - np.floor(h)
    p, q, t = v * (1 - s), v * (1 - s * f), v * (1 - s * (1 - f))
    choices = [np.stack(c, -1) for c in ((v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q))]
    out = np.zeros_like(hsv)
    for k, c in enumerate(choices):
        out = np.where((i == k)[..., None], c, out)
    return out


def rotate_hue(image: ArrayLike, degrees: float, mask: ArrayLike | None = None) -> NDArray[np.float64]:
    """Rotate the hue of the (masked) pixels by *degrees* in HSV, like a paint program's hue slider."""
    img = _img(image)
    hsv = rgb_to_hsv(img)
    hsv[..., 0] = (hsv[..., 0] + degrees / 360.0) % 1.0
    out = hsv_to_rgb(hsv)
    if mask is not None:
        out = np.where(np.asarray(mask, dtype=bool)[..., None], out, img)
    return np.clip(out, 0.0, 1.0)


def add_noise(image: ArrayLike, sigma: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """Add Gaussian noise of standard deviation *sigma* (encoded units) to every pixel."""
    img = _img(image)
    return np.clip(img + rng.normal(0.0, sigma, img.shape), 0.0, 1.0)


def blur(image: ArrayLike, sigma_px: float) -> NDArray[np.float64]:
    """Gaussian blur of *sigma_px* pixels (the object's edge bleeds into the background and back)."""
    img = _img(image)
    if sigma_px <= 0:
        return img.copy()
    return np.clip(gaussian_filter(img, sigma=(sigma_px, sigma_px, 0), mode="nearest"), 0.0, 1.0)


def misregister(image: ArrayLike, dx: float, dy: float, background: float = 0.0) -> NDArray[np.float64]:
    """Shift the art by (*dx*, *dy*) pixels against the scene (a scan aligned imperfectly)."""
    img = _img(image)
    return np.clip(nd_shift(img, (dy, dx, 0), order=1, mode="constant", cval=background), 0.0, 1.0)


def flatten_shading(image: ArrayLike, amount: float, mask: ArrayLike) -> NDArray[np.float64]:
    """Non-physical shading: blend the masked pixels towards their mean colour by *amount* (0–1), as
    a flat marker fill does; the gradation no longer follows the lighting."""
    img = _img(image)
    m = np.asarray(mask, dtype=bool)
    mean = img[m].mean(axis=0)
    out = img.copy()
    out[m] = (1.0 - amount) * img[m] + amount * mean
    return out


def shading_ramp(image: ArrayLike, amount: float, mask: ArrayLike) -> NDArray[np.float64]:
    """Non-physical shading: multiply the masked pixels by a left-to-right ramp ``1 ± amount``."""
    img = _img(image)
    w = img.shape[1]
    ramp = 1.0 + amount * (np.linspace(-1.0, 1.0, w))[None, :, None]
    m = np.asarray(mask, dtype=bool)[..., None]
    return np.clip(np.where(m, img * ramp, img), 0.0, 1.0)


def posterise(image: ArrayLike, levels: int) -> NDArray[np.float64]:
    """Quantise to *levels* levels per channel (marker strokes)."""
    img = _img(image)
    return np.round(img * (levels - 1)) / (levels - 1)
