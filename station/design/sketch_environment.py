"""The environment-lit sketch fit (thesis §3.7.5): the method is described in :mod:`station.design.sketch`.

:func:`fit_environment` solves non-negative least squares of the art over per-lobe basis images with
the gloss highlights trimmed (:func:`_lobe_weights`), projects the colour curve to a design and judges it
(:func:`_environment_verdict`), falling back to the average diffuse colour (:func:`_diffuse_solid`).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls

from station.design.errors import DesignInputError, SketchFitError
from station.design.scene import LobeBasis, srgb_decode
from station.design.sketch_base import (
    HIGHLIGHT_SIGMAS,
    MAX_SHADING_DE,
    MIN_PIXELS,
    NEAR_WHITE,
    SketchFit,
    block_delta_e,
    changed_pixels,
    check_art,
    design_from_curve,
    eroded,
    judged_fit,
    lab3,
    rms_delta_e,
    solid_design,
)
from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.colorimetry import REC709_LUMINANCE, linear_srgb_to_lab
from station.model.domain import DEFAULT_GLOSS_GU


def fit_environment(
    basis: LobeBasis,
    art: ArrayLike,
    initial: ArrayLike | None = None,
    *,
    gloss_gu: float = DEFAULT_GLOSS_GU,
    max_shading_de: float = MAX_SHADING_DE,
    curve_angles: tuple[float, float] = (15.0, 110.0),
    highlight_rounds: int = 3,
    edge_px: int = 1,
    allow_retroreflective: bool = False,
    lighting: str = "",
) -> SketchFit:
    """Fit a design to environment-lit concept art through per-lobe basis images (§3.7.5, interactive).

    Per channel X: ``w_X = argmin_{w >= 0} ‖B_X w − X_art‖`` over the changed, non-near-white
    foreground pixels (``scipy.optimize.nnls``), where column *j* of ``B_X`` is channel X of basis
    image *j*. The gloss lobe is not in the basis, so its highlights are discounted robustly: up to
    *highlight_rounds* times, pixels whose luminance exceeds the fit by more than 3 robust standard
    deviations (1.4826 × MAD) are dropped and the weights refitted. The colour curve at aspecular θ (light at the measurement geometry) is
    ``Σ_j w_j f_j(θ)`` with ``f_j`` the lobe's BRDF factor (1 for the diffuse lobe, cos(θ)^E_j for a
    directional-diffuse lobe); it is projected to face/flop/travel over *curve_angles* (degrees) by
    :func:`fftg_from_curve`. Gloss is not in the basis: it is *gloss_gu* (default 50 GU, thesis §3.7.3).

    ``rms_de`` is between the art and the basis reconstruction ``B w`` (what the viewer shows with these
    weights). A systematic misfit (:func:`block_delta_e`, 4 × 4 pixel tiles) above *max_shading_de*, or
    all weights zero, fails and returns the average diffuse colour (``Σ art / Σ B_diffuse``) as a solid.
    Pixels within *edge_px* of the silhouette are not fitted. A curve darker at 15° than at the far end
    is a failure unless *allow_retroreflective*. *lighting* says what the basis images were lit with
    (e.g. "16 point lights from the sky environment"), reported in the result's ``lighting``.
    """
    t0 = time.perf_counter()
    if basis.images.ndim != 4 or basis.images.shape[-1] != 3:
        raise DesignInputError("basis.images", "(J, H, W, 3) basis images", basis.images.shape)
    shape = basis.images.shape[1:3]
    art_a = check_art(art, shape, "art")
    init_a = None if initial is None else check_art(initial, shape, "initial")
    changed = changed_pixels(art_a, init_a, basis.mask)
    use = changed & (np.min(art_a, axis=-1) <= NEAR_WHITE) & eroded(basis.mask, edge_px)
    n = int(use.sum())
    if n < MIN_PIXELS:
        raise SketchFitError(f"only {n} usable changed foreground pixels (need {MIN_PIXELS})")
    y_all = srgb_decode(art_a[use])  # (n, 3)
    B_all = basis.images[:, use, :]  # (J, n, 3)
    w, keep = _lobe_weights(y_all, B_all, highlight_rounds)
    y, B = y_all[keep], B_all[:, keep, :]
    n = int(keep.sum())
    sub = np.zeros_like(use)
    sub[use] = keep
    use = sub
    recon = np.einsum("jnc,jc->nc", B, w)
    art_lab = linear_srgb_to_lab(np.clip(y, 1e-6, None))
    rms = rms_delta_e(linear_srgb_to_lab(np.clip(recon, 1e-6, None)), art_lab)
    shading_de = block_delta_e(use, y, recon)
    angles = np.arange(curve_angles[0], curve_angles[1] + 1.0, 1.0)
    rgb = basis.lobe_values(angles) @ w
    lab_std = tuple(
        lab3(row)
        for row in linear_srgb_to_lab(np.clip(basis.lobe_values(np.array(ANGLES_3)) @ w, 1e-6, None))
    )
    reason, design, tc = _environment_verdict(
        angles, rgb, w, shading_de, gloss_gu, max_shading_de, allow_retroreflective
    )
    fit = judged_fit(
        (reason, design),
        (rms, shading_de),
        lambda: _diffuse_solid(basis, B, y, use, art_lab, gloss_gu),
        lab_std,
        (tc, n, "default"),
    )
    return dataclasses.replace(fit, seconds=time.perf_counter() - t0, lighting=lighting)


def _lobe_weights(y_all: NDArray, B_all: NDArray, highlight_rounds: int) -> tuple[NDArray, NDArray]:
    """Non-negative lobe weights ``(J, 3)`` of the art *y_all* ``(n, 3)`` (linear sRGB) over the basis
    images *B_all* ``(J, n, 3)``, per channel (``scipy.optimize.nnls``), refitted up to
    *highlight_rounds* times without the pixels brighter than the fit by more than
    :data:`HIGHLIGHT_SIGMAS` robust standard deviations of the luminance residual (the unmodelled gloss
    lobe). Returns the weights and the mask of the pixels kept."""
    n = len(y_all)
    keep = np.ones(n, dtype=bool)
    for _ in range(highlight_rounds + 1):
        y, B = y_all[keep], B_all[:, keep, :]
        w = np.zeros((B.shape[0], 3))
        for c in range(3):
            w[:, c], _ = nnls(B[:, :, c].T, y[:, c], maxiter=50 * B.shape[0])
        # highlights of the unmodelled gloss lobe are positive outliers of the luminance residual
        excess = (y_all - np.einsum("jnc,jc->nc", B_all, w)) @ REC709_LUMINANCE
        sigma = 1.4826 * float(np.median(np.abs(excess[keep] - np.median(excess[keep])))) + 1e-6
        new_keep = excess < HIGHLIGHT_SIGMAS * sigma
        if np.array_equal(new_keep, keep) or new_keep.sum() < MIN_PIXELS:
            break
        keep = new_keep
    return w, keep


def _environment_verdict(
    angles: NDArray,
    rgb: NDArray,
    w: NDArray,
    shading_de: float,
    gloss_gu: float,
    max_shading_de: float,
    allow_retroreflective: bool,
) -> tuple[str, FaceFlopTravelGloss | None, float]:
    """Why the environment fit fails (empty when it does not), the design of its colour curve *rgb*
    (linear sRGB at *angles*, degrees) with *gloss_gu*, and the θ_clamp of the projection."""
    reason = ""
    tc = 0.0
    design: FaceFlopTravelGloss | None = None
    lum = rgb @ REC709_LUMINANCE
    if not np.any(w > 0):
        reason = "all lobe weights are zero"
    elif not allow_retroreflective and lum[0] < lum[-1] * (1.0 - 1e-3):
        reason = "retroreflective fit (darker near specular than far from it): flat or inconsistent shading"
    elif shading_de > max_shading_de:
        reason = (
            f"systematic ΔE*ab {shading_de:.3g} > {max_shading_de:g}: "
            "shading inconsistent with the scene's lighting"
        )
    else:
        try:
            design, tc = design_from_curve(angles, linear_srgb_to_lab(np.clip(rgb, 1e-6, None)), gloss_gu)
        except ValueError as exc:
            reason = f"model refused the fitted colours: {exc}"
    return reason, design, tc


def _diffuse_solid(
    basis: LobeBasis, B: NDArray, y: NDArray, use: NDArray, art_lab: NDArray, gloss_gu: float
) -> tuple[FaceFlopTravelGloss, float, float]:
    """The fallback of a failed environment fit: the average diffuse colour ``Σ art / Σ B_diffuse`` as a
    solid, with its RMS and systematic (:func:`block_delta_e`) ΔE*ab against the art."""
    diffuse = [j for j, e in enumerate(basis.exponents) if e is None]
    if not diffuse:
        raise SketchFitError("fit failed and the basis has no diffuse lobe for the fallback colour")
    denom = np.clip(B[diffuse[0]].sum(axis=0), 1e-12, None)
    albedo = y.sum(axis=0) / denom
    design = solid_design(albedo, gloss_gu)
    recon = B[diffuse[0]] * albedo
    rms = rms_delta_e(linear_srgb_to_lab(np.clip(recon, 1e-6, None)), art_lab)
    shading_de = block_delta_e(use, y, recon)
    return design, rms, shading_de
