"""Sketch-based colour styling (thesis §3.7): fit a design to concept art painted over a known scene.

Point-light fit (§3.7.3, eqs 3.7.1–3.7.2)
----------------------------------------
Over the *changed* foreground pixels ``i`` (art differs from the initial image), after the inverse
sRGB transfer ("inverse gamma") and with highlight (θ below ``min_aspecular_deg``), near-white and
unlit pixels removed, solve per channel X ∈ {R, G, B} in least squares::

    θ'_i² ϕ_i a_X + θ'_i ϕ_i b_X + ϕ_i c_X = X_i / E,     θ'_i = min(θ_i, θ_clamp)       (3.7.2)

for every θ_clamp of a sweep (default 16°…180° in 1° steps) and keep the θ_clamp of least error. The
RGB curve is converted to Lab at the standard angles (15°, 45°, 110°) as in the thesis, and to the
face/flop/travel design that best matches the whole curve in Lab (variable projection over travel,
:func:`fftg_from_curve`). Gloss: the contrast-gloss rule (§3.5.3) on the foreground pixels with
θ < 15°, or the default 50 GU.

Failure ("the colour gradations do not match the lighting", §3.7.4) is detected when the RGB curve
leaves the physical range over 15°…θ_clamp, the model refuses the result, or the design re-rendered
in the scene misses the art by more than ``max_rms_de`` (RMS ΔE*ab over the fitted pixels). The fit
then returns the average diffuse colour of the changed pixels (albedo = linear colour / (E ϕ)) as a
solid, with ``failed=True`` and the reason.

Environment-lit fit (§3.7.5)
---------------------------
The thesis searched face, flop, travel and gloss with a nonlinear optimiser that rendered the scene
per guess ("several minutes"). The image is linear in the lobe weights (DESIGN.md §4), so with the
renderer's per-lobe basis images ``B_j`` the fit is one non-negative least-squares problem per
channel, ``min_w ‖Σ_j w_j B_j − art‖`` (milliseconds), followed by the same curve → design projection.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls

from station.design.errors import DesignInputError, SketchFitError
from station.design.moodboard import contrast_gloss
from station.design.scene import LobeBasis, Scene, shade, srgb_decode
from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.representations import shape_factor

DEFAULT_GLOSS_GU = 50.0
#: Art pixels whose every sRGB-encoded channel exceeds this are "near white" and ignored.
NEAR_WHITE = 0.95
#: Encoded difference above which an art pixel counts as changed (2 code values of 255).
CHANGE_TOLERANCE = 2.0 / 255.0
MIN_PIXELS = 30
TRAVEL_SWEEP = tuple(float(t) for t in range(16, 181))
#: Below this ΔE*ab between face and flop the result is a solid.
SOLID_DE = 0.5


@dataclass(frozen=True)
class SketchFit:
    """Result of a sketch fit.

    Attributes
    ----------
    design : the fitted design (or the fallback solid when ``failed``)
    lab_standard : Lab of the fitted RGB curve at 15°, 45°, 110° (thesis §3.7.3)
    rms_de : RMS ΔE*ab (CIE 1976) between the art and the design re-rendered, over the fitted pixels
        (environment fit: between the art and the lobe-weight reconstruction)
    failed, reason : failure flag and why (empty when it succeeded)
    theta_clamp_deg : the θ_clamp of the sweep kept (point fit) or of the projection (environment fit)
    pixels : number of pixels fitted
    gloss_source : ``"contrast"`` or ``"default"``
    seconds : wall time of the fit
    """

    design: FaceFlopTravelGloss
    lab_standard: tuple[tuple[float, float, float], ...]
    rms_de: float
    failed: bool
    reason: str
    theta_clamp_deg: float
    pixels: int
    gloss_source: str
    seconds: float


def _check_art(art: ArrayLike, shape: tuple[int, int], name: str) -> NDArray[np.float64]:
    a = np.asarray(art, dtype=float)
    if a.shape != (*shape, 3):
        raise DesignInputError(name, f"an sRGB image of shape {(*shape, 3)} (the scene's size)", a.shape)
    if not np.all(np.isfinite(a)) or a.min() < 0.0 or a.max() > 1.0:
        raise DesignInputError(name, "sRGB-encoded values in [0, 1]", "out of range or non-finite")
    return a


def changed_pixels(art: NDArray, initial: NDArray | None, mask: NDArray) -> NDArray[np.bool_]:
    """Foreground pixels the artist changed (any channel differs by more than :data:`CHANGE_TOLERANCE`)."""
    if initial is None:
        return mask.copy()
    return mask & (np.max(np.abs(art - initial), axis=-1) > CHANGE_TOLERANCE)


def rms_delta_e(lab1: NDArray, lab2: NDArray) -> float:
    """RMS of ΔE*ab (CIE 1976, the thesis's figure) between two ``(n, 3)`` Lab arrays."""
    d = np.linalg.norm(np.asarray(lab1) - np.asarray(lab2), axis=-1)
    return float(np.sqrt(np.mean(d * d))) if d.size else 0.0


# -------------------------------------------------------------------------- curve → FFTG projection


def fftg_from_curve(
    angles_deg: ArrayLike, lab: ArrayLike, travel_sweep: tuple[float, ...] = TRAVEL_SWEEP
) -> tuple[NDArray[np.float64], NDArray[np.float64], float, float]:
    """Best face/flop/travel for a densely sampled Lab curve (least squares in Lab = ΔE*ab).

    For each θ_clamp of *travel_sweep* the model ``X(θ) = flop + (face − flop) s(θ)²`` is linear in face
    and flop (eqs 3.3.1–3.3.10); solve it and keep the θ_clamp of least squared error.
    Returns ``(face, flop, travel_deg, rms_de)``.
    """
    t = np.asarray(angles_deg, dtype=float)
    y = np.asarray(lab, dtype=float)
    best: tuple[float, NDArray, float] | None = None
    for tc in travel_sweep:
        w = shape_factor(t, tc)
        A = np.stack([w, 1.0 - w], axis=1)
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        sse = float(np.sum((A @ coef - y) ** 2))
        if best is None or sse < best[0] - 1e-12:
            best = (sse, coef, tc)
    if best is None:
        raise DesignInputError("travel_sweep", "at least one θ_clamp", travel_sweep)
    sse, coef, tc = best
    return coef[0], coef[1], tc, math.sqrt(sse / max(len(t), 1))


def _design_from_curve(angles: NDArray, lab: NDArray, gloss: float) -> tuple[FaceFlopTravelGloss, float]:
    face, flop, tc, _ = fftg_from_curve(angles, lab)
    if np.linalg.norm(face - flop) < SOLID_DE:
        mean = tuple(float(v) for v in np.mean(lab, axis=0))
        return FaceFlopTravelGloss(mean, mean, None, gloss), tc
    return FaceFlopTravelGloss(tuple(face), tuple(flop), tc, gloss), tc  # type: ignore[arg-type]


# --------------------------------------------------------------------------------- point-light fit


def _sweep_quadratic(theta: NDArray, phi: NDArray, y: NDArray, sweep: tuple[float, ...]
                     ) -> tuple[NDArray, float, float]:
    best: tuple[float, NDArray, float] | None = None
    ts = theta / 100.0  # conditioning: coefficients per (100°)^k
    for tc in sweep:
        tp = np.minimum(ts, tc / 100.0)
        A = np.stack([tp * tp * phi, tp * phi, phi], axis=1)  # eq 3.7.2
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        sse = float(np.sum((A @ coef - y) ** 2))
        if best is None or sse < best[0] - 1e-12:
            best = (sse, coef, tc)
    if best is None:
        raise DesignInputError("travel_sweep", "at least one θ_clamp", sweep)
    return best[1], best[2], best[0]


def _curve(coef: NDArray, tc: float, angles: NDArray) -> NDArray:
    tp = np.minimum(angles, tc)[:, None] / 100.0
    return coef[0] * tp * tp + coef[1] * tp + coef[2]


def fit_point_light(
    scene: Scene,
    art: ArrayLike,
    initial: ArrayLike | None = None,
    *,
    min_aspecular_deg: float = 10.0,
    min_lambert: float = 0.05,
    gloss: str = "contrast",
    max_rms_de: float = 8.0,
    travel_sweep: tuple[float, ...] = TRAVEL_SWEEP,
) -> SketchFit:
    """Fit a design to point-lit concept art (thesis §3.7.3; module docstring for the method).

    Parameters
    ----------
    scene
        Buffers of the view the art was painted over (θ in degrees, ϕ, mask, irradiance E).
    art, initial
        sRGB-encoded images in [0, 1], ``(H, W, 3)``; *initial* (the rendering the artist started
        from) selects the changed pixels; ``None`` fits every foreground pixel.
    min_aspecular_deg
        Pixels below this aspecular angle are the highlight and are not fitted (degrees).
    gloss
        ``"contrast"`` (contrast gloss of the foreground pixels with θ < 15°, default 50 GU when fewer
        than 10 such pixels) or ``"default"`` (50 GU).
    max_rms_de
        RMS ΔE*ab above which the fit is declared failed (inconsistent shading).

    Raises
    ------
    DesignInputError
        Images of the wrong shape or range, unknown gloss mode.
    SketchFitError
        Fewer than 30 usable pixels.
    """
    t0 = time.perf_counter()
    if gloss not in ("contrast", "default"):
        raise DesignInputError("gloss", "contrast | default", gloss)
    art_a = _check_art(art, scene.shape, "art")
    init_a = None if initial is None else _check_art(initial, scene.shape, "initial")
    changed = changed_pixels(art_a, init_a, scene.mask)
    near_white = np.min(art_a, axis=-1) > NEAR_WHITE
    use = (changed & ~near_white & (scene.lambert > min_lambert)
           & (scene.aspecular_deg >= min_aspecular_deg))
    n = int(use.sum())
    if n < MIN_PIXELS:
        raise SketchFitError(f"only {n} usable changed foreground pixels (need {MIN_PIXELS})")
    theta, phi = scene.aspecular_deg[use], scene.lambert[use]
    y = srgb_decode(art_a[use]) / scene.irradiance  # inverse gamma
    coef, tc, _ = _sweep_quadratic(theta, phi, y, travel_sweep)

    gloss_gu, gloss_source = DEFAULT_GLOSS_GU, "default"
    if gloss == "contrast":
        low = scene.mask & (scene.aspecular_deg < 15.0)
        if int(low.sum()) >= 10:
            gloss_gu, gloss_source = contrast_gloss(art_a[low]).gloss_gu, "contrast"

    lab_std = tuple(tuple(float(v) for v in row)
                    for row in linear_srgb_to_lab(np.clip(_curve(coef, tc, np.array(ANGLES_3)), 1e-6, None)))
    art_lab = linear_srgb_to_lab(np.clip(y * scene.irradiance, 1e-6, None))

    reason = ""
    hi = max(float(theta.max()), 15.0)
    angles = np.arange(15.0, hi + 1.0, 1.0)
    rgb = _curve(coef, tc, angles)
    design: FaceFlopTravelGloss | None = None
    rms = math.inf
    if np.any(rgb < -0.01) or np.any(rgb > 2.0):
        reason = f"non-physical colour curve (RGB {rgb.min():.3g}..{rgb.max():.3g}): shading inconsistent"
    else:
        try:
            design, tc_design = _design_from_curve(angles, linear_srgb_to_lab(np.clip(rgb, 1e-6, None)), gloss_gu)
            tc = tc_design if not design.is_solid else tc
            fit_lab = linear_srgb_to_lab(np.clip(shade(scene, design)[use], 1e-6, None))
            rms = rms_delta_e(fit_lab, art_lab)
            if rms > max_rms_de:
                reason = f"RMS ΔE*ab {rms:.3g} > {max_rms_de:g}: shading inconsistent with the scene's lighting"
        except ValueError as exc:  # the model refused the colours
            reason = f"model refused the fitted colours: {exc}"
    if reason:
        design, rms = _diffuse_fallback(scene, art_a, changed, gloss_gu, use, art_lab)
    return SketchFit(design, lab_std, rms, bool(reason), reason, float(tc), n, gloss_source,  # type: ignore[arg-type]
                     time.perf_counter() - t0)


def _diffuse_fallback(scene: Scene, art: NDArray, changed: NDArray, gloss_gu: float, use: NDArray,
                      art_lab: NDArray) -> tuple[FaceFlopTravelGloss, float]:
    """Average diffuse colour of the changed pixels (albedo = linear / (E ϕ), ϕ > 0.2) as a solid."""
    sel = changed & (scene.lambert > 0.2) & (np.min(art, axis=-1) <= NEAR_WHITE)
    if not sel.any():
        sel = changed & (scene.lambert > 0.0)
    albedo = srgb_decode(art[sel]) / (scene.irradiance * scene.lambert[sel][:, None])
    lab = np.asarray(linear_srgb_to_lab(np.clip(albedo.mean(axis=0), 1e-6, None)), dtype=float)
    colour = tuple(float(v) for v in lab)
    design = FaceFlopTravelGloss(colour, colour, None, gloss_gu)  # type: ignore[arg-type]
    fit_lab = linear_srgb_to_lab(np.clip(shade(scene, design)[use], 1e-6, None))
    return design, rms_delta_e(fit_lab, art_lab)


# ----------------------------------------------------------------------------- environment-lit fit


def fit_environment(
    basis: LobeBasis,
    art: ArrayLike,
    initial: ArrayLike | None = None,
    *,
    gloss_gu: float = DEFAULT_GLOSS_GU,
    max_rms_de: float = 8.0,
    curve_angles: tuple[float, float] = (15.0, 110.0),
) -> SketchFit:
    """Fit a design to environment-lit concept art through per-lobe basis images (§3.7.5, interactive).

    Per channel X: ``w_X = argmin_{w >= 0} ‖B_X w − X_art‖`` over the changed, non-near-white
    foreground pixels (``scipy.optimize.nnls``), where column *j* of ``B_X`` is channel X of basis
    image *j*. The colour curve at aspecular θ (light at the measurement geometry) is
    ``Σ_j w_j f_j(θ)`` with ``f_j`` the lobe's BRDF factor (1 for the diffuse lobe, cos(θ)^E_j for a
    directional-diffuse lobe); it is projected to face/flop/travel over *curve_angles* (degrees) by
    :func:`fftg_from_curve`. Gloss is not in the basis: it is *gloss_gu* (default 50 GU, thesis §3.7.3).

    ``rms_de`` is between the art and the basis reconstruction ``B w`` (what the viewer shows with these
    weights); a fit above *max_rms_de*, or with all weights zero, fails and returns the average diffuse
    colour (``Σ art / Σ B_diffuse``) as a solid.
    """
    t0 = time.perf_counter()
    if basis.images.ndim != 4 or basis.images.shape[-1] != 3:
        raise DesignInputError("basis.images", "(J, H, W, 3) basis images", basis.images.shape)
    shape = basis.images.shape[1:3]
    art_a = _check_art(art, shape, "art")
    init_a = None if initial is None else _check_art(initial, shape, "initial")
    changed = changed_pixels(art_a, init_a, basis.mask)
    use = changed & (np.min(art_a, axis=-1) <= NEAR_WHITE)
    n = int(use.sum())
    if n < MIN_PIXELS:
        raise SketchFitError(f"only {n} usable changed foreground pixels (need {MIN_PIXELS})")
    y = srgb_decode(art_a[use])  # (n, 3)
    B = basis.images[:, use, :]  # (J, n, 3)
    w = np.zeros((B.shape[0], 3))
    for c in range(3):
        w[:, c], _ = nnls(B[:, :, c].T, y[:, c], maxiter=50 * B.shape[0])
    recon = np.einsum("jnc,jc->nc", B, w)
    art_lab = linear_srgb_to_lab(np.clip(y, 1e-6, None))
    rms = rms_delta_e(linear_srgb_to_lab(np.clip(recon, 1e-6, None)), art_lab)
    angles = np.arange(curve_angles[0], curve_angles[1] + 1.0, 1.0)
    rgb = basis.lobe_values(angles) @ w
    lab_std = tuple(tuple(float(v) for v in row)
                    for row in linear_srgb_to_lab(np.clip(basis.lobe_values(np.array(ANGLES_3)) @ w, 1e-6, None)))
    reason = ""
    tc = 0.0
    design: FaceFlopTravelGloss | None = None
    if not np.any(w > 0):
        reason = "all lobe weights are zero"
    elif rms > max_rms_de:
        reason = f"RMS ΔE*ab {rms:.3g} > {max_rms_de:g}: shading inconsistent with the scene's lighting"
    else:
        try:
            design, tc = _design_from_curve(angles, linear_srgb_to_lab(np.clip(rgb, 1e-6, None)), gloss_gu)
        except ValueError as exc:
            reason = f"model refused the fitted colours: {exc}"
    if reason:
        diffuse = [j for j, e in enumerate(basis.exponents) if e is None]
        if not diffuse:
            raise SketchFitError("fit failed and the basis has no diffuse lobe for the fallback colour")
        denom = np.clip(basis.images[diffuse[0], use, :].sum(axis=0), 1e-12, None)
        albedo = y.sum(axis=0) / denom
        lab = np.asarray(linear_srgb_to_lab(np.clip(albedo, 1e-6, None)), dtype=float)
        colour = tuple(float(v) for v in lab)
        design = FaceFlopTravelGloss(colour, colour, None, gloss_gu)  # type: ignore[arg-type]
        recon = basis.images[diffuse[0], use, :] * albedo
        rms = rms_delta_e(linear_srgb_to_lab(np.clip(recon, 1e-6, None)), art_lab)
    return SketchFit(design, lab_std, rms, bool(reason), reason, float(tc), n, "default",  # type: ignore[arg-type]
                     time.perf_counter() - t0)
