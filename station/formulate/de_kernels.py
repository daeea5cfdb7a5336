"""Colour-difference kernels for ColorSnap's hot loop, bit-identical to :func:`station.model.difference.delta_e`.

:func:`station.model.difference.delta_e` validates and dispatches on every call (about 150 µs for
CIEDE2000 through colour-science), which would dominate a sub-millisecond search. These kernels call
the model's own unchecked arithmetic, so no formula is written here:

* ``cie76``   — ``np.linalg.norm(lab2 - lab1, axis=-1)``, as colour's ``euclidean_distance``.
* ``cie2000`` — :func:`station.model.cie2000.cie2000_columns` (colour's ``delta_E_CIE2000`` operations
  in the same order; Sharma, Wu & Dalal 2005), kL = kC = kH = 1.
* ``din6175`` — :func:`station.model.difference.din6175_unchecked` (DIN 6175-2 as published in a public
  implementation), which needs the aspecular angle of each pair.

tests/formulate/test_snap.py asserts exact equality (``==``, not a tolerance) against
:func:`~station.model.difference.delta_e` on random and edge-case inputs, which is what makes the
ColorSnap ranking identical to a brute-force scan through the public function.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray

from station.model.cie2000 import cie2000_columns
from station.model.difference import DIN_DEFAULT_FACTORS, din6175_unchecked

#: ``kernel(lab_standard, lab_sample, alpha)``: *alpha* the |aspecular angle| per pair (degrees), read by
#: din6175 only.
Kernel = Callable[[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def cie76(
    lab1: NDArray[np.float64], lab2: NDArray[np.float64], alpha: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """ΔE*ab (CIE 1976), shape (...); *alpha* is not read."""
    return np.linalg.norm(lab1 - lab2, axis=-1)


def cie2000(
    lab1: NDArray[np.float64], lab2: NDArray[np.float64], alpha: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """CIEDE2000 with kL = kC = kH = 1, shape (...); *lab1* is the reference; *alpha* is not read."""
    return cie2000_columns(lab1[..., 0], lab1[..., 1], lab1[..., 2], lab2[..., 0], lab2[..., 1], lab2[..., 2])


def din6175(
    lab1: NDArray[np.float64], lab2: NDArray[np.float64], alpha: NDArray[np.float64]
) -> NDArray[np.float64]:
    """DIN 6175-2 ΔE_eff with g = 1, *lab1* the standard, *alpha* the |aspecular angle| (°) of each pair.

    :func:`station.model.difference.din6175_unchecked` itself (the model's arithmetic without its
    input checks). *alpha* must broadcast to the pair shape and be > 0.
    """
    return din6175_unchecked(lab1, lab2, alpha, DIN_DEFAULT_FACTORS).de_eff


KERNELS: Mapping[str, Kernel] = MappingProxyType({"cie76": cie76, "cie2000": cie2000, "din6175": din6175})
