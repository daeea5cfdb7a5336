"""Uploads are decoded at bounded size with bounded concurrency.

The pixel cap is read from the PNG header before a pixel is decoded (a header claiming 20 000 × 20 000
pixels over a few bytes is refused as 422 naming ``image``); an accepted upload stays 8-bit, so a
4-megapixel image costs its 3 bytes a pixel (12 MB), not the 96 MB of float64; and the routes decode at
most ``image_decode_concurrency`` uploads at once.
"""

from __future__ import annotations

import io
import struct
import threading
import tracemalloc
import zlib
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from station.api.services import styling as service
from station.design.images import decode_image, load_image
from station.design.moodboard import region
from tests.api.conftest import Api, make_api
from tests.processes import run
from tests.waiting import pause

V1 = "/api/v1"
PNG = {"Content-Type": "image/png"}
POINTS = {"face_x": 10, "face_y": 10, "flop_x": 1500, "flop_y": 10}


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def _png_header_only(width: int, height: int) -> bytes:
    """A PNG whose IHDR declares *width* × *height* 8-bit RGB and whose IDAT holds one row."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    idat = zlib.compress(b"\0" + b"\0" * 3 * 16)
    return b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", idat) + _chunk(b"IEND", b"")


def _two_tone(side: int = 2000) -> tuple[np.ndarray, bytes]:
    a = np.zeros((side, side, 3), np.uint8)
    a[:, : side // 2] = (200, 180, 40)
    a[:, side // 2 :] = (40, 30, 10)
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, format="PNG", optimize=True)
    return a, buf.getvalue()


@pytest.fixture
def slow_api(tmp_path: Path) -> Iterator[Api]:
    yield from make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, image_decode_concurrency=2)


@pytest.mark.parametrize(
    ("side", "refusal"),
    [
        (5000, f"at most {service.EYEDROP_MAX_PIXELS} pixels"),  # the route's cap, 25 megapixels
        (30_000, "not a decompression bomb"),  # 900 megapixels: Pillow's own guard, on open
    ],
)
def test_header_over_the_pixel_cap_is_422_before_decoding(sqlite_api: Api, side: int, refusal: str) -> None:
    bomb = _png_header_only(side, side)
    assert len(bomb) < 200
    r = sqlite_api.client.post(
        f"{V1}/styling/eyedrop", params=POINTS, content=bomb, headers=sqlite_api.auth("stylist") | PNG
    )
    assert r.status_code == 422, r.text
    detail = r.json()["detail"][0]
    assert "image" in detail["loc"]
    assert detail["ctx"]["accepted"] == refusal


def test_decoded_upload_is_8_bit_and_equals_the_source() -> None:
    source, data = _two_tone(64)
    img = decode_image(data, max_pixels=64 * 64, max_bytes=len(data))
    assert img.pixels.dtype == np.uint8 and img.full_scale == 255.0
    np.testing.assert_array_equal(img.pixels, source)
    np.testing.assert_allclose(img.to_float().pixels, source / 255.0)


def test_windowed_region_equals_the_full_image_disc() -> None:
    rng = np.random.default_rng(7)
    u8 = rng.integers(0, 256, (40, 50, 3), dtype=np.uint8)
    for xy, radius in (((0, 0), 3), ((49.7, 39.2), 5), ((20, 17), 0), ((25, 20), 64)):
        yy, xx = np.mgrid[0:40, 0:50]
        disc = (xx - int(xy[0])) ** 2 + (yy - int(xy[1])) ** 2 <= radius * radius
        expected = u8[disc] / 255.0  # brute force over the whole image
        np.testing.assert_allclose(region(u8, xy, radius), expected)
        np.testing.assert_allclose(region(u8 / 255.0, xy, radius), expected)


def test_eyedrop_of_a_4_megapixel_upload_allocates_a_bounded_amount(tmp_path: Path) -> None:
    """A 16 KB PNG of 2000 × 2000 pixels: the Python-side allocations of one eyedrop (Pillow's export
    and the 8-bit array, 3 bytes a pixel each) peak under 8 bytes a pixel (32 MB), where a float64
    decode alone is 24 bytes a pixel (96 MB)."""
    source, data = _two_tone(2000)
    assert len(data) < 32_000
    del source
    tracemalloc.start()
    try:
        out = service.eyedrop(
            data=data,
            max_bytes=1 << 20,
            face=(10, 10),
            flop=(1500, 10),
            gloss=(1000, 500),
            gloss_gu=50.0,
            travel_deg=75.0,
            radius=3,
            auto_swap=True,
        )
        _now, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 8 * 2000 * 2000, peak
    path = tmp_path / "board.png"
    path.write_bytes(data)
    from station.design.moodboard import eyedrop_design

    direct = eyedrop_design(load_image(path).pixels, (10, 10), (1500, 10), gloss_xy=(1000, 500))
    np.testing.assert_allclose(out["face_lab"], direct.face_lab)
    np.testing.assert_allclose(out["flop_lab"], direct.flop_lab)


def test_concurrent_uploads_are_decoded_at_most_n_at_once(
    slow_api: Api, monkeypatch: pytest.MonkeyPatch
) -> None:
    lock = threading.Lock()
    running, most = 0, 0
    real = service.eyedrop

    def counted(**kwargs: Any) -> Any:
        nonlocal running, most
        with lock:
            running += 1
            most = max(most, running)
        pause(0.15, "a slow decode holding its slot, so that the posts overlap")
        try:
            return real(**kwargs)
        finally:
            with lock:
                running -= 1

    monkeypatch.setattr(service, "eyedrop", counted)
    _source, data = _two_tone(32)
    params = {"face_x": 2, "face_y": 2, "flop_x": 30, "flop_y": 2}

    def post(_i: int) -> int:
        r = slow_api.client.post(
            f"{V1}/styling/eyedrop", params=params, content=data, headers=slow_api.auth("stylist") | PNG
        )
        return r.status_code

    with ThreadPoolExecutor(8) as pool:
        codes = list(pool.map(post, range(8)))
    assert codes == [200] * 8
    assert most == 2


def test_an_image_pillow_cannot_decode_is_an_image_load_error_and_one_cli_line(tmp_path: Path) -> None:
    """A compressed text chunk beyond Pillow's limit (``ValueError`` inside Pillow) is refused as an
    :class:`ImageLoadError` naming ``image``; ``station design eyedrop`` prints one line, exit 2."""
    import sys

    from station.design.errors import ImageLoadError
    from tests.api._images import bomb_png

    data = bomb_png()
    with pytest.raises(ImageLoadError) as caught:
        decode_image(data)
    assert caught.value.field == "image" and "Decompressed" in str(caught.value)
    gif = io.BytesIO()
    Image.new("RGB", (4, 4)).save(gif, "GIF")
    with pytest.raises(ImageLoadError, match="PNG or JPEG"):  # the guards' own refusals pass unchanged
        decode_image(gif.getvalue())
    path = tmp_path / "board.png"
    path.write_bytes(data)
    done = run(
        [
            sys.executable,
            "-m",
            "station.cli",
            "design",
            "eyedrop",
            str(path),
            "--face",
            "1,1",
            "--flop",
            "6,6",
        ],
        timeout=120,
        cwd=Path(__file__).resolve().parents[2],
    )
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "image" in lines[0] and "Traceback" not in done.stderr, done.stderr
