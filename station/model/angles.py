"""Standard aspecular angle sets (degrees, illumination at 45°) and their validation.

The aspecular angle is measured from the specular direction in the plane of illumination, positive
towards the illumination (thesis §3.3.3; ASTM E2194; DIN 6175-2's "effect angle").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from station.model.errors import ModelInputError

#: The common 3-angle set (ASTM E2194), degrees.
ANGLES_3: tuple[float, ...] = (15.0, 45.0, 110.0)
#: The alternative 3-angle set, degrees.
ANGLES_3_ALT: tuple[float, ...] = (25.0, 45.0, 75.0)
#: The 5-angle set of 5-angle instruments, degrees.
ANGLES_5: tuple[float, ...] = (15.0, 25.0, 45.0, 75.0, 110.0)
#: The 6-angle set with the behind-gloss −15° angle, degrees.
ANGLES_6: tuple[float, ...] = (-15.0, 15.0, 25.0, 45.0, 75.0, 110.0)

#: Accepted aspecular angle range in degrees. At 45° illumination the in-plane aspecular angle
#: runs from −45° (view at the normal's far side grazing… limited by the specular lobe) to 135°
#: (view grazing on the light's side); we accept −90 … 180 so out-of-plane geometries fit too.
ANGLE_MIN_DEG = -90.0
ANGLE_MAX_DEG = 180.0


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
