"""The design Lab a ColorSnap query accepts: one (L*, a*, b*) triple per angle, inside the query range.

:data:`LAB_QUERY_RANGE` is the accepted range per coordinate (CIELAB units); a value outside it, or not
finite, raises :class:`~station.formulate.errors.FormulateInputError` naming ``lab.L``/``lab.a``/
``lab.b`` and the range.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.errors import FormulateInputError
from station.model.domain import LAB_RANGES, lab_accepted

__all__ = ["LAB_QUERY_RANGE", "validate_design_lab"]

#: Accepted query Lab: the domain's effect-paint bound (station.model.domain.LAB_RANGES).
LAB_QUERY_RANGE: Mapping[str, tuple[float, float]] = LAB_RANGES
_Q_LO = np.array([v[0] for v in LAB_QUERY_RANGE.values()])
_Q_HI = np.array([v[1] for v in LAB_QUERY_RANGE.values()])
_Q_LO.flags.writeable = _Q_HI.flags.writeable = False


def validate_design_lab(lab: ArrayLike, n_angles: int = 3, field_name: str = "lab") -> NDArray[np.float64]:
    """Return *lab* as an (n_angles, 3) float array, or raise :class:`FormulateInputError`."""
    try:
        q = np.asarray(lab, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise FormulateInputError(field_name, f"{n_angles} Lab triples", lab) from exc
    if q.shape != (n_angles, 3):
        raise FormulateInputError(field_name, f"{n_angles} Lab triples (one per angle)", q.shape)
    if bool(((q >= _Q_LO) & (q <= _Q_HI)).all()):  # fast path; NaN fails both comparisons
        return q
    for j, (name, (lo, hi)) in enumerate(LAB_QUERY_RANGE.items()):
        col = q[:, j]
        if not np.all(np.isfinite(col)) or np.any(col < lo) or np.any(col > hi):
            raise FormulateInputError(f"{field_name}.{name}", f"finite {lab_accepted(name)}", col.tolist())
    return q
