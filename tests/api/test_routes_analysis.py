"""Analysis routes (QA): goniogeometric index, inverse trompe l'oeil, seam sweep, seam QA of two designs.

Every number is checked against the core function called directly and, for a Lambertian grey, against
the closed form of issue 6: with the light at θ_i, k = cos(θ_i + β) / cos θ_i and ΔL* = (L + 16)(k^⅓ − 1).
"""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest
from PIL import Image

from station.analysis import goniogeometric_index, seam_qa
from station.analysis.scenarios import SOLID_LIGHTS_DEG
from station.analysis.sweep import seam_sweep
from station.analysis.trompe import inverse_trompe_loeil
from station.model import FaceFlopTravelGloss
from tests.api.conftest import Api

V1 = "/api/v1"
GREY = {"face": [50.0, 0.0, 0.0], "flop": [50.0, 0.0, 0.0], "travel_deg": None}
BLUE = {
    "name": "blue metallic",
    "face": [60.0, -4.0, -42.0],
    "flop": [18.0, 2.0, -22.0],
    "travel_deg": 55.0,
    "gloss_gu": 88.0,
}
BLUE_PAINT = FaceFlopTravelGloss((60.0, -4.0, -42.0), (18.0, 2.0, -22.0), 55.0, 88.0, "blue metallic")


def _beta_closed_form(lightness: float, eps: float, light_deg: float, brighter: bool) -> float:
    """β at which |ΔL*| of a Lambertian grey reaches ε (ΔL* = (L + 16)(k^⅓ − 1), k = cos(θ_i + β)/cos θ_i)."""
    ti = math.radians(light_deg)
    k = (1.0 + (eps if brighter else -eps) / (lightness + 16.0)) ** 3
    c = k * math.cos(ti)
    return (
        math.inf if c > 1.0 else abs(math.degrees(math.acos(c) - ti))
    )  # light at the normal cannot brighten


def _count(api: Api, path: str) -> int:
    return api.client.get(f"{V1}/{path}", headers=api.auth("admin")).json()["count"]


def test_gg_index_equals_the_core_and_the_lambertian_closed_form(sqlite_api: Api) -> None:
    c, qa = sqlite_api.client, sqlite_api.auth("qa")
    for light in (0.0, 30.0, 60.0):
        body = {"paint": GREY, "lights_deg": [light], "views_deg": [0.0], "epsilon": 2.3, "method": "cie76"}
        r = c.post(f"{V1}/analyses/gg-index", json=body, headers=qa)
        assert r.status_code == 200, r.text
        got = r.json()
        grey = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None)
        assert got == json.loads(json.dumps(goniogeometric_index(grey, light, [0.0], epsilon=2.3).to_dict()))
        expected = min(_beta_closed_form(50.0, 2.3, light, True), _beta_closed_form(50.0, 2.3, light, False))
        assert got["reached"] is True
        assert got["beta_min_deg"] == pytest.approx(expected, abs=0.01)
    # effect paint, several lights, per geometry: same as the core
    body = {
        "paint": BLUE,
        "lights_deg": [30.0, 45.0],
        "method": "cie2000",
        "epsilon": 1.0,
        "per_geometry": True,
        "direction": "+",
        "hinge": "out-of-plane",
    }
    got = c.post(f"{V1}/analyses/gg-index", json=body, headers=qa).json()
    direct = goniogeometric_index(
        BLUE_PAINT, [30.0, 45.0], None, epsilon=1.0, method="cie2000", direction="+", hinge="out-of-plane"
    ).to_dict(per_geometry=True)
    assert got["beta_min_deg"] == pytest.approx(direct["beta_min_deg"])
    assert len(got["per_geometry"]) == len(direct["per_geometry"])


def test_gg_index_never_reached_says_so(sqlite_api: Api) -> None:
    body = {"paint": GREY, "lights_deg": [30.0], "views_deg": [0.0], "epsilon": 50.0, "beta_max_deg": 1.0}
    got = sqlite_api.client.post(
        f"{V1}/analyses/gg-index", json=body, headers=sqlite_api.auth("admin")
    ).json()
    assert got["reached"] is False and got["beta_min_deg"] is None and got["message"]


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"lights_deg": [95.0]}, "lights_deg"),
        ({"lights_deg": []}, "lights_deg"),
        ({"epsilon": 0.0}, "epsilon"),
        ({"method": "cie1900"}, "method"),
        ({"direction": "up"}, "direction"),
        ({"beta_max_deg": 90.0}, "beta_max_deg"),
        ({"beta_max_deg": 5e-324}, "beta_max_deg"),  # found by the schema fuzzer: a 500 before
        ({"paint": GREY | {"face": [50.0, 0.0, 999.0]}}, "paint"),
        (
            {"paint": GREY | {"flop": [20.0, 0.0, 0.0]}},
            "paint",
        ),  # refused by the model: no travel, face != flop
    ],
)
def test_gg_index_bad_input_is_422_naming_the_field(sqlite_api: Api, change: dict, field: str) -> None:
    body = {"paint": GREY, "lights_deg": [30.0]} | change
    r = sqlite_api.client.post(f"{V1}/analyses/gg-index", json=body, headers=sqlite_api.auth("qa"))
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"][:2] == ["body", field]


def test_trompe_loeil_equals_the_core(sqlite_api: Api) -> None:
    body = {"paint": GREY, "lights_deg": list(SOLID_LIGHTS_DEG), "beta_deg": -3.0, "objective": "rms"}
    r = sqlite_api.client.post(f"{V1}/analyses/trompe-loeil", json=body, headers=sqlite_api.auth("qa"))
    assert r.status_code == 200, r.text
    got = r.json()
    grey = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None)
    direct = inverse_trompe_loeil(grey, list(SOLID_LIGHTS_DEG), beta_deg=-3.0, objective="rms")
    assert got["paint"]["face"] == pytest.approx(list(direct.paint.face), abs=1e-6)
    assert got["seam_de_after"] == pytest.approx(list(direct.seam_de_after), abs=1e-6)
    assert got["rms_after"] <= got["rms_before"]
    bad = body | {"beta_deg": 0.0}
    r = sqlite_api.client.post(f"{V1}/analyses/trompe-loeil", json=bad, headers=sqlite_api.auth("qa"))
    assert r.status_code == 422 and "beta" in r.json()["detail"][0]["msg"]


def test_sweep_equals_the_core(sqlite_api: Api) -> None:
    body = {
        "paint": BLUE,
        "betas_deg": [1.0, 3.0, 8.0],
        "lights_deg": [15.0, 45.0],
        "views_deg": [-30.0, 0.0, 30.0],
    }
    r = sqlite_api.client.post(f"{V1}/analyses/sweep", json=body, headers=sqlite_api.auth("qa"))
    assert r.status_code == 200, r.text
    direct = seam_sweep(BLUE_PAINT, [1.0, 3.0, 8.0], [15.0, 45.0], [-30.0, 0.0, 30.0]).to_dict()
    got = r.json()
    np.testing.assert_allclose(got["delta_e"], direct["delta_e"], rtol=1e-12)
    assert np.asarray(got["delta_e"]).shape == (3, 2, 3)
    assert got["index_estimate_deg"] == direct["index_estimate_deg"]
    too_many = body | {"betas_deg": [1.0] * 17}
    r = sqlite_api.client.post(f"{V1}/analyses/sweep", json=too_many, headers=sqlite_api.auth("qa"))
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][:2] == ["body", "betas_deg"]


def test_seam_qa_of_two_designs_is_stored_and_audited(sqlite_api: Api) -> None:
    c = sqlite_api.client
    darker = BLUE | {"face": [57.0, -4.0, -42.0]}
    req = {"design_a": BLUE, "design_b": darker, "beta_deg": 8.0, "lights_deg": [30.0, 45.0]}
    r = c.post(f"{V1}/analyses/seam", json=req, headers=sqlite_api.auth("qa"))
    assert r.status_code == 201, r.text
    stored = r.json()
    direct = seam_qa(BLUE_PAINT, BLUE_PAINT.replace(face=(57.0, -4.0, -42.0)), 8.0, lights_deg=[30.0, 45.0])
    assert stored["result"]["seam_de_max"] == pytest.approx(max(direct.seam_de), rel=1e-9)
    assert stored["result"]["passed"] is direct.passed
    assert stored["inputs"]["design_b"]["face"] == [57.0, -4.0, -42.0]
    events = c.get(f"{V1}/audit", params={"entity": "analysis"}, headers=sqlite_api.auth("admin")).json()
    assert events["data"][0]["action"] == "analysis.seam_qa"
    png = c.get(f"{V1}/analyses/{stored['id']}/report.png", headers=sqlite_api.auth("stylist"))
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    assert png.content.startswith(b"\x89PNG") and Image.open(io.BytesIO(png.content)).size[0] > 400
    assert c.get(f"{V1}/analyses/999/report.png", headers=sqlite_api.auth("qa")).status_code == 404


def test_failed_seam_requests_store_nothing(sqlite_api: Api) -> None:
    c, qa = sqlite_api.client, sqlite_api.auth("qa")
    before = (_count(sqlite_api, "analyses"), _count(sqlite_api, "audit"))
    for bad in (
        {"design_a": BLUE, "design_b": BLUE, "beta_deg": 0.0},  # refused by the core: 0 < |β|
        {"design_a": BLUE, "measurement_a": 1, "design_b": BLUE, "beta_deg": 3.0},  # two sources for panel A
        {"design_b": BLUE, "beta_deg": 3.0},  # no panel A
        {"design_a": BLUE, "design_b": BLUE | {"travel_deg": 10.0}, "beta_deg": 3.0},
        {"design_a": BLUE, "design_b": BLUE, "beta_deg": 3.0, "aspecular_deg": [170.0], "lights_deg": [60.0]},
    ):
        r = c.post(f"{V1}/analyses/seam", json=bad, headers=qa)
        assert r.status_code == 422, (bad, r.text)
    assert (
        c.post(
            f"{V1}/analyses/seam", json={"measurement_a": 7, "design_b": BLUE, "beta_deg": 3.0}, headers=qa
        ).status_code
        == 404
    )
    assert (_count(sqlite_api, "analyses"), _count(sqlite_api, "audit")) == before
