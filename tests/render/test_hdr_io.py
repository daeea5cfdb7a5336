"""HDR reading: real files, round trips through our writers, and every kind of bad file."""

from __future__ import annotations

import numpy as np
import pytest

from station.errors import InputError
from station.render.environment import Environment, load_environment
from station.render.errors import EnvironmentFileError, RenderError
from station.render.hdr_io import float_to_rgbe, read_hdr_image, rgbe_to_float, write_exr, write_hdr


def _image(h: int = 16, w: int = 32) -> np.ndarray:
    rng = np.random.default_rng(3)
    img = rng.lognormal(0.0, 2.0, size=(h, w, 3)).astype(np.float32)
    img[2, 3:12] = 5.0  # a run for the RLE encoder
    return img


def test_real_hdri_files_load(hdri_files):
    for path in hdri_files:
        env = load_environment(path)
        h, w = env.equirect.shape[:2]
        assert w == 2 * h
        assert np.isfinite(env.equirect).all() and env.equirect.min() >= 0
        # Real photographs span far more than 8 bits: the sun/lamps are ≥ 100× the median.
        assert env.equirect.max() > 100 * np.median(env.equirect)


@pytest.mark.parametrize("rle", [True, False])
def test_radiance_round_trip_within_rgbe_precision(tmp_path, rle):
    img = _image()
    path = tmp_path / "t.hdr"
    write_hdr(path, img, rle=rle)
    back = read_hdr_image(path)
    # RGBE keeps 8 mantissa bits of the largest channel: error ≤ 2^-8 of the pixel max (+ half step).
    tol = img.max(axis=-1, keepdims=True) / 128.0
    assert np.all(np.abs(back - img) <= tol)


def test_rgbe_decoding_matches_definition():
    rgbe = np.array([[128, 64, 0, 129], [255, 255, 255, 0]], dtype=np.uint8)
    out = rgbe_to_float(rgbe)
    assert out[0] == pytest.approx([128.5 / 128, 64.5 / 128, 0.5 / 128])  # 2^(129-136) = 1/128
    assert (out[1] == 0).all()
    assert rgbe_to_float(float_to_rgbe(np.array([1.0, 0.5, 0.25]))) == pytest.approx(
        [1.0, 0.5, 0.25], abs=1 / 128
    )


def test_exposure_header_is_divided_out(tmp_path):
    img = _image()
    path = tmp_path / "e.hdr"
    write_hdr(path, img)
    data = path.read_bytes().replace(b"FORMAT=", b"EXPOSURE=2.0\nFORMAT=", 1)
    path.write_bytes(data)
    plain = tmp_path / "p.hdr"
    write_hdr(plain, img)
    assert read_hdr_image(path) == pytest.approx(read_hdr_image(plain) / 2.0)


@pytest.mark.parametrize("half", [False, True])
def test_exr_round_trip(tmp_path, half):
    img = _image()
    path = tmp_path / "t.exr"
    write_exr(path, img, half=half)
    back = read_hdr_image(path)
    assert back == pytest.approx(img, rel=1e-3 if half else 1e-7)


def _expect_bad(path, fragment):
    with pytest.raises(EnvironmentFileError) as info:
        read_hdr_image(path)
    assert fragment in str(info.value)
    assert isinstance(info.value, InputError) and isinstance(info.value, RenderError)


def test_ldr_png_rejected(tmp_path):
    from PIL import Image

    path = tmp_path / "ldr.png"
    Image.fromarray(np.zeros((8, 16, 3), np.uint8)).save(path)
    _expect_bad(path, "low-dynamic-range")


def test_truncated_radiance_rejected(tmp_path):
    path = tmp_path / "t.hdr"
    write_hdr(path, _image())
    path.write_bytes(path.read_bytes()[:-300])
    _expect_bad(path, "truncated")


def test_truncated_real_file_rejected(tmp_path, hdri_files):
    path = tmp_path / "cut.hdr"
    path.write_bytes(hdri_files[0].read_bytes()[:200_000])
    _expect_bad(path, "truncated")


def test_truncated_exr_rejected(tmp_path):
    path = tmp_path / "t.exr"
    write_exr(path, _image())
    path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    _expect_bad(path, "OpenEXR could not read")


def test_absurd_dimensions_rejected(tmp_path):
    path = tmp_path / "huge.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 200000\n" + b"\0" * 64)
    _expect_bad(path, "absurd dimensions")


def test_garbage_and_missing_files_rejected(tmp_path):
    path = tmp_path / "x.hdr"
    path.write_bytes(b"hello world, not an image")
    _expect_bad(path, "unrecognised")
    _expect_bad(tmp_path / "missing.hdr", "cannot read")


@pytest.mark.parametrize(("value", "fragment"), [(np.nan, "NaN"), (-1.0, "negative"), (1e30, "absurd")])
def test_absurd_values_rejected(tmp_path, value, fragment):
    img = _image()
    img[1, 1, 1] = value
    path = tmp_path / "bad.exr"
    write_exr(path, img)
    _expect_bad(path, fragment)


def test_black_and_non_equirect_rejected(tmp_path):
    path = tmp_path / "black.exr"
    write_exr(path, np.zeros((8, 16, 3), np.float32))
    _expect_bad(path, "black")
    with pytest.raises(EnvironmentFileError, match="width = 2"):
        Environment("square", np.ones((16, 16, 3), np.float32))
