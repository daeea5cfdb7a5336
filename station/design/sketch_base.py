"""Shared parts of the sketch fits (thesis §3.7): the result type, the thresholds, pixel selection, the
misfit measures and the colour-curve → face/flop/travel projection (eqs 3.3.1–3.3.10).

The method is described in :mod:`station.design.sketch`; the fits themselves are
:mod:`station.design.sketch_lights` (point light, §3.7.3) and :mod:`station.design.sketch_environment`
(environment-lit, §3.7.5).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import binary_erosion

from station.design.errors import DesignInputError
from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.design_io import design_to_dict
from station.model.domain import SHADING_MISFIT_DE
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


def check_art(art: ArrayLike, shape: tuple[int, int], name: str) -> NDArray[np.float64]:
    """*art* as an ``(H, W, 3)`` float array of sRGB-encoded values in [0, 1] (*shape* is ``(H, W)``);
    :class:`DesignInputError` naming *name* otherwise."""
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


def eroded(mask: NDArray, edge_px: int) -> NDArray:
    """*mask* eroded by *edge_px* pixels (an integer 0..16; :class:`DesignInputError` otherwise)."""
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


def lab3(lab: NDArray) -> tuple[float, float, float]:
    """A Lab triple of plain floats."""
    L, a, b = (float(v) for v in lab)
    return (L, a, b)


def design_from_curve(angles: NDArray, lab: NDArray, gloss: float) -> tuple[FaceFlopTravelGloss, float]:
    """The design of :func:`fftg_from_curve` for a Lab curve at *angles* (degrees) with *gloss* (GU), a
    solid of the curve's mean when face and flop are within :data:`SOLID_DE`; and the θ_clamp kept."""
    face, flop, tc, _ = fftg_from_curve(angles, lab)
    if np.linalg.norm(face - flop) < SOLID_DE:
        mean = lab3(np.mean(lab, axis=0))
        return FaceFlopTravelGloss(mean, mean, None, gloss), tc
    return FaceFlopTravelGloss(lab3(face), lab3(flop), tc, gloss), tc


def solid_design(albedo: NDArray, gloss: float) -> FaceFlopTravelGloss:
    """The solid design of a linear-sRGB *albedo* ``(3,)`` (clipped at 1e-6 before CIELAB, D65) with
    *gloss* (GU): the fallback colour of a failed sketch fit."""
    colour = lab3(np.asarray(linear_srgb_to_lab(np.clip(albedo, 1e-6, None)), dtype=float))
    return FaceFlopTravelGloss(colour, colour, None, gloss)


#: A failed fit's fallback: the solid design and its RMS and systematic ΔE*ab against the art.
Fallback = Callable[[], tuple[FaceFlopTravelGloss, float, float]]


def judged_fit(
    verdict: tuple[str, FaceFlopTravelGloss | None],
    misfit: tuple[float, float],
    fallback: Fallback,
    lab_standard: tuple[tuple[float, float, float], ...],
    fitted: tuple[float, int, str],
) -> SketchFit:
    """The :class:`SketchFit` of a judged fit, ``seconds`` left 0 for the caller.

    *verdict* is ``(reason, design)``: why the fit fails (empty when it does not) and the fitted design;
    *misfit* its ``(rms_de, shading_de)`` (ΔE*ab). When there is a reason or no design, *fallback* gives
    the solid design and its misfit instead. *fitted* is ``(theta_clamp_deg, pixels, gloss_source)``.
    """
    reason, design = verdict
    rms, shading_de = misfit
    if reason or design is None:
        design, rms, shading_de = fallback()
    theta_clamp_deg, pixels, gloss_source = fitted
    return SketchFit(
        design,
        lab_standard,
        rms,
        shading_de,
        bool(reason),
        reason,
        float(theta_clamp_deg),
        pixels,
        gloss_source,
        0.0,
    )
