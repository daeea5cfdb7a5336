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
:func:`fftg_from_curve`).

Gloss (``gloss=``): ``"highlight"`` (the default) fits the highlight the art shows: the 60° gloss g whose
rendering of the fitted design reproduces the foreground pixels within 15° of specular, each clipped to
display white as the art is (:func:`fit_highlight_gloss`: least squares in encoded sRGB over g ∈ [0, 100],
a 1-GU grid then a bounded Brent polish). The mapping from the art's highlight to GU is the scene's own
shading, so art rendered at a higher gloss reads a higher gloss (monotone; tests sweep 10–95 GU).
``"contrast"`` is the thesis's eyedropper rule (§3.5.3, :func:`station.design.moodboard.contrast_gloss`:
the brightest minus the darkest 10 % of those pixels, 0–0.5 → 0–100 GU), kept for comparison: it is not
monotone in the art's gloss (a highlight smaller than the brightest tail lowers the contrast as the gloss
rises, and it saturates from about 40 GU). ``"default"`` is 50 GU; ``"fit"`` subtracts each candidate's
highlight before eq 3.7.2 (:data:`GLOSS_CANDIDATES`).

Failure ("the colour gradations do not match the lighting", §3.7.4) is detected when more than 25 % of
the pixels are outliers, the RGB curve leaves the physical range over 15°…θ_clamp, the model refuses the
result, the fit is retroreflective (face darker than flop: what flat fills produce), or the design re-rendered
in the scene misses the art systematically by more than ``max_shading_de`` (RMS ΔE*ab of cell means in
(θ, ϕ) cells, :func:`shading_delta_e`: pixel noise averages out, inconsistent gradations do not). The fit
then returns the average diffuse colour of the changed pixels (albedo = linear colour / (E ϕ)) as a
solid, with ``failed=True`` and the reason.

Environment-lit fit (§3.7.5)
---------------------------
The thesis searched face, flop, travel and gloss with a nonlinear optimiser that rendered the scene
per guess ("several minutes"). The image is linear in the lobe weights (docs/design.md §4), so with the
renderer's per-lobe basis images ``B_j`` the fit is one non-negative least-squares problem per
channel, ``min_w ‖Σ_j w_j B_j − art‖`` (milliseconds), followed by the same curve → design projection.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import binary_erosion
from scipy.optimize import least_squares, nnls

from station.design.errors import DesignInputError, SketchFitError
from station.design.moodboard import contrast_gloss
from station.design.options import GLOSS_MODES
from station.design.scene import LobeBasis, Scene, shade, srgb_decode, srgb_encode
from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.design_io import design_to_dict
from station.model.domain import DEFAULT_GLOSS_GU, SHADING_MISFIT_DE
from station.model.lobe import lobe_reflectance
from station.model.representations import shape_factor

#: Art pixels whose every sRGB-encoded channel exceeds this are "near white" and ignored.
NEAR_WHITE = 0.95
#: Encoded difference above which an art pixel counts as changed (2 code values of 255).
CHANGE_TOLERANCE = 2.0 / 255.0
MIN_PIXELS = 30
TRAVEL_SWEEP = tuple(float(t) for t in range(16, 181))
#: Below this ΔE*ab between face and flop the result is a solid.
SOLID_DE = 0.5
#: Gloss values (GU) tried by ``gloss="fit"``.
GLOSS_CANDIDATES: tuple[float, ...] = (
    0.0,
    2.0,
    5.0,
    10.0,
    15.0,
    20.0,
    30.0,
    40.0,
    50.0,
    60.0,
    70.0,
    80.0,
    90.0,
    100.0,
)
#: Pixels within this aspecular angle (degrees) are the highlight the gloss is read from.
HIGHLIGHT_DEG = 15.0
#: Fewer highlight pixels than this: the gloss is the default (50 GU).
MIN_HIGHLIGHT_PIXELS = 10
#: Rounds of ``gloss="highlight"``: read the gloss off the highlight, refit the colours without it.
HIGHLIGHT_ROUNDS = 2
#: Squared encoded error per channel value below which two gloss values fit the highlight alike.
TIE_SSE = 1e-8
#: Rec. 709 luminance weights of linear sRGB.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
HIGHLIGHT_SIGMAS = 3.0
#: Point fit: residual (linear luminance) below which a pixel is never an outlier.
OUTLIER_FLOOR = 0.01
#: Share of trimmed outlier pixels above which the art is declared inconsistent.
MAX_TRIMMED = 0.25
#: Side of the square tiles of the environment fit's consistency check (pixels).
BLOCK_PX = 4
#: Default failure threshold of the systematic misfit: 3 JND of ΔE*ab (JND = 2.3, thesis §4.3) — a
#: rendering that departs from the art by several just-noticeable differences on average.
MAX_SHADING_DE = SHADING_MISFIT_DE
#: A fitted face darker than the flop by more than this (L*) is retroreflective: a failure unless allowed.
RETRO_TOLERANCE_L = 1.0
#: Cells of the shading-consistency check: aspecular angle (degrees) × Lambert term.
CELL_THETA_DEG, CELL_LAMBERT = 5.0, 0.1


@dataclass(frozen=True)
class SketchFit:
    """Result of a sketch fit.

    Attributes
    ----------
    design : the fitted design (or the fallback solid when ``failed``)
    lab_standard : Lab of the fitted RGB curve at 15°, 45°, 110° (thesis §3.7.3)
    rms_de : RMS ΔE*ab (CIE 1976, the thesis's figure) between the art and the design re-rendered, over
        the fitted pixels (environment fit: between the art and the lobe-weight reconstruction)
    shading_de : systematic part of the misfit, the failure criterion (point fit: :func:`shading_delta_e`
        over aspecular-angle × Lambert cells; environment fit: :func:`block_delta_e` over image tiles)
    failed, reason : failure flag and why (empty when it succeeded)
    theta_clamp_deg : the θ_clamp of the sweep kept (point fit) or of the projection (environment fit)
    pixels : number of pixels fitted
    gloss_source : ``"highlight"``, ``"contrast"``, ``"fit"`` or ``"default"``
    seconds : wall time of the fit
    lighting : what the art was fitted under, in words (environment fit: e.g. "16 point lights from the
        venice_sunset environment"; the environment is discretised into directional lights)
    """

    design: FaceFlopTravelGloss
    lab_standard: tuple[tuple[float, float, float], ...]
    rms_de: float
    shading_de: float
    failed: bool
    reason: str
    theta_clamp_deg: float
    pixels: int
    gloss_source: str
    seconds: float
    lighting: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form shared by every front (plain Python numbers; a failed fit may hold NaN, which
        each front reports its own way)."""
        return {
            "design": design_to_dict(self.design),
            "rms_de": float(self.rms_de),
            "failed": bool(self.failed),
            "seconds": float(self.seconds),
            "reason": self.reason,
            "shading_de": float(self.shading_de),
            "lab_standard": {
                "angles_deg": list(ANGLES_3),
                "lab": [[float(x) for x in v] for v in self.lab_standard],
            },
            "theta_clamp_deg": float(self.theta_clamp_deg),
            "pixels": int(self.pixels),
            "gloss_source": self.gloss_source,
            "lighting": self.lighting,
        }


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


def shading_delta_e(theta: NDArray, phi: NDArray, art_linear: NDArray, fit_linear: NDArray) -> float:
    """Systematic misfit of a shading model: RMS ΔE*ab between the art's and the fit's mean colours in
    cells of (aspecular angle, Lambert term) (5° × 0.1), weighted by pixel count.

    Within a cell the model predicts nearly one colour, so pixel noise averages out of the cell means
    and what remains is the part of the art the lighting cannot explain (flat fills, shading ramps,
    misregistration): the failure criterion of the point-light fit.
    """
    cell = np.floor(theta / CELL_THETA_DEG) * 1000 + np.floor(phi / CELL_LAMBERT)
    _, inv, counts = np.unique(cell, return_inverse=True, return_counts=True)
    mean_a = np.stack([np.bincount(inv, art_linear[:, c]) for c in range(3)], axis=1) / counts[:, None]
    mean_f = np.stack([np.bincount(inv, fit_linear[:, c]) for c in range(3)], axis=1) / counts[:, None]
    lab_a = linear_srgb_to_lab(np.clip(mean_a, 1e-6, None))
    lab_f = linear_srgb_to_lab(np.clip(mean_f, 1e-6, None))
    d2 = np.sum((lab_a - lab_f) ** 2, axis=1)
    return float(np.sqrt(np.sum(counts * d2) / counts.sum()))


def block_delta_e(use: NDArray, art_linear: NDArray, fit_linear: NDArray, block: int = BLOCK_PX) -> float:
    """Systematic misfit over image tiles: RMS ΔE*ab between the art's and the fit's mean colours in
    *block* × *block* pixel tiles (weighted by pixel count) — the environment fit's analogue of
    :func:`shading_delta_e`, where no single aspecular angle indexes a pixel."""
    ys, xs = np.nonzero(use)
    cell = (ys // block) * (use.shape[1] // block + 1) + xs // block
    _, inv, counts = np.unique(cell, return_inverse=True, return_counts=True)
    mean_a = np.stack([np.bincount(inv, art_linear[:, c]) for c in range(3)], axis=1) / counts[:, None]
    mean_f = np.stack([np.bincount(inv, fit_linear[:, c]) for c in range(3)], axis=1) / counts[:, None]
    d2 = np.sum(
        (linear_srgb_to_lab(np.clip(mean_a, 1e-6, None)) - linear_srgb_to_lab(np.clip(mean_f, 1e-6, None)))
        ** 2,
        axis=1,
    )
    return float(np.sqrt(np.sum(counts * d2) / counts.sum()))


def _eroded(mask: NDArray, edge_px: int) -> NDArray:
    if not isinstance(edge_px, (int, np.integer)) or not 0 <= edge_px <= 16:
        raise DesignInputError("edge_px", "integer 0..16 pixels", edge_px)
    return binary_erosion(mask, iterations=edge_px) if edge_px else mask


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


def _lab3(lab: NDArray) -> tuple[float, float, float]:
    L, a, b = (float(v) for v in lab)
    return (L, a, b)


def _design_from_curve(angles: NDArray, lab: NDArray, gloss: float) -> tuple[FaceFlopTravelGloss, float]:
    face, flop, tc, _ = fftg_from_curve(angles, lab)
    if np.linalg.norm(face - flop) < SOLID_DE:
        mean = _lab3(np.mean(lab, axis=0))
        return FaceFlopTravelGloss(mean, mean, None, gloss), tc
    return FaceFlopTravelGloss(_lab3(face), _lab3(flop), tc, gloss), tc


# --------------------------------------------------------------------------------- point-light fit


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
    art_a = _check_art(art, scene.shape, "art")
    init_a = None if initial is None else _check_art(initial, scene.shape, "initial")
    changed = changed_pixels(art_a, init_a, scene.mask)
    near_white = np.min(art_a, axis=-1) > NEAR_WHITE
    use = (
        changed
        & ~near_white
        & (scene.lambert > min_lambert)
        & _eroded(scene.mask, edge_px)
        & (scene.aspecular_deg >= min_aspecular_deg)
    )
    n_all = int(use.sum())
    if n_all < MIN_PIXELS:
        raise SketchFitError(f"only {n_all} usable changed foreground pixels (need {MIN_PIXELS})")
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
        ) @ LUMINANCE
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

    gloss_gu, gloss_source = DEFAULT_GLOSS_GU, "default"
    if gloss == "highlight":  # alternate: highlight gloss of the fitted colours, colours with it removed
        for _ in range(HIGHLIGHT_ROUNDS):
            try:
                trial, _tc = _design_from_curve(
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

    lab_std = tuple(
        _lab3(row) for row in linear_srgb_to_lab(np.clip(_curve(coef, tc, np.array(ANGLES_3)), 1e-6, None))
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
            design, _tc_design = _design_from_curve(
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
    if reason or design is None:
        design, rms, shading_de = _diffuse_fallback(scene, art_a, changed, gloss_gu, use, art_lab)
    return SketchFit(
        design,
        lab_std,
        rms,
        shading_de,
        bool(reason),
        reason,
        float(tc),
        n,
        gloss_source,
        time.perf_counter() - t0,
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

    art_a = _check_art(art, scene.shape, "art")
    sel = (
        scene.mask
        & (scene.aspecular_deg < HIGHLIGHT_DEG)
        & (scene.lambert > min_lambert)
        & _eroded(scene.mask, edge_px)
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
    lab = np.asarray(linear_srgb_to_lab(np.clip(albedo.mean(axis=0), 1e-6, None)), dtype=float)
    colour = _lab3(lab)
    design = FaceFlopTravelGloss(colour, colour, None, gloss_gu)
    fit_lin = shade(scene, design)[use]
    art_lin = srgb_decode(art[use])
    return (
        design,
        rms_delta_e(linear_srgb_to_lab(np.clip(fit_lin, 1e-6, None)), art_lab),
        shading_delta_e(scene.aspecular_deg[use], scene.lambert[use], art_lin, fit_lin),
    )


# ----------------------------------------------------------------------------- environment-lit fit


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
    art_a = _check_art(art, shape, "art")
    init_a = None if initial is None else _check_art(initial, shape, "initial")
    changed = changed_pixels(art_a, init_a, basis.mask)
    use = changed & (np.min(art_a, axis=-1) <= NEAR_WHITE) & _eroded(basis.mask, edge_px)
    n = int(use.sum())
    if n < MIN_PIXELS:
        raise SketchFitError(f"only {n} usable changed foreground pixels (need {MIN_PIXELS})")
    y_all = srgb_decode(art_a[use])  # (n, 3)
    B_all = basis.images[:, use, :]  # (J, n, 3)
    keep = np.ones(n, dtype=bool)
    for _ in range(highlight_rounds + 1):
        y, B = y_all[keep], B_all[:, keep, :]
        w = np.zeros((B.shape[0], 3))
        for c in range(3):
            w[:, c], _ = nnls(B[:, :, c].T, y[:, c], maxiter=50 * B.shape[0])
        # highlights of the unmodelled gloss lobe are positive outliers of the luminance residual
        excess = (y_all - np.einsum("jnc,jc->nc", B_all, w)) @ LUMINANCE
        sigma = 1.4826 * float(np.median(np.abs(excess[keep] - np.median(excess[keep])))) + 1e-6
        new_keep = excess < HIGHLIGHT_SIGMAS * sigma
        if np.array_equal(new_keep, keep) or new_keep.sum() < MIN_PIXELS:
            break
        keep = new_keep
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
        _lab3(row)
        for row in linear_srgb_to_lab(np.clip(basis.lobe_values(np.array(ANGLES_3)) @ w, 1e-6, None))
    )
    reason = ""
    tc = 0.0
    design: FaceFlopTravelGloss | None = None
    lum = rgb @ LUMINANCE
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
            design, tc = _design_from_curve(angles, linear_srgb_to_lab(np.clip(rgb, 1e-6, None)), gloss_gu)
        except ValueError as exc:
            reason = f"model refused the fitted colours: {exc}"
    if reason or design is None:
        diffuse = [j for j, e in enumerate(basis.exponents) if e is None]
        if not diffuse:
            raise SketchFitError("fit failed and the basis has no diffuse lobe for the fallback colour")
        denom = np.clip(B[diffuse[0]].sum(axis=0), 1e-12, None)
        albedo = y.sum(axis=0) / denom
        lab = np.asarray(linear_srgb_to_lab(np.clip(albedo, 1e-6, None)), dtype=float)
        colour = _lab3(lab)
        design = FaceFlopTravelGloss(colour, colour, None, gloss_gu)
        recon = B[diffuse[0]] * albedo
        rms = rms_delta_e(linear_srgb_to_lab(np.clip(recon, 1e-6, None)), art_lab)
        shading_de = block_delta_e(use, y, recon)
    return SketchFit(
        design,
        lab_std,
        rms,
        shading_de,
        bool(reason),
        reason,
        float(tc),
        n,
        "default",
        time.perf_counter() - t0,
        lighting,
    )
