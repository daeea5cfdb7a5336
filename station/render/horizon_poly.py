"""Chebyshev polynomials of the wide lobes' cosine factor g(R·N) for the GL renderer.

The directionally diffuse term of a wide lobe is weighted by g(c) = ∫ p(ω) (N·ω)₊ dω at c = R·N
(:func:`station.render.lobes.horizon_factors`, thesis eq 2.3.3 with the horizon), which the renderers read
from the horizon table by linear interpolation over HORIZON_TABLE_SIZE nodes
(:func:`station.render.numpy_renderer.horizon_table`). g is smooth in c, and for the library's wide lobes
a Chebyshev polynomial of degree :data:`HORIZON_DEGREE` in x = 2c − 1 is as close to it as the table: the
shader then evaluates the polynomial (Clenshaw's recurrence, arithmetic) instead of looking the table up,
which on llvmpipe costs more than the recurrence. A lobe is given its polynomial only where the
polynomial's largest error against g is no more than the table's, both measured at the table's nodes and
midpoints (where linear interpolation errs most); every other lobe keeps the table.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["HORIZON_DEGREE", "horizon_chebyshev"]

#: Degree of the polynomial (nine coefficients a lobe).
HORIZON_DEGREE = 8


def horizon_chebyshev(
    exponents: Sequence[float], table: NDArray[np.floating], wide: Sequence[bool]
) -> tuple[NDArray[np.float64], int]:
    """(Chebyshev coefficients (m, HORIZON_DEGREE + 1) of g in x = 2c − 1, zero for a lobe without
    them; bit mask of the lobes whose polynomial is used) for lobes with Phong *exponents* (bound order),
    their horizon *table* (m, N, 2) of (g, h) at c = k/(N − 1), and *wide* (the lobes with horizon
    factors; the others' g is c itself, exact in the table). Dimensionless."""
    from station.render.lobes import horizon_factors

    m, n = table.shape[0], table.shape[1]
    coeffs = np.zeros((m, HORIZON_DEGREE + 1))
    mask = 0
    nodes = np.linspace(0.0, 1.0, n)
    mids = 0.5 * (nodes[1:] + nodes[:-1])
    c = np.concatenate([nodes, mids])
    for i in range(m):
        if not wide[i]:
            continue
        # g at the nodes is the table's own (the same quadrature); at the midpoints it is summed here
        g_mid = horizon_factors(float(exponents[i]), mids)[0]
        g = np.concatenate([table[i, :, 0].astype(np.float64), g_mid])
        table_err = float(np.max(np.abs(0.5 * (table[i, 1:, 0] + table[i, :-1, 0]) - g_mid)))
        fit = np.polynomial.chebyshev.chebfit(2.0 * c - 1.0, g, HORIZON_DEGREE)
        poly_err = float(np.max(np.abs(np.polynomial.chebyshev.chebval(2.0 * c - 1.0, fit) - g)))
        if poly_err <= table_err:
            coeffs[i] = fit
            mask |= 1 << i
    return coeffs, mask
