"""Panel colour ``c(f, Ω, Ψ)`` under a point light or an environment (thesis eqs 4.3.2–4.3.4).

Definition used throughout (with DESIGN.md §7 errata 2 and 3 applied):

``c = I · f(L, V) · (L·N)`` (eq 4.3.2; Lambert's term is ``L·N``, erratum 2). ``I·f`` is the paint's
colour: constant for a solid (eq 4.3.3), the clamped-quadratic ``g`` evaluated at the aspecular angle
for an effect paint (eq 4.3.4, face at 15° as in §3.3, erratum 3). The product with the shading factor
is taken in tristimulus space, not on Lab numbers: the paint's Lab is turned into ``XYZ / XYZ_white``,
each component is multiplied by the shading factor ``k`` and the result is turned back into Lab with
the CIE function ``f`` (cube root above (6/29)³, linear below). So ``Y' = k·Y`` and
``L*' = 116 f(k·Y/Y_n) − 16``; for a neutral grey above the linear segment
``ΔL* = (L* + 16)(k^{1/3} − 1)``. The white point cancels, so no illuminant enters.

Exposure: ``"reference"`` (default) sets the scene white to a white diffuser on panel A,
``k = max(L·N, 0) / (L·N_A)``: panel A shows the paint's own Lab, the colour a QA engineer measured,
and panel B differs by the shading ratio. ``"absolute"`` uses ``k = max(L·N, 0)`` (white = a diffuser
lit at normal incidence). A surface turned away from the light (``L·N ≤ 0``) is black, ``k = 0``.

Gloss is excluded as in the thesis (§4.3.2 note: highlights need not line up across a seam). With
``gloss=True`` the neutral normalised-Phong lobe of :func:`station.model.gloss.lobe_from_gloss`
(``ρ_s (n+1)/(2π) cosⁿψ`` of the reflected flux) adds ``ρ_s (n+1)/2 · cosⁿ(α)`` to the reflectance
factor before shading (α = aspecular angle; the 1/cos θ_view foreshortening is left out).

Environment lighting: an :class:`Environment` is a plain list of sample directions (panel-A frame,
+z = normal) and linear-RGB radiance per sample (solid angle folded in). Each sample is a point light;
the paint's Lab at each sample's aspecular angle is turned into linear sRGB reflectance, weighted by
radiance and ``max(L·N, 0)``, summed, divided per channel by the same sum for a white diffuser on panel A
(a von Kries white balance), and turned back into Lab. The service and the CLI convert
``station.render`` environments into this form; this package never imports the renderer.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.analysis.errors import AnalysisInputError
from station.analysis.geometry import aspecular_deg

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

Exposure = Literal["reference", "absolute"]

_Z = np.array([0.0, 0.0, 1.0])
_DELTA = 6.0 / 29.0
_DELTA3 = _DELTA**3
_3DELTA2 = 3.0 * _DELTA**2


def cie_f(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """CIE 1976 ``f``: cube root above (6/29)³, linear ``t/(3δ²) + 4/29`` below (defined for t ≤ 0 too)."""
    return np.where(t > _DELTA3, np.cbrt(np.maximum(t, _DELTA3)), t / _3DELTA2 + 4.0 / 29.0)


def cie_f_inverse(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Inverse of :func:`cie_f`."""
    return np.where(u > _DELTA, u**3, _3DELTA2 * (u - 4.0 / 29.0))


def lab_to_relative_xyz(lab: ArrayLike) -> NDArray[np.float64]:
    """Lab → ``(X/X_n, Y/Y_n, Z/Z_n)`` (white-relative tristimulus), shape (..., 3)."""
    lab = np.asarray(lab, dtype=float)
    f = np.empty(lab.shape)
    f[..., 1] = (lab[..., 0] + 16.0) / 116.0
    f[..., 0] = f[..., 1] + lab[..., 1] / 500.0
    f[..., 2] = f[..., 1] - lab[..., 2] / 200.0
    return cie_f_inverse(f)


def relative_xyz_to_lab(t: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`lab_to_relative_xyz`."""
    f = cie_f(np.asarray(t, dtype=float))
    lab = np.empty(f.shape)
    lab[..., 0] = 116.0 * f[..., 1] - 16.0
    lab[..., 1] = 500.0 * (f[..., 0] - f[..., 1])
    lab[..., 2] = 200.0 * (f[..., 1] - f[..., 2])
    return lab


def shade_lab(lab: ArrayLike, k: ArrayLike, add: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Scale a colour's tristimulus values by the shading factor *k* (eq 4.3.2), returning Lab.

    Parameters
    ----------
    lab
        Paint colour, CIE Lab, shape (..., 3).
    k
        Shading factor(s) ≥ 0, broadcast against ``lab[..., 0]``.
    add
        Neutral reflectance factor added to X/X_n, Y/Y_n, Z/Z_n before shading (the optional gloss lobe).
    """
    t = lab_to_relative_xyz(lab)
    if not (np.isscalar(add) and add == 0.0):
        t = t + np.asarray(add, dtype=float)[..., None]
    return relative_xyz_to_lab(t * np.asarray(k, dtype=float)[..., None])


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


def gloss_reflectance(
    paint: FaceFlopTravelGloss, aspec_deg: NDArray[np.float64]
) -> NDArray[np.float64] | float:
    """Neutral reflectance factor of the paint's gloss lobe at *aspec_deg* (normalised Phong), or 0."""
    gloss_gu = getattr(paint, "gloss_gu", None)
    if not gloss_gu:
        return 0.0
    n, albedo = _phong_lobe(float(gloss_gu))
    cos = np.cos(np.radians(np.minimum(aspec_deg, 90.0)))
    return albedo * (n + 1.0) / 2.0 * np.maximum(cos, 0.0) ** n


@functools.lru_cache(maxsize=256)
def _phong_lobe(gloss_gu: float) -> tuple[float, float]:
    """(Phong exponent, specular albedo) of :func:`station.model.gloss.lobe_from_gloss`, cached (it
    simulates the gloss meter, milliseconds per call)."""
    from station.model.gloss import lobe_from_gloss

    lobe = lobe_from_gloss(gloss_gu)
    return float(lobe.phong_exponent), float(lobe.specular_albedo)


def paint_lab(paint: FaceFlopTravelGloss, aspec_deg: ArrayLike) -> NDArray[np.float64]:
    """The paint's Lab at aspecular angle(s) in degrees (``FaceFlopTravelGloss.lab_at``), shape (..., 3)."""
    a = np.asarray(aspec_deg, dtype=float)
    return np.asarray(paint.lab_at(a), dtype=float).reshape(*a.shape, 3)


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
    lab = paint_lab(paint, aspec)
    k = np.maximum(np.einsum("...i,...i->...", light, normal), 0.0)
    if exposure == "reference":
        n_ref = _Z if reference_normal is None else reference_normal
        k_ref = np.einsum("...i,...i->...", light, n_ref)
        if np.any(k_ref <= 0.0):
            raise AnalysisInputError(
                "light", "a light above panel A (L·N_A > 0)", "light at or behind panel A"
            )
        k = k / k_ref
    elif exposure != "absolute":
        raise AnalysisInputError("exposure", '"reference" or "absolute"', exposure)
    add = gloss_reflectance(paint, aspec) if gloss else 0.0
    return shade_lab(lab, k, add)


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
    from station.model.colorimetry import lab_to_linear_srgb, linear_srgb_to_lab

    N = np.asarray(normal, dtype=float)
    L = env.directions  # (S, 3)
    Nb = N[..., None, :]  # (..., 1, 3)
    aspec = aspecular_deg(L, view, Nb)  # (..., S)
    lab = paint_lab(paint, aspec)
    if gloss:
        lab = shade_lab(lab, np.ones(aspec.shape), gloss_reflectance(paint, aspec))
    rgb = lab_to_linear_srgb(lab)  # (..., S, 3)
    cos = np.maximum(np.sum(L * Nb, axis=-1), 0.0)[..., None]  # (..., S, 1)
    pixel = np.sum(rgb * env.radiance * cos, axis=-2)
    white = np.sum(env.radiance * np.maximum(L[:, 2], 0.0)[:, None], axis=0)
    if np.any(white <= 0):
        raise AnalysisInputError("environment", "some light above panel A in every RGB channel")
    return np.asarray(linear_srgb_to_lab(pixel / white), dtype=float)
