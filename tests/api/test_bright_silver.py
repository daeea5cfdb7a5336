"""The bright silver (L*15 = 125) through the service routes: designs create/edit, variations, styling,
formulation and analysis; L* 250 is a 422 naming the field from every route that takes a design.

Each answer is compared with an independent expectation: the stored design read back, the documented
variation steps, a brute-force ColorSnap over the stored rows, the colorant model's own prediction of
the returned recipe, and the analysis core called directly on the same paint.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image
from sqlalchemy import insert

from db.models import LibraryPaint
from station.analysis import goniogeometric_index
from station.api.services.library import library_rows
from station.formulate.colorants import predict_lab
from station.formulate.demo import generate_library
from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.design_io import design_to_dict
from station.model.difference import delta_e
from tests.api.conftest import Api

V1 = "/api/v1"


def _body(design: FaceFlopTravelGloss) -> dict:
    d = design_to_dict(design)
    return {k: d[k] for k in ("name", "face", "flop", "travel_deg", "gloss_gu")}


@pytest.fixture
def lib_api(sqlite_api: Api) -> tuple[Api, list[dict]]:
    rows = library_rows(generate_library(n_solid=30, n_metallic=30, n_pearl=10, seed=5))
    with sqlite_api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
        session.execute(insert(LibraryPaint), rows)
        session.commit()
    return sqlite_api, rows


def test_designs_create_and_edit(sqlite_api: Api, bright_silver: FaceFlopTravelGloss) -> None:
    c, auth = sqlite_api.client, sqlite_api.auth("stylist")
    r = c.post(f"{V1}/designs", json={"name": "Silver", "design": _body(bright_silver)}, headers=auth)
    assert r.status_code == 201, r.text
    d = r.json()
    assert d["design"]["face"] == [125.0, -0.6, -1.8] and d["design"]["flop"] == [38.0, -0.3, -3.2]
    lighter = _body(bright_silver) | {"face": [130.0, -0.6, -1.8]}
    r = c.put(f"{V1}/designs/{d['id']}", json={"design": lighter}, headers=auth)
    assert r.status_code == 200, r.text
    assert r.json()["latest_version"] == 2 and r.json()["design"]["face"][0] == 130.0


def test_variations_and_styling(sqlite_api: Api, bright_silver: FaceFlopTravelGloss) -> None:
    c, auth = sqlite_api.client, sqlite_api.auth("stylist")
    r = c.post(
        f"{V1}/styling/variations",
        json={"design": _body(bright_silver), "degree": 5.0, "category": "face"},
        headers=auth,
    )
    assert r.status_code == 200, r.text
    ring = {v["label"]: v for v in r.json()["variations"]}
    assert ring["lighter"]["design"]["face"] == pytest.approx([130.0, -0.6, -1.8])
    assert ring["darker"]["design"]["face"] == pytest.approx([120.0, -0.6, -1.8])
    sw = c.post(
        f"{V1}/styling/swatch", json={"design": _body(bright_silver), "width": 64, "height": 16}, headers=auth
    )
    assert sw.status_code == 200 and Image.open(io.BytesIO(sw.content)).size == (64, 16)
    png = c.post(
        f"{V1}/styling/render",
        json={"design": _body(bright_silver), "scene": "sphere-point", "size": 32},
        headers=auth,
    )
    assert png.status_code == 200
    pixels = np.asarray(Image.open(io.BytesIO(png.content)))
    assert pixels.shape[:2] == (32, 32) and pixels.max() > 0


def test_formulation(lib_api: tuple[Api, list[dict]], bright_silver: FaceFlopTravelGloss) -> None:
    api, rows = lib_api
    target = bright_silver.lab_at(np.array(ANGLES_3))
    r = api.client.post(
        f"{V1}/formulation/snap",
        json={"design": _body(bright_silver), "k": 2, "metric": "cie76"},
        headers=api.auth("chemist"),
    )
    assert r.status_code == 200, r.text
    stored = np.array(
        [[row["lab"][[float(a) for a in row["angles_deg"]].index(a)] for a in ANGLES_3] for row in rows]
    )
    sums = np.linalg.norm(stored - target[None], axis=-1).sum(-1)
    order = np.argsort(sums, kind="stable")[:2]
    assert [m["code"] for m in r.json()["matches"]] == [rows[i]["code"] for i in order]
    r = api.client.post(
        f"{V1}/formulation/formulate", json={"design": _body(bright_silver)}, headers=api.auth("chemist")
    )
    assert r.status_code == 200, r.text
    got = r.json()
    from station.formulate.colorants import default_database

    conc = np.array([got["recipe"].get(n, 0.0) for n in default_database().names])
    np.testing.assert_allclose(
        got["de_per_angle"], delta_e(predict_lab(conc, ANGLES_3), target, "cie2000"), atol=1e-3
    )


def test_analysis(sqlite_api: Api, bright_silver: FaceFlopTravelGloss) -> None:
    body = {
        "paint": _body(bright_silver),
        "lights_deg": [45.0],
        "views_deg": [10.0],
        "epsilon": 2.3,
        "method": "cie76",
    }
    r = sqlite_api.client.post(f"{V1}/analyses/gg-index", json=body, headers=sqlite_api.auth("qa"))
    assert r.status_code == 200, r.text
    direct = goniogeometric_index(bright_silver, [45.0], [10.0], epsilon=2.3, method="cie76")
    assert r.json()["beta_min_deg"] == pytest.approx(direct.beta_min_deg)
    t = {"paint": _body(bright_silver), "lights_deg": [30.0, 45.0], "views_deg": [0.0, 10.0], "beta_deg": 3.0}
    r = sqlite_api.client.post(f"{V1}/analyses/trompe-loeil", json=t, headers=sqlite_api.auth("qa"))
    assert r.status_code == 200, r.text


@pytest.mark.parametrize(
    ("path", "role", "wrap"),
    [
        ("designs", "stylist", lambda d: {"name": "x", "design": d}),
        ("styling/variations", "stylist", lambda d: {"design": d, "degree": 5.0}),
        ("formulation/formulate", "chemist", lambda d: {"design": d}),
        ("analyses/gg-index", "qa", lambda d: {"paint": d, "lights_deg": [45.0]}),
    ],
)
def test_out_of_range_is_a_422_naming_the_field(sqlite_api: Api, bright_silver, path, role, wrap) -> None:
    bad = _body(bright_silver) | {"face": [250.0, -0.6, -1.8]}
    r = sqlite_api.client.post(f"{V1}/{path}", json=wrap(bad), headers=sqlite_api.auth(role))
    assert r.status_code == 422, r.text
    detail = r.json()["detail"][0]
    assert "face" in detail["loc"] and detail["loc"][-1] == 0  # face[0] = L*
    assert "200" in detail["msg"]
