"""Palette swatch and booklet thumbnail (thesis §3.4.6)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from station.design.errors import DesignInputError
from station.design.images import load_image, save_png
from station.design.palette import booklet, border_grey, swatch
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab, srgb_decode


def test_swatch_bar_shows_the_curve_and_border_shows_gloss(red_metallic) -> None:
    sw = swatch(red_metallic, width=120, height=20, border=3)
    assert sw.pixels.shape == (20, 120, 3) and sw.pixels.dtype == np.uint8
    assert sw.out_of_gamut_columns == 0
    bar = sw.pixels[10, 3:-3].astype(float) / 255.0
    lab = linear_srgb_to_lab(srgb_decode(bar))
    expect = red_metallic.lab_at(sw.angles_deg)
    assert np.max(np.linalg.norm(lab - expect, axis=1)) < 1.0  # 8-bit quantisation
    assert sw.angles_deg[0] == 15.0 and sw.angles_deg[-1] == 110.0
    # border grey rises with gloss: 0.15 at 0 GU, 1.0 at 100 GU, 0.575 at 50 GU
    assert sw.pixels[0, 0, 0] == round(border_grey(50.0) * 255)
    assert border_grey(0.0) == pytest.approx(0.15) and border_grey(100.0) == pytest.approx(1.0)
    dull = swatch(red_metallic.replace(gloss_gu=5.0), width=120, height=20, border=3)
    assert dull.pixels[0, 0, 0] < sw.pixels[0, 0, 0]


def test_swatch_reports_out_of_gamut_columns() -> None:
    vivid = FaceFlopTravelGloss((50.0, -20.0, -60.0), (30.0, -10.0, -50.0), 60.0, 50.0)
    assert swatch(vivid).out_of_gamut_columns > 0


def test_swatch_rejects_bad_sizes(red_metallic) -> None:
    with pytest.raises(DesignInputError, match="border"):
        swatch(red_metallic, width=20, height=8, border=4)
    with pytest.raises(DesignInputError, match="width"):
        swatch(red_metallic, width=2)


def test_booklet_thumbnail_is_shaded_and_saves_as_png(tmp_path, red_metallic) -> None:
    img = booklet(red_metallic, 48)
    assert img.shape == (48, 48, 3)
    centre_column = img[8:40, 24].astype(float)
    assert centre_column.std() > 1.0  # shaded, not flat
    path = save_png(tmp_path / "booklet.png", img)
    with Image.open(path) as im:
        assert im.format == "PNG" and im.info.get("icc_profile")
    back = load_image(path)
    assert np.array_equal(np.round(back.pixels * 255).astype(np.uint8), img)
