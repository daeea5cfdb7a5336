"""The point-light sketch fit (thesis §3.7.3, eqs 3.7.1–3.7.2): the method is described in
:mod:`station.design.sketch`.

:func:`fit_point_light` selects the usable pixels, solves eq 3.7.2 over a θ_clamp sweep with robust
trimming (:func:`_robust_sweep`), reads the gloss (:func:`_choose_gloss`), projects the colour curve to a
design and judges it (:func:`_point_result`), falling back to the average diffuse colour.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from station.design.errors import DesignInputError, SketchFitError
from station.design.moodboard import contrast_gloss
from station.design.options import GLOSS_MODES
from station.design.scene import Scene, shade, srgb_decode, srgb_encode
from station.design.sketch_base import (
    GLOSS_CANDIDATES,
    HIGHLIGHT_DEG,
    HIGHLIGHT_ROUNDS,
    HIGHLIGHT_SIGMAS,
    MAX_SHADING_DE,
    MAX_TRIMMED,
    MIN_HIGHLIGHT_PIXELS,
    MIN_PIXELS,
    NEAR_WHITE,
    OUTLIER_FLOOR,
    RETRO_TOLERANCE_L,
    TIE_SSE,
    TRAVEL_SWEEP,
    SketchFit,
    changed_pixels,
    check_art,
    design_from_curve,
    eroded,
    judged_fit,
    lab3,
    rms_delta_e,
    shading_delta_e,
    solid_design,
)
from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.colorimetry import REC709_LUMINANCE, linear_srgb_to_lab
from station.model.domain import DEFAULT_GLOSS_GU
from station.model.lobe import lobe_reflectance


def _sweep_quadratic(
    theta: NDArray, phi: NDArray, y: NDArray, sweep: tuple[float, ...]
) -> tuple[NDArray, float, float]:
    """Least squares of eq 3.7.2 for every θ_clamp of *sweep*; return (coefficients, θ_clamp, SSE).

    Normal equations from prefix sums over the pixels sorted by θ: below θ_clamp a pixel contributes
    its own θ'^k, above it θ_clamp^k, so each θ_clamp costs O(1) after an O(n log n) sort.
    Coefficients are per (100°)^k for conditioning.
    """
    order = np.argsort(theta)
    ts, p, yy = theta[order] / 100.0, phi[order], y[order]
    p2 = p * p
    # prefix sums (with a leading zero) of ϕ² θ^k (k = 0..4) and ϕ θ^k y (k = 0..2)
    pw = np.stack([p2 * ts**k for k in range(5)], axis=1)
    py = np.stack([(p * ts**k)[:, None] * yy for k in range(3)], axis=1)  # (n, 3, channels)
    cpw = np.vstack([np.zeros((1, 5)), np.cumsum(pw, axis=0)])
    cpy = np.concatenate([np.zeros((1, 3, yy.shape[1])), np.cumsum(py, axis=0)])
    tot_p2, tot_py = cpw[-1, 0], cpy[-1, 0]
    yty = float(np.sum(yy * yy))
    best: tuple[float, NDArray, float] | None = None
    for tc in sweep:
        c = tc / 100.0
        m = int(np.searchsorted(ts, c, side="left"))  # pixels [0, m) have θ < θ_clamp
        above_p2 = tot_p2 - cpw[m, 0]
        above_py = tot_py - cpy[m, 0]
        s = [cpw[m, k] + above_p2 * c**k for k in range(5)]  # Σ ϕ² θ'^k
        ata = np.array([[s[4], s[3], s[2]], [s[3], s[2], s[1]], [s[2], s[1], s[0]]])
        aty = np.stack([cpy[m, 2] + above_py * c * c, cpy[m, 1] + above_py * c, cpy[m, 0] + above_py])
        try:
            coef = np.linalg.solve(ata, aty)
        except np.linalg.LinAlgError:
            continue
        sse = yty - 2.0 * float(np.sum(coef * aty)) + float(np.sum(coef * (ata @ coef)))
        if best is None or sse < best[0] - 1e-12:
            best = (sse, coef, tc)
    if best is None:
        raise SketchFitError("eq 3.7.2 is singular for every θ_clamp of the sweep (too few distinct angles)")
    return best[1], best[2], max(best[0], 0.0)


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
    gloss: str = "highlight",
    max_shading_de: float = MAX_SHADING_DE,
    travel_sweep: tuple[float, ...] = TRAVEL_SWEEP,
    edge_px: int = 1,
    outlier_rounds: int = 2,
    refine: bool = False,
    allow_retroreflective: bool = False,
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
        ``"highlight"`` (default: the gloss whose rendering reproduces the art's pixels with θ < 15°,
        :func:`fit_highlight_gloss`; 50 GU when fewer than 10 such pixels), ``"contrast"`` (contrast
        gloss of those pixels, the thesis's rule, not monotone in the art's gloss), ``"default"``
        (50 GU), or ``"fit"``: the highlight of
        each gloss in :data:`GLOSS_CANDIDATES` (rendered with the scene shader's specular term) is
        subtracted before eq 3.7.2 and the gloss of least error is kept — an extension of the thesis,
        which did not solve for gloss; it also stops a broad low-gloss highlight from being read as a
        bright face.
    max_shading_de
        Systematic misfit (:func:`shading_delta_e`, ΔE*ab) above which the fit is declared failed
        (inconsistent shading); default 6.9 = 3 JND.
    edge_px
        Pixels within this distance of the silhouette are not fitted (misregistered or blurred art
        puts background there; the thesis masked such areas by hand).
    outlier_rounds
        Rounds of robust trimming: pixels whose luminance residual of eq 3.7.2 is more than 3 robust
        standard deviations (1.4826 × MAD, at least 0.01) from the median are dropped and the sweep
        rerun. More than 25 % trimmed → failed.
    refine
        Polish face, flop and travel by nonlinear least squares in Lab (:func:`_refine`) after the
        linear fit (about 0.25 s more at 64²; on hue-rotated art it lowers the median RMS from about
        0.4 to 0.2 ΔE*ab). Off by default: the thesis's linear method alone.
    allow_retroreflective
        Accept a fit whose face is darker than its flop. Off by default: flat fills (the shading of a
        marker drawing) fit best as "brighter away from specular", which the thesis's system treats as
        rare (§3.5.2) — here it is reported as a failure.

    Raises
    ------
    DesignInputError
        Images of the wrong shape or range, unknown gloss mode.
    SketchFitError
        Fewer than 30 usable pixels.
    """
    t0 = time.perf_counter()
    if gloss not in GLOSS_MODES:
        raise DesignInputError("gloss", " | ".join(GLOSS_MODES), gloss)
    art_a, changed, use = _usable_pixels(scene, art, initial, min_lambert, edge_px, min_aspecular_deg)
    kept, coef, tc, g_fit = _robust_sweep(scene, art_a, use, gloss, travel_sweep, outlier_rounds)
    gloss_gu, source, coef, tc = _choose_gloss(
        gloss, scene, art_a, kept, (coef, tc, g_fit), travel_sweep, edge_px, min_lambert
    )
    checks = (refine, allow_retroreflective, max_shading_de)
    fit = _point_result(scene, art_a, changed, kept, (coef, tc), (gloss_gu, source), checks)
    return dataclasses.replace(fit, seconds=time.perf_counter() - t0)


@dataclass(frozen=True)
class _Kept:
    """The pixels the point-light fit keeps after robust trimming.

    Attributes
    ----------
    use : ``(H, W)`` mask of the kept pixels
    theta, phi : their aspecular angle (degrees) and Lambert term
    y : their linear sRGB over the irradiance E, ``(n, 3)``
    trimmed : share of the usable pixels trimmed as outliers of eq 3.7.2
    """

    use: NDArray[np.bool_]
    theta: NDArray
    phi: NDArray
    y: NDArray
    trimmed: float


def _usable_pixels(
    scene: Scene,
    art: ArrayLike,
    initial: ArrayLike | None,
    min_lambert: float,
    edge_px: int,
    min_aspecular_deg: float,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
    """The art checked, its changed foreground pixels, and those of them that are not near white, lit,
    away from the silhouette and outside the highlight; :class:`SketchFitError` when fewer than
    :data:`MIN_PIXELS`."""
    art_a = check_art(art, scene.shape, "art")
    init_a = None if initial is None else check_art(initial, scene.shape, "initial")
    changed = changed_pixels(art_a, init_a, scene.mask)
    near_white = np.min(art_a, axis=-1) > NEAR_WHITE
    use = (
        changed
        & ~near_white
        & (scene.lambert > min_lambert)
        & eroded(scene.mask, edge_px)
        & (scene.aspecular_deg >= min_aspecular_deg)
    )
    n_all = int(use.sum())
    if n_all < MIN_PIXELS:
        raise SketchFitError(f"only {n_all} usable changed foreground pixels (need {MIN_PIXELS})")
    return art_a, changed, use


def _robust_sweep(
    scene: Scene,
    art_a: NDArray,
    use: NDArray,
    gloss: str,
    travel_sweep: tuple[float, ...],
    outlier_rounds: int,
) -> tuple[_Kept, NDArray, float, float | None]:
    """Eq 3.7.2 over *travel_sweep* with robust trimming (*outlier_rounds* rounds; 3 robust standard
    deviations of the luminance residual, at least :data:`OUTLIER_FLOOR`). With ``gloss="fit"`` or
    ``"highlight"`` each gloss of :data:`GLOSS_CANDIDATES` has its highlight subtracted first and the one
    of least error is kept. Returns the kept pixels, the coefficients, θ_clamp and the gloss fitted."""
    n_all = int(use.sum())
    theta_all, phi_all = scene.aspecular_deg[use], scene.lambert[use]
    y_all = srgb_decode(art_a[use]) / scene.irradiance  # inverse gamma
    keep = np.ones(n_all, dtype=bool)
    candidates: tuple[float | None, ...] = GLOSS_CANDIDATES if gloss in ("fit", "highlight") else (None,)
    spec_all = {g: (np.zeros(n_all) if g is None else lobe_reflectance(g, theta_all)) for g in candidates}
    g_fit: float | None = None
    for _ in range(outlier_rounds + 1):  # robust least squares: trim outliers, refit
        best_g: tuple[float, NDArray, float, float | None] | None = None
        for g in candidates:  # gloss="fit": subtract each candidate's highlight, keep the least error
            yg = y_all[keep] - spec_all[g][keep][:, None]
            coef_g, tc_g, sse_g = _sweep_quadratic(theta_all[keep], phi_all[keep], yg, travel_sweep)
            if best_g is None or sse_g < best_g[0]:
                best_g = (sse_g, coef_g, tc_g, g)
        assert best_g is not None  # noqa: S101 - candidates is never empty
        _, coef, tc, g_fit = best_g
        resid = (
            y_all - spec_all[g_fit][:, None] - phi_all[:, None] * _curve(coef, tc, theta_all)
        ) @ REC709_LUMINANCE
        med = float(np.median(resid[keep]))
        sigma = 1.4826 * float(np.median(np.abs(resid[keep] - med)))
        new_keep = np.abs(resid - med) <= max(HIGHLIGHT_SIGMAS * sigma, OUTLIER_FLOOR)
        if np.array_equal(new_keep, keep) or new_keep.sum() < MIN_PIXELS:
            break
        keep = new_keep
    sub = np.zeros_like(use)
    sub[use] = keep
    use = sub
    theta, phi, y = theta_all[keep], phi_all[keep], y_all[keep]
    n = int(keep.sum())
    trimmed = 1.0 - n / n_all
    return _Kept(use, theta, phi, y, trimmed), coef, tc, g_fit


def _choose_gloss(
    gloss: str,
    scene: Scene,
    art_a: NDArray,
    kept: _Kept,
    curve: tuple[NDArray, float, float | None],
    travel_sweep: tuple[float, ...],
    edge_px: int,
    min_lambert: float,
) -> tuple[float, str, NDArray, float]:
    """The gloss (GU) of mode *gloss* and its source; with ``"highlight"`` the curve ``(coef, θ_clamp)``
    refitted without the highlight read (:data:`HIGHLIGHT_ROUNDS` rounds). *curve* is the sweep's
    ``(coef, θ_clamp, gloss fitted)``. Returns ``(gloss_gu, source, coef, θ_clamp)``."""
    coef, tc, g_fit = curve
    theta, phi, y = kept.theta, kept.phi, kept.y
    gloss_gu, gloss_source = DEFAULT_GLOSS_GU, "default"
    if gloss == "highlight":  # alternate: highlight gloss of the fitted colours, colours with it removed
        for _ in range(HIGHLIGHT_ROUNDS):
            try:
                trial, _tc = design_from_curve(
                    np.arange(15.0, max(float(theta.max()), 15.0) + 1.0, 1.0),
                    linear_srgb_to_lab(
                        np.clip(
                            _curve(coef, tc, np.arange(15.0, max(float(theta.max()), 15.0) + 1.0)), 1e-6, None
                        )
                    ),
                    DEFAULT_GLOSS_GU,
                )
            except ValueError:
                break
            read = fit_highlight_gloss(scene, art_a, trial, edge_px=edge_px, min_lambert=min_lambert)
            if read is None:
                break
            gloss_gu, gloss_source = read, "highlight"
            coef, tc, _sse = _sweep_quadratic(
                theta, phi, y - lobe_reflectance(read, theta)[:, None], travel_sweep
            )
    if gloss == "fit" and g_fit is not None:
        gloss_gu, gloss_source = float(g_fit), "fit"
    elif gloss == "contrast":
        low = scene.mask & (scene.aspecular_deg < 15.0)
        if int(low.sum()) >= 10:
            gloss_gu, gloss_source = contrast_gloss(art_a[low]).gloss_gu, "contrast"
    return gloss_gu, gloss_source, coef, tc


def _point_result(
    scene: Scene,
    art_a: NDArray,
    changed: NDArray,
    kept: _Kept,
    curve: tuple[NDArray, float],
    gloss: tuple[float, str],
    checks: tuple[bool, bool, float],
) -> SketchFit:
    """The design of the curve ``(coef, θ_clamp)`` with gloss ``(GU, source)``, judged (trimmed share,
    physical curve, retroreflection, :func:`shading_delta_e` over *max_shading_de*) and replaced by
    :func:`_diffuse_fallback` when it fails; ``seconds`` is left 0 for the caller. *checks* is
    ``(refine, allow_retroreflective, max_shading_de)`` of :func:`fit_point_light`."""
    coef, tc = curve
    refine, allow_retroreflective, max_shading_de = checks
    gloss_gu, gloss_source = gloss
    theta, phi, y, use, trimmed = kept.theta, kept.phi, kept.y, kept.use, kept.trimmed
    lab_std = tuple(
        lab3(row) for row in linear_srgb_to_lab(np.clip(_curve(coef, tc, np.array(ANGLES_3)), 1e-6, None))
    )
    art_lab = linear_srgb_to_lab(np.clip(y * scene.irradiance, 1e-6, None))

    reason = ""
    hi = max(float(theta.max()), 15.0)
    angles = np.arange(15.0, hi + 1.0, 1.0)
    rgb = _curve(coef, tc, angles)
    design: FaceFlopTravelGloss | None = None
    rms = shading_de = math.inf
    if trimmed > MAX_TRIMMED:
        reason = f"{100 * trimmed:.0f} % of the pixels are outliers of eq 3.7.2: shading inconsistent"
    elif np.any(rgb < -0.01) or np.any(rgb > 2.0):
        reason = f"non-physical colour curve (RGB {rgb.min():.3g}..{rgb.max():.3g}): shading inconsistent"
    else:
        try:
            design, _tc_design = design_from_curve(
                angles, linear_srgb_to_lab(np.clip(rgb, 1e-6, None)), gloss_gu
            )
            if refine and not design.is_solid:
                design = _refine(design, theta, phi, art_lab, scene.irradiance)
            tc = design.travel_deg if design.travel_deg is not None else tc
            fit_lin = shade(scene, design)[use]
            rms = rms_delta_e(linear_srgb_to_lab(np.clip(fit_lin, 1e-6, None)), art_lab)
            shading_de = shading_delta_e(theta, phi, y * scene.irradiance, fit_lin)
            if not allow_retroreflective and design.face[0] < design.flop[0] - RETRO_TOLERANCE_L:
                reason = (
                    f"retroreflective fit (face L* {design.face[0]:.3g} < flop L* {design.flop[0]:.3g}): "
                    "flat or inconsistent shading"
                )
            elif shading_de > max_shading_de:
                reason = (
                    f"systematic ΔE*ab {shading_de:.3g} > {max_shading_de:g}: "
                    "shading inconsistent with the scene's lighting"
                )
        except ValueError as exc:  # the model refused the colours
            reason = f"model refused the fitted colours: {exc}"
    return judged_fit(
        (reason, design),
        (rms, shading_de),
        lambda: _diffuse_fallback(scene, art_a, changed, gloss_gu, use, art_lab),
        lab_std,
        (tc, len(theta), gloss_source),
    )


def fit_highlight_gloss(
    scene: Scene,
    art: ArrayLike,
    design: FaceFlopTravelGloss,
    *,
    edge_px: int = 1,
    min_lambert: float = 0.05,
) -> float | None:
    """The 60° gloss (GU) whose rendering of *design* in *scene* best reproduces the art's highlight.

    Over the foreground pixels with aspecular angle below :data:`HIGHLIGHT_DEG` (lit, away from the
    silhouette by *edge_px*), minimise Σ ‖encode(clip(D + E·g_lobe(θ; g))) − art‖² over g ∈ [0, 100] GU:
    the 1-GU grid's best point, then a bounded Brent search within ±1 GU of it. D is the design's diffuse
    shading (the scene shader without its lobe), g_lobe the lobe of
    :func:`station.model.lobe.lobe_reflectance`. The render is clipped at display white as painted art
    is, so a saturated highlight is read from the pixels around it. Where several gloss values fit
    alike (within :data:`TIE_SSE` per value: a near-white design whose highlight lies wholly in pixels
    clipped at white, which no method can read), the one nearest the default 50 GU is returned. ``None``
    when fewer than
    :data:`MIN_HIGHLIGHT_PIXELS` pixels are in the highlight.
    """
    from scipy.optimize import minimize_scalar

    from station.model.domain import GLOSS_MAX_GU, GLOSS_MIN_GU
    from station.model.shading import point_light_rgb

    art_a = check_art(art, scene.shape, "art")
    sel = (
        scene.mask
        & (scene.aspecular_deg < HIGHLIGHT_DEG)
        & (scene.lambert > min_lambert)
        & eroded(scene.mask, edge_px)
    )
    if int(sel.sum()) < MIN_HIGHLIGHT_PIXELS:
        return None
    target = art_a[sel]
    lam, theta = scene.lambert[sel], scene.aspecular_deg[sel]
    diffuse = point_light_rgb(design, lam, theta, irradiance=scene.irradiance, specular=False)

    def sse(g: float) -> float:
        spec = (scene.irradiance * lobe_reflectance(float(g), theta))[:, None]
        return float(np.sum((srgb_encode(diffuse + spec) - target) ** 2))

    grid = np.arange(GLOSS_MIN_GU, GLOSS_MAX_GU + 0.5, 1.0)
    errors = np.array([sse(g) for g in grid])
    # gloss values the art cannot tell apart (a highlight hidden in pixels clipped at white): the one
    # nearest the default
    tied = np.flatnonzero(errors <= errors.min() + TIE_SSE * target.size)
    best = float(grid[tied[np.argmin(np.abs(grid[tied] - DEFAULT_GLOSS_GU))]])
    if tied.size > 1:
        return best
    lo, hi = max(GLOSS_MIN_GU, best - 1.0), min(GLOSS_MAX_GU, best + 1.0)
    res = minimize_scalar(sse, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    g = float(res.x) if float(res.fun) <= errors.min() else best
    return min(max(g, GLOSS_MIN_GU), GLOSS_MAX_GU)


def _refine(
    design: FaceFlopTravelGloss, theta: NDArray, phi: NDArray, art_lab: NDArray, irradiance: float
) -> FaceFlopTravelGloss:
    """Polish face, flop and travel by nonlinear least squares of the per-pixel Lab residual
    ``Lab(E ϕ rgb(θ)) − Lab(art)`` (scipy ``least_squares``), started from the linear fit."""
    from station.model.colorimetry import lab_to_linear_srgb

    def residual(x: NDArray) -> NDArray:
        face, flop, tc = x[:3], x[3:6], x[6]
        theta_c = np.minimum(theta, tc)
        s2 = ((tc - theta_c) / (tc - 15.0)) ** 2
        lab = flop + (face - flop) * s2[:, None]
        lin = irradiance * phi[:, None] * lab_to_linear_srgb(lab)
        return (linear_srgb_to_lab(np.clip(lin, 1e-6, None)) - art_lab).ravel()

    x0 = np.array([*design.face, *design.flop, design.travel_deg], dtype=float)
    lo = np.array([0, -150, -150, 0, -150, -150, 15.5])
    hi = np.array([200, 150, 150, 200, 150, 150, 180.0])
    res = least_squares(
        residual, np.clip(x0, lo + 1e-9, hi - 1e-9), bounds=(lo, hi), max_nfev=60, x_scale="jac"
    )
    before = float(np.sum(residual(x0) ** 2)) if np.all((x0 >= lo) & (x0 <= hi)) else math.inf
    if not res.success or 2.0 * res.cost >= before:
        return design
    return design.replace(
        face=tuple(float(v) for v in res.x[:3]),
        flop=tuple(float(v) for v in res.x[3:6]),
        travel_deg=float(res.x[6]),
    )


def _diffuse_fallback(
    scene: Scene, art: NDArray, changed: NDArray, gloss_gu: float, use: NDArray, art_lab: NDArray
) -> tuple[FaceFlopTravelGloss, float, float]:
    """Average diffuse colour of the changed pixels (albedo = linear / (E ϕ), ϕ > 0.2) as a solid."""
    sel = changed & (scene.lambert > 0.2) & (np.min(art, axis=-1) <= NEAR_WHITE)
    if not sel.any():
        sel = changed & (scene.lambert > 0.0)
    albedo = srgb_decode(art[sel]) / (scene.irradiance * scene.lambert[sel][:, None])
    design = solid_design(albedo.mean(axis=0), gloss_gu)
    fit_lin = shade(scene, design)[use]
    art_lin = srgb_decode(art[use])
    return (
        design,
        rms_delta_e(linear_srgb_to_lab(np.clip(fit_lin, 1e-6, None)), art_lab),
        shading_delta_e(scene.aspecular_deg[use], scene.lambert[use], art_lin, fit_lin),
    )
