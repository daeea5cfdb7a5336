"""CIE Lab ⇄ XYZ in NumPy against colour-science (the library of the field) and hand values."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.model.colorimetry import WHITEPOINT, lab_to_xyz, xyz_to_lab

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
