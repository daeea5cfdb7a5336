"""CIE Lab ⇄ XYZ in NumPy against colour-science (the library of the field) and hand values."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.model.colorimetry import OBSERVER_10, WHITEPOINT, lab_to_xyz, xyz_to_lab

RNG = np.random.default_rng(7)
# Both branches of f: dark colours (L* < 8, the linear segment), effect-paint faces above L* 100,
# saturated a*, b* (the linear segment on X or Z), negative tristimulus values out of gamut.
LABS = np.concatenate(
    [
        np.column_stack([RNG.uniform(0, 200, 400), RNG.uniform(-150, 150, 400), RNG.uniform(-150, 150, 400)]),
        np.column_stack([RNG.uniform(0, 8, 100), RNG.uniform(-20, 20, 100), RNG.uniform(-20, 20, 100)]),
        np.array([[0.0, 0.0, 0.0], [8.0, 0.0, 0.0], [100.0, 0.0, 0.0], [125.0, -0.6, -1.8]]),
    ]
)


def test_the_white_point_is_colour_sciences() -> None:
    """The written-out D65 / 10° chromaticity is colour-science's, to the last bit."""
    theirs = np.asarray(colour.CCS_ILLUMINANTS[OBSERVER_10]["D65"], dtype=float)
    assert WHITEPOINT.dtype == theirs.dtype and WHITEPOINT.tolist() == theirs.tolist()


@pytest.mark.parametrize("whitepoint", [WHITEPOINT, np.array([0.44757, 0.40745])])
def test_lab_to_xyz_matches_colour_science(whitepoint: np.ndarray) -> None:
    ours = lab_to_xyz(LABS, whitepoint)
    theirs = colour.Lab_to_XYZ(LABS, whitepoint)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


@pytest.mark.parametrize("whitepoint", [WHITEPOINT, np.array([0.44757, 0.40745])])
def test_xyz_to_lab_matches_colour_science(whitepoint: np.ndarray) -> None:
    xyz = colour.Lab_to_XYZ(LABS, whitepoint)
    np.testing.assert_allclose(xyz_to_lab(xyz, whitepoint), colour.XYZ_to_Lab(xyz, whitepoint), atol=1e-9)
    np.testing.assert_allclose(xyz_to_lab(lab_to_xyz(LABS, whitepoint), whitepoint), LABS, atol=1e-9)


def test_hand_values() -> None:
    # White: Y = 1 and X, Z = x/y, (1-x-y)/y of the white point.
    x, y = WHITEPOINT
    np.testing.assert_allclose(lab_to_xyz([100.0, 0.0, 0.0]), [x / y, 1.0, (1 - x - y) / y], atol=1e-15)
    # L* = 50 grey: Y = ((50 + 16) / 116)³ = 0.184186…
    assert lab_to_xyz([50.0, 0.0, 0.0])[1] == pytest.approx((66 / 116) ** 3, abs=1e-15)
    # L* = 4 (linear segment): Y = 4 / κ = 4 · 27 / 24389.
    assert lab_to_xyz([4.0, 0.0, 0.0])[1] == pytest.approx(4 * 27 / 24389, abs=1e-15)
    # Shapes: (..., 3) in, (..., 3) out.
    assert lab_to_xyz(np.zeros((2, 5, 3))).shape == (2, 5, 3)


def test_the_written_out_srgb_matrix_is_colour_sciences() -> None:
    """The display pipeline's matrix is the one derived from colour-science's sRGB, to within 1e-14
    relative: the derivation's products and inverse run in the BLAS and LAPACK kernels that OpenBLAS picks
    for the CPU, whose summation order moves the last bits (up to 10 units in the last place, 1.7e-15
    relative, on an AVX-512 machine against the one the matrix was written out on). A change in any of
    an entry's first 14 significant digits fails it."""
    from station.model.colorimetry import _XYZ10_TO_LINEAR_SRGB, derive_xyz10_to_linear_srgb

    np.testing.assert_allclose(_XYZ10_TO_LINEAR_SRGB, derive_xyz10_to_linear_srgb(), rtol=1e-14, atol=0)


#: Linear and encoded values on both segments, the knee, out of [0, 1], signed zeros, inf and NaN.
_TRANSFER = np.concatenate(
    [
        RNG.uniform(-0.5, 1.5, 2000),
        RNG.uniform(0.0, 0.06, 2000),
        np.array([0.0, -0.0, 0.0031308, 0.04044936, 1.0, 1e-300, np.inf, -np.inf, np.nan]),
    ]
)


@pytest.mark.parametrize(
    "value", [_TRANSFER, _TRANSFER[:3999].reshape(-1, 3), 0.5, 0.002, -0.25, float("nan"), 1]
)
def test_the_srgb_transfer_functions_are_colour_sciences(value: object) -> None:
    """:func:`srgb_encode` / :func:`srgb_decode` give colour-science's ``eotf_inverse_sRGB`` /
    ``eotf_sRGB`` to the last bit, shape and NaN included."""
    from station.model.colorimetry import srgb_decode, srgb_encode

    for ours, theirs in (
        (srgb_encode, colour.models.eotf_inverse_sRGB),
        (srgb_decode, colour.models.eotf_sRGB),
    ):
        got = ours(value)  # type: ignore[arg-type]
        want = np.asarray(theirs(np.asarray(value, dtype=float)), dtype=float)
        assert got.shape == want.shape and got.dtype == want.dtype
        np.testing.assert_array_equal(got, want, strict=True)
        assert np.signbit(got).tolist() == np.signbit(want).tolist()
