"""Validation of aspecular angle sets (degrees, illumination at 45°).

The standard sets themselves (:data:`ANGLES_3` …) and the accepted range live in
:mod:`station.model.domain`; they are re-exported here for existing imports.

The aspecular angle is measured from the specular direction in the plane of illumination, positive
towards the illumination (thesis §3.3.3; ASTM E2194; DIN 6175-2's "effect angle").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.domain import (
    ANGLE_MAX_DEG,
    ANGLE_MIN_DEG,
    ANGLES_3,
    ANGLES_3_ALT,
    ANGLES_5,
    ANGLES_6,
    ILLUMINATION_DEG,
)
from station.model.errors import ModelInputError

#: Refractive index of the clear coat and binder the flakes sit in (a typical acrylic/polyurethane, 1.5).
CLEAR_COAT_INDEX = 1.5

__all__ = [
    "ANGLES_3",
    "ANGLES_3_ALT",
    "ANGLES_5",
    "ANGLES_6",
    "ANGLE_MAX_DEG",
    "ANGLE_MIN_DEG",
    "CLEAR_COAT_INDEX",
    "flake_equivalent_aspecular",
    "flake_tilt_deg",
    "validate_angle_set",
]


def validate_angle_set(angles_deg: Sequence[float], field: str = "angles_deg") -> tuple[float, ...]:
    """Check an aspecular angle set: finite, in range, strictly increasing, no duplicates.

    Parameters
    ----------
    angles_deg
        Aspecular angles in degrees.
    field
        Name used in error messages.

    Returns
    -------
    tuple of float
        The same angles as a tuple of Python floats.

    Raises
    ------
    ModelInputError
        Naming the field and the accepted range.

    Examples
    --------
    >>> validate_angle_set([15, 45, 110])
    (15.0, 45.0, 110.0)
    >>> validate_angle_set([15, 200])
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: angles_deg[1]: expected a finite angle in [-90, 180] degrees, got 200.0
    >>> validate_angle_set([45, 15])
    Traceback (most recent call last):
        ...
    station.model.errors.ModelInputError: angles_deg: expected angles in increasing order, got [45.0, 15.0]
    """
    try:
        arr = np.asarray(angles_deg, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ModelInputError(field, "a sequence of numbers (degrees)", angles_deg) from exc
    if arr.size == 0:
        raise ModelInputError(field, "at least one aspecular angle", list(angles_deg))
    for i, v in enumerate(arr):
        if not np.isfinite(v) or not (ANGLE_MIN_DEG <= v <= ANGLE_MAX_DEG):
            raise ModelInputError(
                f"{field}[{i}]", f"a finite angle in [{ANGLE_MIN_DEG:g}, {ANGLE_MAX_DEG:g}] degrees", float(v)
            )
    diffs = np.diff(arr)
    if np.any(diffs == 0):
        raise ModelInputError(field, "distinct angles (no duplicates)", arr.tolist())
    if np.any(diffs < 0):
        raise ModelInputError(field, "angles in increasing order", arr.tolist())
    return tuple(float(v) for v in arr)


def flake_tilt_deg(aspecular_deg: ArrayLike, n: float = CLEAR_COAT_INDEX) -> NDArray[np.float64]:
    """Tilt α (degrees, inside the film) of the flakes that mirror the 45° illumination into the view.

    With the light refracted to φ_i′ = asin(sin 45° / n) and the view at 45° − θ from the normal in air
    (θ signed, positive towards the illumination) refracted to φ_v′, α = (φ_i′ − φ_v′) / 2 (Snell). The
    sign of θ matters: −15° views at 60°, +15° at 30°, and the flakes that serve −15° are tilted less
    (|α| 3.57° against 4.33° for n = 1.5), so an effect paint reads lighter at −15° than at +15°, as
    real multi-angle instruments report (e.g. L* 67.9 at 45as-15 against 63.7 at 45as15).

    >>> flake_tilt_deg([-15, 15]).round(2).tolist()
    [-3.57, 4.33]
    """
    theta = np.asarray(aspecular_deg, dtype=np.float64)
    view = np.radians(np.clip(ILLUMINATION_DEG - theta, -89.0, 89.0))
    phi_i = np.arcsin(np.sin(np.radians(ILLUMINATION_DEG)) / n)
    phi_v = np.arcsin(np.sin(view) / n)
    return np.asarray(np.degrees(0.5 * (phi_i - phi_v)), dtype=np.float64)


def flake_equivalent_aspecular(aspecular_deg: ArrayLike, n: float = CLEAR_COAT_INDEX) -> NDArray[np.float64]:
    """The non-negative aspecular angle whose flakes are tilted as much as those of *aspecular_deg* (degrees).

    The face/flop/travel model (thesis §3.3) is a function of |θ| and cannot tell −15° from +15°; evaluated
    at this angle it sees the far side of specular as the flakes do (:func:`flake_tilt_deg`). For θ ≥ 0
    the angle is θ itself; for θ < 0 it solves α(θ′) = |α(θ)|: φ_v′(θ′) = φ_i′ − 2|α|, so
    θ′ = 45° − asin(n sin(φ_i′ − 2|α|)). −15° maps to 12.5°, nearer specular than the face angle.

    >>> flake_equivalent_aspecular([-15, 15, 45]).round(2).tolist()
    [12.51, 15.0, 45.0]
    """
    theta = np.asarray(aspecular_deg, dtype=np.float64)
    alpha = np.radians(np.abs(flake_tilt_deg(theta, n)))
    phi_i = np.arcsin(np.sin(np.radians(ILLUMINATION_DEG)) / n)
    mirrored = ILLUMINATION_DEG - np.degrees(np.arcsin(np.clip(n * np.sin(phi_i - 2.0 * alpha), -1.0, 1.0)))
    return np.asarray(np.where(theta >= 0.0, theta, mirrored), dtype=np.float64)
