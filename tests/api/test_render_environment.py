"""``POST /api/v1/styling/render`` with an environment: built-in or uploaded HDR, stage options, refusals."""

from __future__ import annotations

import base64
import io

import numpy as np
import pytest
from PIL import Image

from station.model import FaceFlopTravelGloss
from station.model.gloss import ClearCoat
from station.render.hdr_io import write_hdr
from station.render.numpy_renderer import BACKGROUND
from station.render.procedural import procedural_environment
from station.render.scene_image import ENV_WIDTH, environment_from_bytes, render_design_image
from station.render.stage import Stage
from station.render.tonemap import to_display
from tests.api.conftest import Api

V1 = "/api/v1"
RED = {
    "name": "Red metallic",
    "face": [45.0, 40.0, 25.0],
    "flop": [20.0, 30.0, 15.0],
    "travel_deg": 60.0,
    "gloss_gu": 85.0,
}
RED_DESIGN = FaceFlopTravelGloss((45.0, 40.0, 25.0), (20.0, 30.0, 15.0), 60.0, 85.0, "Red metallic")


def _post(api: Api, body: dict):
    return api.client.post(f"{V1}/styling/render", json=body, headers=api.auth("stylist"))


def _png(r) -> np.ndarray:
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "image/png"
    return np.asarray(Image.open(io.BytesIO(r.content)).convert("RGB"))


def test_builtin_environment_equals_the_core(sqlite_api: Api) -> None:
    got = _png(_post(sqlite_api, {"design": RED, "environment": "sky", "size": 48, "rotation_deg": 30.0}))
    env = procedural_environment("sky", ENV_WIDTH)
    expected = render_design_image(
        [RED_DESIGN], env, stage=Stage(rotation_deg=30.0), coat=ClearCoat(), size=48
    )
    _same_picture(got, expected)
    # Without backdrop and ground the corners are the flat grey, and the coat switch changes the picture.
    plain = _png(
        _post(
            sqlite_api, {"design": RED, "environment": "sky", "size": 48, "backdrop": False, "ground": False}
        )
    )
    grey = to_display(np.full((1, 1, 3), BACKGROUND, np.float32))[0, 0]
    np.testing.assert_array_equal(plain[0, 0], grey)
    assert np.abs(got[0, 0].astype(int) - grey.astype(int)).max() > 5  # the backdrop shows the sky
    thesis = _png(
        _post(
            sqlite_api,
            {"design": RED, "environment": "sky", "size": 48, "coat_index": None, "rotation_deg": 30.0},
        )
    )
    assert np.abs(thesis.astype(int) - got.astype(int)).max() > 3


def test_uploaded_hdr(sqlite_api: Api, tmp_path, hdri_files) -> None:
    from station.render.environment import load_environment

    path = tmp_path / "small.hdr"
    write_hdr(path, load_environment(hdri_files[0]).downsampled(64).equirect)
    data = path.read_bytes()
    got = _png(
        _post(
            sqlite_api,
            {
                "design": RED,
                "environment_hdr": base64.b64encode(data).decode(),
                "size": 40,
                "coat_index": 1.6,
            },
        )
    )
    expected = render_design_image(
        [RED_DESIGN], environment_from_bytes(data), stage=Stage(), coat=ClearCoat(1.6), size=40
    )
    _same_picture(got, expected)


def _same_picture(got: np.ndarray, expected: np.ndarray) -> None:
    """Equal up to one 8-bit level on under 1 % of the values: the prefilter cache holds float16 maps, so a
    first (computed) and a later (cached) render may round a few values differently."""
    diff = np.abs(got.astype(int) - expected.astype(int))
    assert diff.max() <= 1 and (diff > 0).mean() < 0.01


def _field(r) -> list:
    assert r.status_code == 422, r.text
    return [d["loc"] for d in r.json()["detail"]]


def test_refusals_name_the_field(sqlite_api: Api, tmp_path) -> None:
    ok_hdr = tmp_path / "ok.hdr"
    write_hdr(ok_hdr, np.ones((8, 16, 3), np.float32))
    b64 = base64.b64encode(ok_hdr.read_bytes()).decode()
    assert ["body", "environment"] in _field(_post(sqlite_api, {"environment": "moon"}))
    assert ["body", "shape"] in _field(_post(sqlite_api, {"environment": "sky", "shape": "boat"}))
    assert ["body", "coat_index"] in _field(_post(sqlite_api, {"environment": "sky", "coat_index": 0.9}))
    assert ["body", "backdrop_blur_deg"] in _field(
        _post(sqlite_api, {"environment": "sky", "backdrop_blur_deg": 120.0})
    )
    assert ["body", "environment_hdr"] in _field(_post(sqlite_api, {"environment_hdr": "%%%not base64"}))
    png = io.BytesIO()
    Image.new("RGB", (16, 8)).save(png, format="PNG")
    r = _post(sqlite_api, {"environment_hdr": base64.b64encode(png.getvalue()).decode()})
    assert ["body", "environment_hdr"] in _field(r) and "low-dynamic-range" in r.text
    assert ["body", "environment_hdr"] in _field(
        _post(sqlite_api, {"environment": "sky", "environment_hdr": b64})
    )
    # A header claiming 4096 × 2048 pixels is refused before any pixel is decoded.
    huge = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2048 +X 4096\n" + b"\x00" * 64
    r = _post(sqlite_api, {"environment_hdr": base64.b64encode(huge).decode()})
    assert ["body", "environment_hdr"] in _field(r) and "4096x2048" in r.text
    # Not equirectangular (16 × 16).
    sq = tmp_path / "sq.hdr"
    write_hdr(sq, np.ones((16, 16, 3), np.float32))
    r = _post(sqlite_api, {"environment_hdr": base64.b64encode(sq.read_bytes()).decode()})
    assert ["body", "environment_hdr"] in _field(r)


def test_upload_byte_cap() -> None:
    from station.render.errors import RenderInputError
    from station.render.scene_image import MAX_UPLOAD_BYTES

    with pytest.raises(RenderInputError, match="environment_hdr"):
        environment_from_bytes(b"#?RADIANCE\n" + b"\x00" * MAX_UPLOAD_BYTES)
    with pytest.raises(RenderInputError, match="empty"):
        environment_from_bytes(b"")
