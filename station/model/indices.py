"""Library indices of a multi-angle colour (thesis §5.3.3, eqs 5.3.1–5.3.3; docs/design.md §3).

Each index has a known failure region, detected and reported in :attr:`IndexResult.warnings`:

* Flop Index: undefined when L*15 < L*110 (flop brighter than face; reported as None); numerically
  unstable for dark colours (L*45 below :data:`DARK_L45`, where the thesis found most values > 25).
* Hue Shift Index: meaningless when the face is achromatic (C*15 below :data:`ACHROMATIC_C15`,
  reported as None) and for colours whose hue rotates by more than 90° between face and flop
  (interference paints: the distance to the face's hue line no longer measures the shift).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from station.model.errors import ModelInputError

#: L*45 below which the Flop Index is flagged as numerically unstable (dark colours).
DARK_L45 = 20.0
#: Flop Index above which the value is flagged as implausible (thesis: > 25 comes from dark colours).
FLOP_INDEX_IMPLAUSIBLE = 25.0
#: C*15 below which the face counts as achromatic for the Hue Shift Index.
ACHROMATIC_C15 = 2.0


@dataclass(frozen=True)
class IndexResult:
    """Flop, Chroma and Hue Shift Index (ΔE units for the last two) with failure warnings."""

    flop_index: float | None
    chroma_index: float
    hue_shift_index: float | None
    warnings: tuple[str, ...] = ()


def _lab(value: ArrayLike, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise ModelInputError(name, "three finite numbers L*, a*, b*", value)
    return arr


def library_indices(lab15: ArrayLike, lab45: ArrayLike, lab110: ArrayLike) -> IndexResult:
    """Compute the thesis's three library indices from Lab at 15°, 45° and 110°.

    Flop Index = 2.69 (L15 − L110)^1.11 / L45^0.86 (eq 5.3.1);
    Chroma Index = |C15 − C110| (eq 5.3.2);
    Hue Shift Index = |a110 b15 − a15 b110| / C15 (eq 5.3.3).

    Examples
    --------
    Flop Index 2.69·70^1.11/60^0.86; Chroma Index |50 − √500|; Hue Shift Index |10·40 − 30·20|/50, and
    none for an achromatic face (C*15 < 2):

    >>> r = library_indices([100, 0, 0], [60, 0, 0], [30, 0, 0])
    >>> round(r.flop_index, 4), r.chroma_index, r.hue_shift_index
    (8.8838, 0.0, None)
    >>> r = library_indices([60, 30, 40], [45, 20, 30], [30, 10, 20])
    >>> round(r.chroma_index, 6), round(r.hue_shift_index, 6)
    (27.63932, 4.0)
    """
    l15, l45, l110 = _lab(lab15, "lab15"), _lab(lab45, "lab45"), _lab(lab110, "lab110")
    warnings: list[str] = []
    flop: float | None
    if l45[0] <= 0.0:
        flop = None
        warnings.append("flop_index: L*45 = 0, the formula divides by zero")
    elif l15[0] < l110[0]:
        flop = None
        warnings.append("flop_index: L*15 < L*110 (flop brighter than face): undefined for this colour")
    else:
        flop = float(2.69 * (l15[0] - l110[0]) ** 1.11 / l45[0] ** 0.86)
        if l45[0] < DARK_L45 or flop > FLOP_INDEX_IMPLAUSIBLE:
            warnings.append(
                f"flop_index: dark colour (L*45 = {l45[0]:.1f}) — the formula is numerically unstable here"
            )
    c15 = float(np.hypot(l15[1], l15[2]))
    c110 = float(np.hypot(l110[1], l110[2]))
    chroma = abs(c15 - c110)
    hue: float | None
    if c15 < ACHROMATIC_C15:
        hue = None
        warnings.append(f"hue_shift_index: achromatic face (C*15 = {c15:.2f}): hue shift undefined")
    else:
        hue = float(abs(l110[1] * l15[2] - l15[1] * l110[2]) / c15)
        if c110 >= ACHROMATIC_C15 and float(np.dot(l15[1:], l110[1:])) < 0.0:
            warnings.append("hue_shift_index: hue rotates more than 90° from face to flop: index unreliable")
    return IndexResult(flop, chroma, hue, tuple(warnings))
