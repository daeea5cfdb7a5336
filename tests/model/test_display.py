"""Lab ⇄ display sRGB (station.model.display) against closed forms and colour-science."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.model.colorimetry import WHITEPOINT
from station.model.display import decode_display, display_to_lab, encode_display, lab_to_display, to_uint8


def test_neutral_greys_by_hand() -> None:
    lightness = np.array([0.0, 5.0, 18.0, 50.0, 100.0])
    y = np.where(lightness > 8.0, ((lightness + 16.0) / 116.0) ** 3, lightness / 903.2963)
    v = np.where(y <= 0.0031308, 12.92 * y, 1.055 * y ** (1 / 2.4) - 0.055)  # IEC 61966-2-1
    lab = np.stack([lightness, np.zeros(5), np.zeros(5)], axis=-1)
    np.testing.assert_allclose(lab_to_display(lab), np.repeat(v[:, None], 3, axis=1), atol=1e-9)


def test_chromatic_colours_match_colour_science() -> None:
    lab = np.array([[60.0, 30.0, -20.0], [40.0, -20.0, 30.0], [80.0, 5.0, 60.0]])
    expected = colour.XYZ_to_RGB(
        colour.Lab_to_XYZ(lab, WHITEPOINT),
        colour.RGB_COLOURSPACES["sRGB"],
        illuminant=WHITEPOINT,
        chromatic_adaptation_transform="CAT02",
        apply_cctf_encoding=True,
    )
    # colour's sRGB matrix is rounded to 4 decimals; the model rescales it so the white is exact
    np.testing.assert_allclose(lab_to_display(lab), np.clip(expected, 0, 1), atol=5e-4)
    np.testing.assert_allclose(display_to_lab(lab_to_display(lab)), lab, atol=1e-9)


def test_display_clips_and_quantises() -> None:
    assert encode_display(np.array([-0.5, 2.0])) == pytest.approx([0.0, 1.0])
    assert lab_to_display(np.array([130.0, 0.0, 0.0])) == pytest.approx([1.0, 1.0, 1.0])
    x = np.linspace(0.0, 1.0, 11)
    assert decode_display(encode_display(x)) == pytest.approx(x, abs=1e-12)
    assert to_uint8(np.array([0.0, 0.5 / 255, 1.0, 1.5])).tolist() == [0, 1, 255, 255]
