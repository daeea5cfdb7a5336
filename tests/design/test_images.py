"""Safe image loading: size caps, decompression-bomb guard, colour profiles."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from station.design.errors import ImageLoadError
from station.design.images import load_image
from station.model.colorimetry import srgb_encode
from tests.design.iccgen import linear_srgb_profile


def _png(path, value=(128, 64, 32), size=(8, 6), **kw):
    Image.new("RGB", size, value).save(path, **kw)
    return path


def test_png_without_profile_is_assumed_srgb(tmp_path) -> None:
    img = load_image(_png(tmp_path / "a.png"))
    assert img.pixels.shape == (6, 8, 3)
    assert img.pixels[0, 0] == pytest.approx(np.array([128, 64, 32]) / 255)
    assert "assumed sRGB" in img.colour_note and not img.profile_converted


def test_embedded_non_srgb_profile_is_honoured(tmp_path) -> None:
    # the profile says the stored numbers are *linear* sRGB: 128/255 must come back sRGB-encoded
    path = _png(tmp_path / "lin.png", (128, 128, 128), icc_profile=linear_srgb_profile())
    img = load_image(path)
    assert img.profile_converted and "Linear sRGB test profile" in img.colour_note
    assert img.pixels[0, 0, 1] == pytest.approx(srgb_encode(128 / 255), abs=1.5 / 255)


def test_jpeg_and_greyscale_and_alpha(tmp_path) -> None:
    Image.new("RGB", (5, 5), (200, 100, 50)).save(tmp_path / "a.jpg", quality=95)
    assert load_image(tmp_path / "a.jpg").source_format == "JPEG"
    Image.new("L", (5, 5), 77).save(tmp_path / "g.png")
    assert load_image(tmp_path / "g.png").pixels[0, 0] == pytest.approx([77 / 255] * 3)
    Image.new("RGBA", (5, 5), (10, 20, 30, 0)).save(tmp_path / "rgba.png")
    assert load_image(tmp_path / "rgba.png").pixels.shape == (5, 5, 3)


def test_caps_and_bad_files(tmp_path) -> None:
    path = _png(tmp_path / "big.png", size=(40, 40))
    with pytest.raises(ImageLoadError, match="at most 100 pixels"):
        load_image(path, max_pixels=100)
    with pytest.raises(ImageLoadError, match="bytes"):
        load_image(path, max_bytes=10)
    with pytest.raises(ImageLoadError, match="existing"):
        load_image(tmp_path / "missing.png")
    (tmp_path / "junk.png").write_bytes(b"not an image at all")
    with pytest.raises(ImageLoadError, match="PNG or JPEG"):
        load_image(tmp_path / "junk.png")
    Image.new("RGB", (4, 4)).save(tmp_path / "a.gif")
    with pytest.raises(ImageLoadError, match="PNG or JPEG"):
        load_image(tmp_path / "a.gif")
    full = (tmp_path / "big.png").read_bytes()
    (tmp_path / "cut.png").write_bytes(full[: len(full) // 2])
    with pytest.raises(ImageLoadError):
        load_image(tmp_path / "cut.png")


@pytest.mark.parametrize("limit", [500, 1000])  # 1600 px: warning zone (> limit) and error zone (> 2 limit)
def test_pillow_decompression_bomb_guard_is_a_typed_error(tmp_path, monkeypatch, limit) -> None:
    # Pillow's guard is process-wide configuration; lowering it here stands in for a real bomb
    # (a multi-gigapixel file) that would be slow and memory-hungry to build in a unit test.
    path = _png(tmp_path / "bomb.png", size=(40, 40))
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", limit)
    with pytest.raises(ImageLoadError, match="decompression bomb"):
        load_image(path)
