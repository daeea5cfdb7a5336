"""Reflectance spectra ⇄ Lab, spectral recovery and a metamerism index.

Tristimulus integration follows ASTM E308 through colour-science: the tristimulus weighting factors
for 400–700 nm at 10 nm (ASTM E2022 / E308 table method, range-adjusted) are computed once per
illuminant and observer, so XYZ = R · W for any number of spectra. White (R = 1) gives Y = 1.

Spectral recovery (Lab → plausible reflectance) minimises the roughness Σ(R_{i+1} − R_i)² subject to
reproducing the XYZ exactly with 0 <= R <= 1 — the same weights, so the recovered spectrum maps back
to the asked Lab to numerical precision.
"""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.colorimetry import OBSERVER_10, xyz_to_lab
from station.model.domain import DIFFUSE_WHITE_L, REFLECTANCE_MAX
from station.model.errors import FitError, ModelInputError
from station.model.illuminants import Illuminant, illuminant_sd, observer_cie_name

#: Wavelength grid of every reflectance spectrum in the product, nm (31 values).
WAVELENGTHS: NDArray[np.float64] = np.arange(400.0, 701.0, 10.0)


def weighting_factors(
    illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10
) -> NDArray[np.float64]:
    """ASTM E308 tristimulus weighting factors, shape (31, 3), normalised so white has Y = 1.

    *illuminant* is a catalogue name (:func:`station.model.illuminants.illuminant_name`: D65, D50, A,
    F2, F11, TL84, LED-B3, LED-B4 or another colour-science illuminant) or a user
    :class:`~station.model.illuminants.Illuminant`; *observer* a colour-science observer name or
    ``"2"`` / ``"10"``. Computed once per (illuminant, observer) and cached.
    """
    if not isinstance(illuminant, Illuminant):
        illuminant, _ = illuminant_sd(illuminant)  # the canonical name (validates)
    return _weighting_factors(illuminant, observer_cie_name(observer))


@cache
def _weighting_factors(illuminant: str | Illuminant, observer: str) -> NDArray[np.float64]:
    import colour  # colour-science (about a second) is imported by the functions that use it

    _, sd_illuminant = illuminant_sd(illuminant)
    cmfs = colour.MSDS_CMFS[observer]
    shape = colour.SpectralShape(400, 700, 10)
    w = np.empty((WAVELENGTHS.size, 3))
    for i in range(WAVELENGTHS.size):  # XYZ is linear in R: integrate unit impulses once
        values = np.zeros(WAVELENGTHS.size)
        values[i] = 1.0
        sd = colour.SpectralDistribution(dict(zip(WAVELENGTHS, values, strict=True)))
        with warnings.catch_warnings():  # colour warns that it trims the CMFs to our 400–700 nm range
            warnings.simplefilter("ignore")
            w[i] = colour.sd_to_XYZ(sd, cmfs, sd_illuminant, method="ASTM E308", shape=shape) / 100.0
    white_y = w[:, 1].sum()
    if not (np.all(np.isfinite(w)) and np.isfinite(white_y) and white_y > 0.0):
        name = illuminant.name if isinstance(illuminant, Illuminant) else illuminant
        raise ModelInputError("illuminant", "a spectral power giving a finite, positive white", name)
    w /= white_y  # white → Y = 1 exactly
    w.setflags(write=False)
    return w


def whitepoint_xyz(illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10) -> NDArray[np.float64]:
    """XYZ of the perfect white under *illuminant* with the product's weights (Y = 1)."""
    return weighting_factors(illuminant, observer).sum(axis=0)


def _check_reflectance(reflectance: ArrayLike) -> NDArray[np.float64]:
    r = np.asarray(reflectance, dtype=float)
    if r.shape[-1:] != (WAVELENGTHS.size,):
        raise ModelInputError(
            "reflectance", f"shape (..., {WAVELENGTHS.size}) for 400–700 nm at 10 nm", r.shape
        )
    if not np.all(np.isfinite(r)) or np.any(r < 0.0) or np.any(r > REFLECTANCE_MAX):
        raise ModelInputError(
            "reflectance",
            f"finite reflectance factors 0 <= R <= {REFLECTANCE_MAX:.3g}",
            "out-of-range values",
        )
    return r


def reflectance_to_xyz(
    reflectance: ArrayLike, illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10
) -> NDArray[np.float64]:
    """XYZ (white Y = 1) of reflectance spectra (..., 31) under *illuminant* (ASTM E308)."""
    return _check_reflectance(reflectance) @ weighting_factors(illuminant, observer)


def reflectance_to_lab(
    reflectance: ArrayLike, illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10
) -> NDArray[np.float64]:
    """CIE L*a*b* of reflectance spectra (..., 31) relative to *illuminant*'s white for *observer*.

    Parameters
    ----------
    reflectance
        Reflectance factors at :data:`WAVELENGTHS` (400–700 nm, 10 nm), shape (..., 31).
    illuminant
        ``"D65"`` (default), a booth name (``"A"``, ``"F11"``, ``"TL84"``, ``"LED-B3"``, …), another
        colour-science illuminant name, or a user :class:`~station.model.illuminants.Illuminant`.
    observer
        CIE observer (colour-science name or ``"2"`` / ``"10"``); default the 1964 10° observer.

    Examples
    --------
    A flat reflectance R reads X/X_n = Y/Y_n = Z/Z_n = R, so L* = 116 R^(1/3) − 16 and a* = b* = 0:

    >>> import numpy as np
    >>> (reflectance_to_lab(np.ones(31)).round(9) + 0.0).tolist()  # + 0.0 folds a signed zero
    [100.0, 0.0, 0.0]
    >>> lab = reflectance_to_lab(np.full(31, 0.18))
    >>> round(float(lab[0]), 6), bool(np.all(np.abs(lab[1:]) < 1e-9))
    (49.496108, True)
    """
    import colour

    xyz = reflectance_to_xyz(reflectance, illuminant, observer)
    white = whitepoint_xyz(illuminant, observer)
    return xyz_to_lab(xyz, colour.XYZ_to_xy(white))


def _difference_operator(n: int) -> NDArray[np.float64]:
    d = np.zeros((n - 1, n))
    d[np.arange(n - 1), np.arange(n - 1)] = -1.0
    d[np.arange(n - 1), np.arange(1, n)] = 1.0
    return d


def reflectance_from_lab(
    lab: ArrayLike, illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10
) -> NDArray[np.float64]:
    """Recover smooth reflectance spectra (..., 31) that reproduce Lab exactly.

    Reflectance is bounded to [0, 1] for L* up to :data:`~station.model.domain.DIFFUSE_WHITE_L` (an
    object colour) and to [0, :data:`~station.model.domain.REFLECTANCE_MAX`] above: an effect paint's
    face near the specular (L* 100–200, a bright aluminium) has a radiance factor above 1.

    Raises
    ------
    ModelInputError
        When a Lab lies outside the colour solid of those bounds (no reflectance reproduces it).
    """
    import colour
    from scipy.optimize import LinearConstraint, minimize

    lab_arr = np.asarray(lab, dtype=float)
    if lab_arr.shape[-1:] != (3,) or not np.all(np.isfinite(lab_arr)):
        raise ModelInputError("lab", "finite L*, a*, b* triples", lab_arr.shape)
    w = weighting_factors(illuminant, observer)
    white = whitepoint_xyz(illuminant, observer)
    flat = lab_arr.reshape(-1, 3)
    targets = colour.Lab_to_XYZ(flat, colour.XYZ_to_xy(white)) * white[1]
    n = WAVELENGTHS.size
    d = _difference_operator(n)
    q = d.T @ d + 1e-6 * np.eye(n)  # roughness, regularised so Q is invertible
    q_inv_w = np.linalg.solve(q, w)
    gram = w.T @ q_inv_w

    def roughness(x: NDArray[np.float64]) -> float:
        return float(0.5 * x @ q @ x)

    def roughness_grad(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return q @ x

    out = np.empty((flat.shape[0], n))
    for k, xyz in enumerate(targets):
        top = 1.0 if flat[k, 0] <= DIFFUSE_WHITE_L else REFLECTANCE_MAX
        r = q_inv_w @ np.linalg.solve(gram, xyz)  # closed form without bounds
        if np.any(r < -1e-12) or np.any(r > top + 1e-12):
            res = minimize(
                roughness,
                np.clip(r, 0.0, top),
                jac=roughness_grad,
                bounds=[(0.0, top)] * n,
                constraints=LinearConstraint(w.T, xyz, xyz),  # W^T R = XYZ exactly
                method="SLSQP",
                options={"ftol": 1e-14, "maxiter": 500},
            )
            r = res.x
            if not res.success or np.max(np.abs(r @ w - xyz)) > 1e-7:
                raise ModelInputError(
                    f"lab[{k}]",
                    f"a colour inside the object-colour solid (reachable with 0 <= R <= {top:.3g})",
                    [round(float(v), 3) for v in flat[k]],
                )
        out[k] = np.clip(r, 0.0, top)
    return out.reshape((*lab_arr.shape[:-1], n))


def metamerism_index(
    reflectance_ref: ArrayLike,
    reflectance_sample: ArrayLike,
    reference_illuminant: str | Illuminant = "D65",
    test_illuminants: tuple[str | Illuminant, ...] = ("A", "F11"),
    method: str = "cie2000",
    aspecular_deg: ArrayLike | None = None,
    observer: str = OBSERVER_10,
) -> dict[str, NDArray[np.float64]]:
    """Special metamerism index (change in illuminant) between two samples, per geometry.

    *aspecular_deg* (degrees, one per spectrum) is required by ``method="din6175"``. Illuminants are
    catalogue names or user :class:`~station.model.illuminants.Illuminant` objects (keyed by their
    ``name`` in the result); *observer* is a colour-science name or ``"2"`` / ``"10"``.

    The sample is first corrected additively in Lab for its mismatch under the reference illuminant
    (CIE 15 / ISO 105-J02 practice), then the difference under each test illuminant is the index.

    Returns
    -------
    dict
        ``{illuminant: ΔE per spectrum}`` for each test illuminant, plus ``"reference"`` with the
        uncorrected difference under the reference illuminant.
    """
    from station.model.difference import delta_e

    ref = np.asarray(reflectance_ref, dtype=float)
    smp = np.asarray(reflectance_sample, dtype=float)
    if ref.shape != smp.shape:
        raise FitError(f"reflectance_sample: shape {smp.shape} differs from reflectance_ref {ref.shape}")
    lab_r0 = reflectance_to_lab(ref, reference_illuminant, observer)
    lab_s0 = reflectance_to_lab(smp, reference_illuminant, observer)
    out: dict[str, NDArray[np.float64]] = {
        "reference": delta_e(lab_r0, lab_s0, method, aspecular_deg=aspecular_deg)
    }
    for ill in test_illuminants:
        lab_r = reflectance_to_lab(ref, ill, observer)
        lab_s = reflectance_to_lab(smp, ill, observer) - (lab_s0 - lab_r0)
        out[ill.name if isinstance(ill, Illuminant) else ill] = delta_e(
            lab_r, lab_s, method, aspecular_deg=aspecular_deg
        )
    return out
