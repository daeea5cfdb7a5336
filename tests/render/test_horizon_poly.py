"""The wide lobes' Chebyshev polynomials of g (station.render.horizon_poly): used only where they are as
close to g as the horizon table's linear interpolation, checked against g summed independently at
points the fit never saw."""

from __future__ import annotations

import numpy as np
import pytest

from station.render.horizon_poly import HORIZON_DEGREE, horizon_chebyshev
from station.render.lobes import horizon_factors
from station.render.numpy_renderer import horizon_table, horizon_wide, lobe_factors

LIBRARY_WIDE = (2.2442, 4.4884, 14.115)  # the library basis's wide lobes


def _fit(exps: tuple[float, ...]) -> tuple[np.ndarray, int, np.ndarray]:
    table = horizon_table(exps)
    coeffs, mask = horizon_chebyshev(exps, table, horizon_wide(exps))
    return coeffs, mask, table


def test_library_wide_lobes_get_polynomials_as_close_as_the_table() -> None:
    """At 2,001 random c (seeded; not the fit's nodes or midpoints): against g as the table sums it, each
    polynomial's worst error is within 10 % of the table's interpolation error (a few 1e-6); against g
    summed with 4× the quadrature nodes both are within 2e-5 (the quadrature's own error)."""
    exps = (*LIBRARY_WIDE, 238.6692, 2706.2064)
    coeffs, mask, table = _fit(exps)
    assert mask == 0b111  # the wide ones; the narrow ones keep g = c from the table
    c = np.sort(np.random.default_rng(3).random(2001))
    table_g = lobe_factors(table, c)[0]
    for i, e in enumerate(LIBRARY_WIDE):
        g = horizon_factors(e, c)[0]
        poly = np.polynomial.chebyshev.chebval(2.0 * c - 1.0, coeffs[i])
        table_err = np.abs(table_g[:, i] - g).max()
        assert 0.0 < table_err < 2e-5
        assert np.abs(poly - g).max() <= 1.1 * table_err
        fine = horizon_factors(e, c, nodes=4096)[0]
        assert np.abs(poly - fine).max() < 2e-5 and np.abs(table_g[:, i] - fine).max() < 2e-5
    assert not coeffs[3:].any()


@pytest.mark.parametrize("exponent", [1.0, 64.0, 199.0])
def test_a_lobe_the_polynomial_cannot_follow_keeps_the_table(exponent: float) -> None:
    """For these lobes a degree-8 polynomial errs more than the table (g of E = 1 bends near c = 0, the
    sharper lobes' g near c = 1), so they keep their lookup: the fit's own check, against a least-squares
    fit computed here."""
    coeffs, mask, table = _fit((exponent,))
    c = np.linspace(0.0, 1.0, 1001)
    g = horizon_factors(exponent, c)[0]
    ref = np.polynomial.chebyshev.chebfit(2.0 * c - 1.0, g, HORIZON_DEGREE)
    poly_err = np.abs(np.polynomial.chebyshev.chebval(2.0 * c - 1.0, ref) - g).max()
    table_err = np.abs(lobe_factors(table, c)[0][:, 0] - g).max()
    assert poly_err > table_err
    assert mask == 0 and not coeffs.any()


def test_no_tables_no_polynomials() -> None:
    exps = LIBRARY_WIDE
    table = horizon_table(exps, "none")
    assert horizon_chebyshev(exps, table, horizon_wide(exps, "none"))[1] == 0
