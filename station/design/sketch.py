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

Modules
-------
This module gathers the public names: the result type, thresholds, misfit measures and curve projection
live in :mod:`station.design.sketch_base`, the point-light fit in :mod:`station.design.sketch_lights`,
the environment-lit fit in :mod:`station.design.sketch_environment`.
"""

from __future__ import annotations

from station.design.sketch_base import (
    BLOCK_PX,
    CELL_LAMBERT,
    CELL_THETA_DEG,
    CHANGE_TOLERANCE,
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
    SOLID_DE,
    TIE_SSE,
    TRAVEL_SWEEP,
    SketchFit,
    block_delta_e,
    changed_pixels,
    fftg_from_curve,
    rms_delta_e,
    shading_delta_e,
)
from station.design.sketch_environment import (
    fit_environment,
)
from station.design.sketch_lights import (
    fit_highlight_gloss,
    fit_point_light,
)

__all__ = [
    "BLOCK_PX",
    "CELL_LAMBERT",
    "CELL_THETA_DEG",
    "CHANGE_TOLERANCE",
    "GLOSS_CANDIDATES",
    "HIGHLIGHT_DEG",
    "HIGHLIGHT_ROUNDS",
    "HIGHLIGHT_SIGMAS",
    "MAX_SHADING_DE",
    "MAX_TRIMMED",
    "MIN_HIGHLIGHT_PIXELS",
    "MIN_PIXELS",
    "NEAR_WHITE",
    "OUTLIER_FLOOR",
    "RETRO_TOLERANCE_L",
    "SOLID_DE",
    "TIE_SSE",
    "TRAVEL_SWEEP",
    "SketchFit",
    "block_delta_e",
    "changed_pixels",
    "fftg_from_curve",
    "fit_environment",
    "fit_highlight_gloss",
    "fit_point_light",
    "rms_delta_e",
    "shading_delta_e",
]
