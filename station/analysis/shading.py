"""Panel colour ``c(f, Ω, Ψ)`` under a point light or an environment (thesis eqs 4.3.2–4.3.4).

Definition used throughout (with docs/design.md errata 2 and 3 applied): the model's reference
point-light shading, :func:`station.model.shading.point_light_rgb`.

``c = I · f(L, V) · (L·N)`` (eq 4.3.2; Lambert's term is ``L·N``, erratum 2). ``I·f`` is the paint's
colour: constant for a solid (eq 4.3.3), the clamped-quadratic ``g`` evaluated at the aspecular angle
for an effect paint (eq 4.3.4, face at 15° as in §3.3, erratum 3). The product with the shading factor
is taken in tristimulus space (linear sRGB, a linear map of XYZ), not on Lab numbers, and the result is
turned back into Lab with colour-science. So ``Y' = k·Y`` and ``L*' = 116 f(k·Y/Y_n) − 16``; for a
neutral grey above the linear segment ``ΔL* = (L* + 16)(k^{1/3} − 1)``. The white point cancels, so
no illuminant enters (:func:`station.model.shading.shade_lab` does the same for a Lab colour).

Exposure: ``"reference"`` (default) sets the scene white to a white diffuser on panel A,
``k = max(L·N, 0) / (L·N_A)``: panel A shows the paint's own Lab, the colour a QA engineer measured,
and panel B differs by the shading ratio. ``"absolute"`` uses ``k = max(L·N, 0)`` (white = a diffuser
lit at normal incidence). A surface turned away from the light (``L·N ≤ 0``) is black, ``k = 0``.

Gloss is excluded as in the thesis (§4.3.2 note: highlights need not line up across a seam). With
``gloss=True`` the neutral normalised-Phong lobe of :mod:`station.model.lobe` adds the reflectance
factor ``ρ_s (n+1)/2 · cosⁿ(α)`` on lit panels (α = aspecular angle), not scaled by ``L·N`` (the
K_G lobe of eq 2.3.2; at the mirror direction the irradiance's ``L·N`` cancels the radiance's
``1/cos θ_view``, so this is the peak the gloss meter reads), divided by ``L·N_A`` for the reference
exposure like the rest of the picture.

Environment lighting: an :class:`Environment` is a plain list of sample directions (panel-A frame,
+z = normal) and linear-RGB radiance per sample (solid angle folded in). Each sample is a point light;
the paint's point-light pixel (linear sRGB, gloss lobe optional) is weighted by radiance, summed,
divided per channel by the same sum for a white diffuser on panel A (a von Kries white balance), and
turned back into Lab. The service and the CLI convert
``station.render`` environments into this form; this package never imports the renderer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.analysis.errors import AnalysisInputError
from station.analysis.geometry import aspecular_deg
from station.model.colorimetry import linear_srgb_to_lab
from station.model.shading import point_light_rgb, shade_lab

__all__ = ["Environment", "Exposure", "environment_colour", "point_colour", "shade_lab"]

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

Exposure = Literal["reference", "absolute"]

_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Environment:
    """Environment lighting as plain samples (no renderer types).

    Attributes
    ----------
    directions
        Unit vectors towards each sample, panel-A frame (+z = panel normal), shape (n, 3).
    radiance
        Linear-RGB radiance × solid angle of each sample, shape (n, 3), ≥ 0.
    """

    directions: NDArray[np.float64]
    radiance: NDArray[np.float64]

    def __post_init__(self) -> None:
        d = np.asarray(self.directions, dtype=float)
        r = np.asarray(self.radiance, dtype=float)
        if d.ndim != 2 or d.shape[1] != 3 or d.shape[0] == 0:
            raise AnalysisInputError(
                "environment.directions", "an (n, 3) array of unit vectors, n ≥ 1", getattr(d, "shape", None)
            )
        if r.shape != d.shape:
            raise AnalysisInputError("environment.radiance", f"an array of shape {d.shape}", r.shape)
        if not (np.all(np.isfinite(d)) and np.all(np.isfinite(r))) or np.any(r < 0):
            raise AnalysisInputError("environment.radiance", "finite, non-negative values")
        norms = np.linalg.norm(d, axis=1)
        if np.any(norms < 1e-9):
            raise AnalysisInputError("environment.directions", "non-zero vectors")
        object.__setattr__(self, "directions", d / norms[:, None])
        object.__setattr__(self, "radiance", r)

    @classmethod
    def from_samples(cls, samples: list[tuple[ArrayLike, ArrayLike]]) -> Environment:
        """Build from ``[(direction (3,), rgb (3,)), ...]``."""
        if not samples:
            raise AnalysisInputError("environment", "at least one (direction, rgb) sample", samples)
        return cls(
            np.array([s[0] for s in samples], dtype=float), np.array([s[1] for s in samples], dtype=float)
        )

    @classmethod
    def from_equirect(cls, image: ArrayLike) -> Environment:
        """Build from a small equirectangular linear-RGB array, shape (h, w, 3).

        Row 0 is the zenith (+z, panel A's normal), the last row the nadir; column 0 starts at azimuth 0
        (+x) and azimuth grows towards +y. Each pixel becomes one sample weighted by its solid angle
        ``sin θ · Δθ · Δφ``. Pass a downsampled map (e.g. 16 × 32): the cost is linear in pixels.
        """
        img = np.asarray(image, dtype=float)
        if img.ndim != 3 or img.shape[2] != 3 or img.shape[0] < 2 or img.shape[1] < 2:
            raise AnalysisInputError("environment.image", "an (h, w, 3) array with h, w ≥ 2", img.shape)
        h, w, _ = img.shape
        theta = (np.arange(h) + 0.5) * math.pi / h
        phi = (np.arange(w) + 0.5) * 2.0 * math.pi / w
        tt, pp = np.meshgrid(theta, phi, indexing="ij")
        dirs = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], axis=-1)
        weight = np.sin(tt) * (math.pi / h) * (2.0 * math.pi / w)
        return cls(dirs.reshape(-1, 3), (img * weight[..., None]).reshape(-1, 3))


def _has_gloss(paint: object) -> bool:
    """Whether the paint carries a gloss (GU) for the optional gloss lobe."""
    return bool(getattr(paint, "gloss_gu", None))


def point_colour(
    paint: FaceFlopTravelGloss,
    light: NDArray[np.float64],
    view: NDArray[np.float64],
    normal: NDArray[np.float64],
    *,
    reference_normal: NDArray[np.float64] | None = None,
    exposure: Exposure = "reference",
    gloss: bool = False,
) -> NDArray[np.float64]:
    """Colour ``c`` of a panel with normal(s) *normal* under a point light (eqs 4.3.2–4.3.4), Lab (..., 3).

    *light*, *view*: unit vectors (3,) or broadcastable (..., 3); *normal*: (..., 3). With
    ``exposure="reference"`` the shading is divided by ``L·N_ref`` (*reference_normal*, default +z).
    """
    aspec = aspecular_deg(light, view, normal)
    lambert = np.einsum("...i,...i->...", light, normal)
    if exposure == "reference":
        n_ref = _Z if reference_normal is None else reference_normal
        k_ref = np.einsum("...i,...i->...", light, n_ref)
        if np.any(k_ref <= 0.0):
            raise AnalysisInputError(
                "light", "a light above panel A (L·N_A > 0)", "light at or behind panel A"
            )
        white = np.asarray(k_ref, dtype=float)[..., None]
    elif exposure == "absolute":
        white = np.ones(1)
    else:
        raise AnalysisInputError("exposure", '"reference" or "absolute"', exposure)
    rgb = point_light_rgb(paint, lambert, aspec, specular=gloss and _has_gloss(paint))
    return np.asarray(linear_srgb_to_lab(rgb / white), dtype=float)


def environment_colour(
    paint: FaceFlopTravelGloss,
    env: Environment,
    view: NDArray[np.float64],
    normal: NDArray[np.float64],
    *,
    gloss: bool = False,
) -> NDArray[np.float64]:
    """Colour of a panel with normal(s) *normal* (..., 3) under *env*, seen from *view*; Lab (..., 3).

    Exposure is always "reference": divided per channel by a white diffuser on panel A (+z).
    """
    N = np.asarray(normal, dtype=float)
    L = env.directions  # (S, 3)
    Nb = N[..., None, :]  # (..., 1, 3)
    aspec = aspecular_deg(L, view, Nb)  # (..., S)
    lambert = np.sum(L * Nb, axis=-1)  # (..., S)
    rgb = point_light_rgb(paint, lambert, aspec, specular=gloss and _has_gloss(paint))
    pixel = np.sum(rgb * env.radiance, axis=-2)
    white = np.sum(env.radiance * np.maximum(L[:, 2], 0.0)[:, None], axis=0)
    if np.any(white <= 0):
        raise AnalysisInputError("environment", "some light above panel A in every RGB channel")
    return np.asarray(linear_srgb_to_lab(pixel / white), dtype=float)
