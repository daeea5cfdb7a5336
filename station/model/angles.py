"""Validation of aspecular angle sets (degrees, illumination at 45°).

The standard sets themselves (:data:`ANGLES_3` …) and the accepted range live in
:mod:`station.model.domain`; they are re-exported here for existing imports.

The aspecular angle is measured from the specular direction in the plane of illumination, positive
towards the illumination (thesis §3.3.3; ASTM E2194; DIN 6175-2's "effect angle").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from station.model.domain import ANGLE_MAX_DEG, ANGLE_MIN_DEG, ANGLES_3, ANGLES_3_ALT, ANGLES_5, ANGLES_6
from station.model.errors import ModelInputError

__all__ = [
    "ANGLES_3",
    "ANGLES_3_ALT",
    "ANGLES_5",
    "ANGLES_6",
    "ANGLE_MAX_DEG",
    "ANGLE_MIN_DEG",
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
