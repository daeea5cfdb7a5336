"""Appearance under a booth illuminant: display colour (CAT16), a design per illuminant, metameric pairs.

Lab under an illuminant is :func:`station.model.spectra.reflectance_to_lab` (ASTM E308 weights through
colour-science, relative to that illuminant's own white, 2° or 10° observer); this module builds on it:

* :func:`display_equivalent_lab` / :func:`lab_to_display_under` — what a D65 display shows of a Lab
  seen under an illuminant, for an observer adapted (fully, or to a degree D) to that illuminant:
  Lab → XYZ relative to the illuminant's white → CAT16 to D65's white (colour-science's von Kries /
  Zhai 2018 adaptation with the CAT16 matrix) → the product's D65 Lab → its display pipeline
  (:mod:`station.model.colorimetry`, :mod:`station.model.display`). Under D65 nothing changes.
* :func:`light_colour` — the booth light's own colour on that display (no adaptation): what the
  environment of a booth render is tinted by.
* :func:`fit_under_illuminant` — the face/flop/travel/gloss design fitted to the Lab per geometry under
  an illuminant (the model hierarchy unchanged: the same :func:`station.model.fit.fit_fftg`);
  :func:`display_design_under` — the design to render: fitted to the display-equivalent Lab.
* :func:`metameric_black` / :func:`metameric_pair` — a spectrum invisible under one illuminant (the null
  space of its weighting factors) and, added to a paint's spectra per geometry, a sample that matches
  the standard under D65 and not under A: the test object of every booth check.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.colorimetry import OBSERVER_10, lab_to_linear_srgb, lab_to_xyz, xyz_to_lab
from station.model.display import encode_display
from station.model.domain import BOOTH_SHAPES, REFLECTANCE_MAX, check_ranged
from station.model.errors import ModelInputError
from station.model.fit import FitResult, fit_fftg
from station.model.illuminants import REFERENCE_ILLUMINANT, Illuminant, illuminant_sd, observer_cie_name
from station.model.representations import AspecularMeasurements
from station.model.spectra import WAVELENGTHS, reflectance_to_lab, weighting_factors, whitepoint_xyz

__all__ = [
    "BOOTH_SHAPES",
    "check_booth_shape",
    "display_design_under",
    "display_equivalent_lab",
    "fit_under_illuminant",
    "lab_to_display_under",
    "lab_to_linear_srgb_under",
    "light_colour",
    "metameric_black",
    "metameric_pair",
]


def check_booth_shape(shape: str, field: str = "shape") -> str:
    """*shape* if it is one of :data:`BOOTH_SHAPES`, else :class:`ModelInputError` naming *field*."""
    if shape not in BOOTH_SHAPES:
        raise ModelInputError(field, f"one of {', '.join(BOOTH_SHAPES)}", shape)
    return shape


def _name(illuminant: str | Illuminant) -> str:
    return illuminant.name if isinstance(illuminant, Illuminant) else illuminant_sd(illuminant)[0]


def display_equivalent_lab(
    lab: ArrayLike,
    illuminant: str | Illuminant,
    observer: str = OBSERVER_10,
    adaptation: float = 1.0,
) -> NDArray[np.float64]:
    """The corresponding colour under D65 of *lab* seen under *illuminant* (CAT16), as the product's Lab.

    Lab → XYZ relative to *illuminant*'s white → CAT16 (colour-science) to D65's white for the same
    observer → Lab relative to D65. Hand the result to anything that takes the product's D65 Lab or a
    design (the display pipeline, the renderer): it shows the colour as the booth's observer sees it.
    Under D65 it is *lab* itself.

    Parameters
    ----------
    lab
        CIE L*a*b* relative to *illuminant*'s white for *observer*, shape (..., 3)
        (:func:`station.model.spectra.reflectance_to_lab` with the same illuminant and observer).
    illuminant
        Booth name or user :class:`~station.model.illuminants.Illuminant`.
    observer
        colour-science observer name or ``"2"`` / ``"10"``.
    adaptation
        Degree of adaptation D of the observer to *illuminant*, 0–1: 1 (default) a fully adapted
        observer (CAT16 von Kries: the illuminant's white shows as the display white); below 1 the
        two-step CAT16 of Zhai & Luo (2018) with D_b = D, D_d = 1 (the light's colour shows through).
    """
    import colour  # colour-science (about a second) is imported by the functions that use it

    d = check_ranged("adaptation", adaptation, 0.0, 1.0)
    white = whitepoint_xyz(illuminant, observer)  # Y = 1
    target = whitepoint_xyz(REFERENCE_ILLUMINANT, observer)
    xyz = lab_to_xyz(lab, colour.XYZ_to_xy(white))  # Y of the white = 1
    if d == 1.0:
        adapted = colour.adaptation.chromatic_adaptation_VonKries(xyz, white, target, transform="CAT16")
    else:
        with colour.utilities.domain_range_scale("reference"):
            adapted = (
                colour.adaptation.chromatic_adaptation_Zhai2018(
                    xyz * 100.0, white * 100.0, target * 100.0, D_b=d, D_d=1.0, transform="CAT16"
                )
                / 100.0
            )
    return xyz_to_lab(adapted, colour.XYZ_to_xy(target))


def lab_to_linear_srgb_under(
    lab: ArrayLike,
    illuminant: str | Illuminant,
    observer: str = OBSERVER_10,
    adaptation: float = 1.0,
) -> NDArray[np.float64]:
    """Linear sRGB (unclipped, white = 1) of Lab seen under *illuminant*, shown on a D65 display.

    :func:`station.model.colorimetry.lab_to_linear_srgb` of :func:`display_equivalent_lab` (same
    parameters): a perfect white under any illuminant, fully adapted, is (1, 1, 1).
    """
    return lab_to_linear_srgb(display_equivalent_lab(lab, illuminant, observer, adaptation))


def lab_to_display_under(
    lab: ArrayLike,
    illuminant: str | Illuminant,
    observer: str = OBSERVER_10,
    adaptation: float = 1.0,
) -> NDArray[np.float64]:
    """Display sRGB in [0, 1] of Lab seen under *illuminant* (see :func:`lab_to_linear_srgb_under`)."""
    return encode_display(lab_to_linear_srgb_under(lab, illuminant, observer, adaptation))


def display_design_under(
    reflectance: ArrayLike,
    angles_deg: Sequence[float],
    illuminant: str | Illuminant,
    observer: str = OBSERVER_10,
    gloss_gu: float | None = None,
    adaptation: float = 1.0,
) -> FitResult:
    """The design to render for spectra per geometry seen under *illuminant* (the model hierarchy unchanged).

    Lab per geometry under *illuminant* → :func:`display_equivalent_lab` →
    :func:`station.model.fit.fit_fftg`.
    The design is in the product's D65 / 10° Lab, so the renderer, its lobe fit and cached basis images
    are used as they are; switching illuminant changes the design's numbers only. (:func:`fit_under_illuminant`
    is the colorimetric design, Lab relative to the illuminant's white.)
    """
    lab = display_equivalent_lab(
        reflectance_to_lab(reflectance, illuminant, observer), illuminant, observer, adaptation
    )
    return fit_fftg(AspecularMeasurements(tuple(float(a) for a in angles_deg), lab, gloss_gu))


def light_colour(illuminant: str | Illuminant, observer: str = OBSERVER_10) -> NDArray[np.float64]:
    """Linear sRGB of the illuminant's white on a D65 display, scaled so its largest channel is 1.

    No adaptation: the colour of the booth's light as a D65-adapted viewer sees it (the lamp's white as
    Lab relative to D65's white, then the product's display pipeline): A is orange, D65 is (1, 1, 1).
    The tint of a booth environment. Shape (3,).
    """
    import colour

    white = whitepoint_xyz(illuminant, observer)
    d65 = whitepoint_xyz(REFERENCE_ILLUMINANT, observer)
    rgb = np.clip(lab_to_linear_srgb(xyz_to_lab(white, colour.XYZ_to_xy(d65))), 0.0, None)
    return np.asarray(rgb / rgb.max(), dtype=float)


def fit_under_illuminant(
    reflectance: ArrayLike,
    angles_deg: Sequence[float],
    illuminant: str | Illuminant,
    observer: str = OBSERVER_10,
    gloss_gu: float | None = None,
) -> FitResult:
    """The face/flop/travel/gloss design of spectra per geometry as seen under *illuminant*.

    Lab per geometry under *illuminant* (its own white, *observer*) → :func:`station.model.fit.fit_fftg`
    (thesis §3.3.3; the model hierarchy unchanged). The design's Lab is relative to that illuminant.

    Parameters
    ----------
    reflectance
        Shape (n, 31): one spectrum per aspecular angle, 400–700 nm at 10 nm.
    angles_deg
        The n aspecular angles in degrees, strictly increasing (at least three).
    gloss_gu
        Specular gloss (GU) or None.
    """
    lab = reflectance_to_lab(reflectance, illuminant, observer)
    measurements = AspecularMeasurements(
        tuple(float(a) for a in angles_deg),
        lab,
        gloss_gu,
        illuminant=_name(illuminant),
        observer=observer_cie_name(observer),
    )
    return fit_fftg(measurements)


def metameric_black(
    invisible_under: str | Illuminant = "D65",
    visible_under: str | Illuminant = "A",
    observer: str = OBSERVER_10,
    free: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """A metameric black: a spectrum (31,) with XYZ = 0 under *invisible_under*, unit Euclidean norm.

    It is the direction of the null space of *invisible_under*'s weighting factors W (P = I − W W⁺)
    whose tristimulus values under *visible_under* are largest (the leading right singular vector of
    W_vis^T P), signed so that it raises the long-wavelength end (where A is strongest).

    *free* (boolean, 31) restricts it to those wavelengths (zero elsewhere): the black of a spectrum
    that sits on a bound (R = 0 or the maximum) at the other wavelengths.

    Raises
    ------
    ModelInputError
        Fewer than four free wavelengths (three constraints leave no null space).
    """
    w0 = weighting_factors(invisible_under, observer)
    w1 = weighting_factors(visible_under, observer)
    mask = np.ones(WAVELENGTHS.size, dtype=bool) if free is None else np.asarray(free, dtype=bool)
    if mask.shape != WAVELENGTHS.shape or int(mask.sum()) < 4:
        raise ModelInputError(
            "free", f"a mask of {WAVELENGTHS.size} wavelengths with at least 4 free", int(mask.sum())
        )
    w0f, w1f = w0[mask], w1[mask]
    projector = np.eye(int(mask.sum())) - w0f @ np.linalg.pinv(w0f)
    _, _, vt = np.linalg.svd(w1f.T @ projector)
    black = np.zeros(WAVELENGTHS.size)
    black[mask] = projector @ vt[0]
    black /= np.linalg.norm(black)
    if black @ np.linspace(-1.0, 1.0, WAVELENGTHS.size) < 0.0:  # more at the long-wavelength end
        black = -black
    return np.asarray(black, dtype=float)


#: Reflectance within this of a bound counts as on it: a metameric black leaves such wavelengths alone.
_BOUND_MARGIN = 1e-4


def metameric_pair(
    reflectance: ArrayLike,
    strength: float = 0.3,
    invisible_under: str | Illuminant = "D65",
    visible_under: str | Illuminant = "A",
    observer: str = OBSERVER_10,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A metameric pair per geometry: ``(standard, sample)``, equal under one illuminant, not another.

    The sample is each geometry's spectrum plus t_g times its :func:`metameric_black` (restricted to
    the wavelengths where the spectrum is off its bounds), with t_g = *strength* times the largest step
    (either sign) that keeps 0 <= R <= REFLECTANCE_MAX at that geometry; so its Lab under
    *invisible_under* equals the standard's (to round-off) and differs under *visible_under*.

    Parameters
    ----------
    reflectance
        The standard's spectra, shape (n, 31) (e.g. a library paint's, via
        :func:`station.model.spectra.reflectance_from_lab`).
    strength
        Fraction 0 < strength <= 1 of the admissible step.

    Raises
    ------
    ModelInputError
        The spectra are not (n, 31) in range, or a geometry's spectrum has fewer than four wavelengths
        off its bounds (no room for a metameric black).
    """
    s = check_ranged("strength", strength, 0.0, 1.0)
    if s <= 0.0:
        raise ModelInputError("strength", "0 < strength <= 1", strength)
    std = np.atleast_2d(np.asarray(reflectance, dtype=float))
    reflectance_to_lab(std)  # validates shape and range
    out = np.empty_like(std)
    for g, r in enumerate(std):
        free = (r > _BOUND_MARGIN) & (r < REFLECTANCE_MAX - _BOUND_MARGIN)
        if int(free.sum()) < 4:
            raise ModelInputError(
                f"reflectance[{g}]", "a spectrum with room for a metameric black", "no room"
            )
        black = metameric_black(invisible_under, visible_under, observer, free)
        steps = []
        for sign in (1.0, -1.0):
            b = sign * black
            with np.errstate(divide="ignore", invalid="ignore"):  # 0 / 0 where the black is 0
                up = np.where(b > 0, (REFLECTANCE_MAX - r) / b, np.inf)
                down = np.where(b < 0, -r / b, np.inf)
            steps.append(sign * float(min(up.min(), down.min())))
        t = max(steps, key=abs) * s
        if abs(t) <= 1e-9:
            raise ModelInputError(
                f"reflectance[{g}]", "a spectrum with room for a metameric black", "no room"
            )
        out[g] = np.clip(r + t * black, 0.0, REFLECTANCE_MAX)
    return std.copy(), out
