"""Scene options of ``POST /api/v1/styling/render`` and the environment-lit goniogeometric index
(``POST /api/v1/analyses/gg-index/environment``) over real HTTP against a running ``station serve``."""

from __future__ import annotations

import base64
import io
import json
import math
from collections.abc import Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

from station.analysis import goniogeometric_index
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.design_io import default_flakes
from station.model.difference import delta_e
from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render.cubemap import equirect_directions
from station.render.flakes import flake_lod
from station.render.hdr_io import write_hdr
from station.render.numpy_renderer import gbuffer
from station.render.procedural import procedural_environment
from station.render.scene_image import ENV_WIDTH, render_scene_image
from station.render.shapes import Scene
from station.render.stage import Stage
from tests.serve_process import ServeProcess, ServeStartError

#: A ``station serve`` child for the module: a long file, run early (tests/conftest.py orders the files).
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
V1 = "/api/v1"
SILVER = {
    "name": "Silver",
    "face": [90.0, 0.0, -1.0],
    "flop": [30.0, 0.0, -2.0],
    "travel_deg": 60.0,
    "gloss_gu": 88.0,
}
SILVER_DESIGN = FaceFlopTravelGloss((90.0, 0.0, -1.0), (30.0, 0.0, -2.0), 60.0, 88.0, "Silver")
GREY = {
    "name": "Grey",
    "face": [55.0, 0.0, 0.0],
    "flop": [55.0, 0.0, 0.0],
    "travel_deg": None,
    "gloss_gu": 60.0,
}


class Service:
    def __init__(self, base: str, token: str) -> None:
        self.base, self.token = base, token

    def post(self, path: str, body: dict) -> httpx.Response:
        return httpx.post(
            f"{self.base}{V1}{path}",
            json=body,
            headers={"Authorization": f"Bearer {self.token}"},
            timeout=120,
        )


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Service]:
    svc = ServeProcess(
        tmp_path_factory.mktemp("serve") / "data", ("--no-demo-library",), cwd=REPO, start_timeout_s=60
    )
    try:
        svc.start()
    except ServeStartError as exc:
        pytest.fail(str(exc))
    try:
        yield Service(svc.base, svc.token)
    finally:
        svc.stop()


def _png(r: httpx.Response) -> np.ndarray:
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "image/png"
    return np.asarray(Image.open(io.BytesIO(r.content)).convert("RGB"))


def _decode(img8: np.ndarray) -> np.ndarray:
    """8-bit sRGB to linear sRGB (IEC 61966-2-1): the displayed colour, averaged over areas below."""
    c = img8.astype(float) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _field(r: httpx.Response) -> list:
    assert r.status_code == 422, r.text
    return [d["loc"] for d in r.json()["detail"]]


def _same(got: np.ndarray, expected: np.ndarray) -> None:
    """Equal up to one 8-bit level on under 1 % of values (float16 maps in the prefilter cache)."""
    diff = np.abs(got.astype(int) - expected.astype(int))
    assert diff.max() <= 1 and (diff > 0).mean() < 0.01


def test_flakes_and_their_level_of_detail(service: Service) -> None:
    body = {"design": SILVER, "environment": "sky", "size": 160, "shape": "speedshape"}
    off = _png(service.post("/styling/render", body))
    r = service.post("/styling/render", {**body, "flakes": True})
    on = _png(r)
    # The header is the level of detail's own choice for this view, and the picture the core's.
    layer = default_flakes(SILVER_DESIGN)
    assert layer is not None
    choice = flake_lod(layer, Scene("speedshape").view_camera, 160)
    assert choice.on and r.headers["X-Flakes"] == choice.reason
    env = procedural_environment("sky", ENV_WIDTH)
    core = render_scene_image([SILVER_DESIGN], env, stage=Stage(), coat=ClearCoat(), size=160, flakes=layer)
    _same(on, core.image)
    # Sparkle pixel to pixel (8 levels at most here: a pixel shows the flakes of a cell of 16 pixels or more,
    # station.render.flakes.CELL_PIXELS), the same mean colour over 16 × 16 areas of the body (ΔE00 ≤ 0.5).
    assert np.abs(on.astype(int) - off.astype(int)).max() > 5
    lin_on, lin_off = _decode(on), _decode(off)
    body_px = gbuffer(Scene("speedshape"), 160, 160).mask
    blocks = []
    for i in range(0, 160, 16):
        for j in range(0, 160, 16):
            if body_px[i : i + 16, j : j + 16].all():
                blocks.append(
                    (
                        lin_on[i : i + 16, j : j + 16].mean((0, 1)),
                        lin_off[i : i + 16, j : j + 16].mean((0, 1)),
                    )
                )
    assert len(blocks) >= 8
    a, b = np.array([x for x, _ in blocks]), np.array([y for _, y in blocks])
    assert delta_e(linear_srgb_to_lab(a), linear_srgb_to_lab(b), method="cie2000").max() <= 0.5
    # A smaller picture: thousands of flakes per pixel, switched off, and said so; the picture is flake-free.
    small = service.post("/styling/render", {**body, "size": 48, "flakes": True})
    assert "off" in small.headers["X-Flakes"] and "smaller than a pixel" in small.headers["X-Flakes"]
    _same(_png(small), _png(service.post("/styling/render", {**body, "size": 48})))
    # A solid has no flake layer; explicit parameters override the defaults.
    solid = service.post("/styling/render", {**body, "design": GREY, "size": 32, "flakes": True})
    assert solid.status_code == 200 and solid.headers["X-Flakes"] == "no flake layer"
    coarse = service.post(
        "/styling/render",
        {**body, "size": 48, "flakes": True, "flake_layer": {"size_um": 400.0, "density_per_mm2": 5.0}},
    )
    want = flake_lod(FlakeLayer(400.0, 5.0, 8.0, 0.5), Scene("speedshape").view_camera, 48)
    assert coarse.headers["X-Flakes"] == want.reason and want.on


def test_lod_mesh_and_scene_options(service: Service) -> None:
    body = {"design": SILVER, "environment": "booth", "size": 64}
    r = service.post("/styling/render", {**body, "lod_de": 2.0})
    env = procedural_environment("booth", ENV_WIDTH)
    # the core's picture with its level of detail (station.render.scene_image.scene_lod): the same choice
    # and the same picture as the service's
    core = render_scene_image([SILVER_DESIGN], env, stage=Stage(), coat=ClearCoat(), size=64, lod_de=2.0)
    assert json.loads(r.headers["X-Lod"]) == core.lod and core.lod is not None and "lobes" in core.lod
    _same(_png(r), core.image)
    # Exposure +1 EV against 0; backdrop blur and rotation change the picture's background.
    base = _png(service.post("/styling/render", body))
    brighter = _png(service.post("/styling/render", {**body, "exposure_ev": 1.0}))
    assert brighter.astype(int).sum() > base.astype(int).sum()
    turned = _png(service.post("/styling/render", {**body, "rotation_deg": 90.0, "backdrop_blur_deg": 30.0}))
    assert np.abs(turned[:8].astype(int) - base[:8].astype(int)).max() > 3
    # The built-in car: the GL engine when the service has an OpenGL stack, else 503 saying why.
    car = service.post("/styling/render", {**body, "mesh": "car", "size": 96})
    if car.status_code == 503:
        assert "OpenGL" in car.text
        return
    img = _png(car)
    assert car.headers["X-Render-Engine"] == "gl"
    core_car = render_scene_image([SILVER_DESIGN], env, stage=Stage(), coat=ClearCoat(), size=96, mesh="car")
    assert np.abs(img.astype(int) - core_car.image.astype(int)).max() <= 2
    assert (
        np.abs(
            img.astype(int) - _png(service.post("/styling/render", {**body, "size": 96})).astype(int)
        ).max()
        > 20
    )


def test_scene_options_are_validated_naming_the_field(service: Service) -> None:
    env = {"environment": "sky", "size": 32}
    cases: list[tuple[dict[str, object], list[str]]] = [
        ({"flakes": "yes"}, ["body", "flakes"]),
        ({"flakes": True, "flake_layer": {"spread_deg": 90.0}}, ["body", "flake_layer", "spread_deg"]),
        ({"flakes": True, "flake_layer": {"size_um": 0.5}}, ["body", "flake_layer", "size_um"]),
        ({"flake_layer": {"size_um": 20.0}}, ["body", "flake_layer"]),  # parameters without flakes
        ({"mesh": "boat"}, ["body", "mesh"]),
        ({"lod_de": 0.0}, ["body", "lod_de"]),
        ({"lod_de": 11.0}, ["body", "lod_de"]),
        ({"exposure_ev": 11.0}, ["body", "exposure_ev"]),
        ({"rotation_deg": 400.0}, ["body", "rotation_deg"]),
        ({"backdrop_blur_deg": -1.0}, ["body", "backdrop_blur_deg"]),
        ({"coat_index": 3.5}, ["body", "coat_index"]),
        ({"ground": "no"}, ["body", "ground"]),
    ]
    for extra, loc in cases:
        r = service.post("/styling/render", {**env, **extra})
        assert loc in _field(r), (extra, r.text)
    r = service.post("/styling/render", {**env, "flakes": True, "flake_layer": {"spread_deg": 90.0}})
    assert "45" in r.text  # the range is named
    # Scene options need an environment render: the point-light scene refuses them by name.
    assert ["body", "flakes"] in _field(service.post("/styling/render", {"flakes": True}))
    assert ["body", "mesh"] in _field(service.post("/styling/render", {"mesh": "car"}))


def _one_light_hdr(tmp_path: Path, theta_deg_row: int) -> tuple[str, float]:
    """An equirect map 33 × 66, black but one pixel whose centre lies in the world x–y plane (z = 0,
    u = 0.75): a single point light at polar angle θ of that pixel, seen from a panel facing up."""
    h, w = 33, 66
    img = np.zeros((h, w, 3), np.float32)
    img[theta_deg_row, 49] = 1000.0
    d = equirect_directions(h, w)[theta_deg_row, 49]
    assert abs(d[2]) < 1e-9 and d[0] > 0
    path = tmp_path / "one.hdr"
    write_hdr(path, img)
    return base64.b64encode(path.read_bytes()).decode(), math.degrees(math.atan2(d[0], d[1]))


def test_environment_index_of_one_light_is_the_point_light_index(service: Service, tmp_path) -> None:
    """An uploaded map with one lit pixel is a point light: the environment-lit index equals the
    point-light index (a different shading path, station.analysis.shading.point_colour) at that angle."""
    paint = {
        "name": "Blue",
        "face": [62.0, -4.0, -38.0],
        "flop": [24.0, 1.0, -20.0],
        "travel_deg": 70.0,
        "gloss_gu": 88.0,
    }
    design = FaceFlopTravelGloss((62.0, -4.0, -38.0), (24.0, 1.0, -20.0), 70.0, 88.0, "Blue")
    b64, theta = _one_light_hdr(tmp_path, 5)
    views = [-20.0, 0.0, 25.0]
    r = service.post(
        "/analyses/gg-index/environment", {"paint": paint, "environment_hdr": b64, "views_deg": views}
    )
    assert r.status_code == 200, r.text
    got = r.json()
    assert got["samples"] == 1 and got["reached"]
    # The light lies at +x of the panel's frame: polar angle +θ or −θ depending on the sign convention;
    # the point-light index must match one of them to the stated resolution, and not the other.
    plus = goniogeometric_index(design, theta, views).beta_min_deg
    minus = goniogeometric_index(design, -theta, views).beta_min_deg
    assert plus is not None and minus is not None and abs(plus - minus) > 0.01
    assert min(abs(got["beta_min_deg"] - plus), abs(got["beta_min_deg"] - minus)) < 1e-4
    # Built-in environments, turned and on a vertical panel, are reachable too.
    sky = service.post(
        "/analyses/gg-index/environment",
        {
            "paint": paint,
            "environment": "sky",
            "rotation_deg": 45.0,
            "panel": "front",
            "views_deg": [0.0, 30.0],
        },
    )
    assert (
        sky.status_code == 200
        and sky.json()["environment"].startswith("sky")
        and sky.json()["samples"] == 2048
    )
    assert 0.0 < sky.json()["beta_min_deg"] < 30.0


def test_environment_index_refusals(service: Service) -> None:
    paint = {
        "name": "Grey",
        "face": [55.0, 0.0, 0.0],
        "flop": [55.0, 0.0, 0.0],
        "travel_deg": None,
        "gloss_gu": 60.0,
    }
    post = lambda extra: service.post("/analyses/gg-index/environment", {"paint": paint, **extra})  # noqa: E731
    assert ["body", "environment"] in _field(post({}))
    assert ["body", "environment"] in _field(post({"environment": "moon"}))
    assert ["body", "method"] in _field(post({"environment": "sky", "method": "din6175"}))
    assert ["body", "panel"] in _field(post({"environment": "sky", "panel": "side"}))
    assert ["body", "rotation_deg"] in _field(post({"environment": "sky", "rotation_deg": 720.0}))
    assert ["body", "environment_hdr"] in _field(post({"environment_hdr": "%%%"}))
    assert ["body", "beta_max_deg"] in _field(post({"environment": "sky", "beta_max_deg": 95.0}))
    assert ["body", "beta_max_deg"] in _field(post({"environment": "sky", "beta_max_deg": 5e-324}))
