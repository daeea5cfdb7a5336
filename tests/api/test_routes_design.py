"""Styling routes (stylist): variations, palette swatch PNG, eyedroppers and sketch fit on uploaded images.

Each result is compared with the ``station.design`` function called directly on the same pixels, and the
eyedropper's Lab with the sRGB → Lab conversion of the uniform patch it sampled.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from station.design.moodboard import eyedrop_design
from station.design.palette import swatch
from station.design.scene import builtin_scene, shade, srgb_encode, to_uint8
from station.design.sketch import fit_point_light
from station.design.variations import variations
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab, srgb_decode
from station.model.design_io import design_to_dict
from tests.api.conftest import Api

V1 = "/api/v1"
BLUE = {
    "name": "Blue metallic",
    "face": [62.0, -4.0, -38.0],
    "flop": [24.0, 1.0, -20.0],
    "travel_deg": 70.0,
    "gloss_gu": 50.0,
}
BLUE_DESIGN = FaceFlopTravelGloss((62.0, -4.0, -38.0), (24.0, 1.0, -20.0), 70.0, 50.0, "Blue metallic")
PNG = {"Content-Type": "image/png"}


def _png(pixels: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, format="PNG")
    return buf.getvalue()


def _audit_count(api: Api) -> int:
    return api.client.get(f"{V1}/audit", headers=api.auth("admin")).json()["count"]


def test_variations_equal_the_core(sqlite_api: Api) -> None:
    for category, degree in (("face", 5.0), ("travel-gloss", 10.0)):
        r = sqlite_api.client.post(
            f"{V1}/styling/variations",
            json={"design": BLUE, "degree": degree, "category": category},
            headers=sqlite_api.auth("stylist"),
        )
        assert r.status_code == 200, r.text
        ring = variations(BLUE_DESIGN, degree, category)  # type: ignore[arg-type]
        got = r.json()
        assert got["centre"] == design_to_dict(ring.centre)
        assert [v["label"] for v in got["variations"]] == [v.label for v in ring.variations]
        assert [v["design"] for v in got["variations"]] == [
            None if v.design is None else design_to_dict(v.design) for v in ring.variations
        ]
    r = sqlite_api.client.post(
        f"{V1}/styling/variations", json={"design": BLUE, "degree": 0.0}, headers=sqlite_api.auth("stylist")
    )
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][:2] == ["body", "degree"]


def test_swatch_png_is_the_core_swatch(sqlite_api: Api) -> None:
    body = {"design": BLUE, "width": 120, "height": 24, "border": 3}
    r = sqlite_api.client.post(f"{V1}/styling/swatch", json=body, headers=sqlite_api.auth("stylist"))
    assert r.status_code == 200 and r.headers["content-type"] == "image/png"
    sw = swatch(BLUE_DESIGN, 120, 24, 3)
    np.testing.assert_array_equal(np.asarray(Image.open(io.BytesIO(r.content))), sw.pixels)
    assert int(r.headers["x-out-of-gamut-columns"]) == sw.out_of_gamut_columns
    booklet = sqlite_api.client.post(
        f"{V1}/styling/swatch",
        json={"design": BLUE, "kind": "booklet", "size": 48},
        headers=sqlite_api.auth("admin"),
    )
    assert Image.open(io.BytesIO(booklet.content)).size == (48, 48)
    bad = sqlite_api.client.post(
        f"{V1}/styling/swatch",
        json=body | {"border": 12},  # 2·border >= height
        headers=sqlite_api.auth("stylist"),
    )
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"][:2] == ["body", "border"]


def test_eyedrop_on_an_uploaded_image(sqlite_api: Api) -> None:
    img = np.zeros((40, 60, 3), np.uint8)
    img[:, :30] = (200, 150, 90)  # light face colour on the left
    img[:, 30:] = (60, 40, 20)  # dark flop colour on the right
    params = {"face_x": 10, "face_y": 20, "flop_x": 45, "flop_y": 20, "travel_deg": 60.0, "radius": 3}
    r = sqlite_api.client.post(
        f"{V1}/styling/eyedrop", params=params, content=_png(img), headers=sqlite_api.auth("stylist") | PNG
    )
    assert r.status_code == 200, r.text
    got = r.json()
    patch = lambda rgb: linear_srgb_to_lab(srgb_decode(np.array(rgb) / 255.0))  # noqa: E731
    np.testing.assert_allclose(got["face_lab"], patch((200, 150, 90)), atol=1e-6)
    np.testing.assert_allclose(got["flop_lab"], patch((60, 40, 20)), atol=1e-6)
    direct = eyedrop_design(img / 255.0, (10, 20), (45, 20), travel_deg=60.0, radius=3)
    assert got["design"] == design_to_dict(direct.design) and got["swapped"] is False
    assert "sRGB" in got["colour"]
    # the swap: face picked on the dark side
    swapped = sqlite_api.client.post(
        f"{V1}/styling/eyedrop",
        params=params | {"face_x": 45, "flop_x": 10},
        content=_png(img),
        headers=sqlite_api.auth("stylist") | PNG,
    ).json()
    assert swapped["swapped"] is True


def test_eyedrop_refusals_store_nothing(sqlite_api: Api) -> None:
    before = _audit_count(sqlite_api)
    auth = sqlite_api.auth("stylist") | PNG
    img = _png(np.full((20, 20, 3), 128, np.uint8))
    params = {"face_x": 5, "face_y": 5, "flop_x": 10, "flop_y": 10}
    outside = sqlite_api.client.post(
        f"{V1}/styling/eyedrop", params=params | {"flop_x": 25}, content=img, headers=auth
    )
    assert outside.status_code == 422 and outside.json()["detail"][0]["loc"][:2] == ["body", "flop_x"]
    junk = sqlite_api.client.post(
        f"{V1}/styling/eyedrop", params=params, content=b"not an image", headers=auth
    )
    assert junk.status_code == 422 and junk.json()["detail"][0]["loc"][:2] == ["body", "image"]
    empty = sqlite_api.client.post(f"{V1}/styling/eyedrop", params=params, content=b"", headers=auth)
    assert empty.status_code == 422
    missing = sqlite_api.client.post(f"{V1}/styling/eyedrop", params={"face_x": 5}, content=img, headers=auth)
    assert missing.status_code == 422 and missing.json()["detail"][0]["loc"][:2] == ["query", "face_y"]
    bomb = _png(np.zeros((2000, 2001, 3), np.uint8))  # a few kB of PNG, just over 4 megapixels decoded
    assert len(bomb) < 100_000
    r = sqlite_api.client.post(f"{V1}/styling/eyedrop", params=params, content=bomb, headers=auth)
    assert r.status_code == 422 and "4000000 pixels" in r.json()["detail"][0]["msg"]
    huge = sqlite_api.client.post(
        f"{V1}/styling/eyedrop", params=params, content=b"\0" * 1_100_000, headers=auth
    )
    assert huge.status_code == 413  # the service's body cap (1 MiB by default)
    assert _audit_count(sqlite_api) == before


@pytest.mark.parametrize("scene", ["sphere-point", "panel-point"])
def test_sketch_fit_equals_the_core(sqlite_api: Api, scene: str) -> None:
    s = builtin_scene(scene, 48)
    art = to_uint8(srgb_encode(shade(s, BLUE_DESIGN)))  # the design itself, painted over the scene
    rendered = sqlite_api.client.post(
        f"{V1}/styling/render",
        json={"design": BLUE, "scene": scene, "size": 48},
        headers=sqlite_api.auth("stylist"),
    )
    assert rendered.status_code == 200 and rendered.headers["content-type"] == "image/png"
    np.testing.assert_array_equal(np.asarray(Image.open(io.BytesIO(rendered.content))), art)
    r = sqlite_api.client.post(
        f"{V1}/styling/sketch-fit",
        params={"scene": scene},
        content=_png(art),
        headers=sqlite_api.auth("stylist") | PNG,
    )
    assert r.status_code == 200, r.text
    got = r.json()
    silver = FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 50.0, "silver")
    direct = fit_point_light(s, art / 255.0, srgb_encode(shade(s, silver)))
    assert got["failed"] is direct.failed is False
    assert got["design"]["face"] == pytest.approx(list(direct.design.face), abs=1e-9)
    assert got["rms_de"] == pytest.approx(direct.rms_de, abs=1e-9)
    np.testing.assert_allclose(
        got["design"]["face"], BLUE_DESIGN.face, atol=1.5
    )  # recovers the painted design
    not_square = sqlite_api.client.post(
        f"{V1}/styling/sketch-fit", content=_png(art[:, :40]), headers=sqlite_api.auth("stylist") | PNG
    )
    assert not_square.status_code == 422 and not_square.json()["detail"][0]["loc"][:2] == ["body", "art"]
