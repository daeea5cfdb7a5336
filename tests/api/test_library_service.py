"""The library through the service: ColorSnap with a type filter and one stored library, each match's
own library and synthetic flag, the stored libraries listed, and a 50 000-paint CSV upload over real
HTTP under the upload's own cap (every other route keeps the small cap)."""

from __future__ import annotations

from pathlib import Path

import httpx
import httpx2
import numpy as np
import pytest

from db.models import Role
from station.api.services.library import library_rows
from station.formulate.demo import generate_library
from station.formulate.library import Library
from tests.api.conftest import Api, make_api
from tests.api.test_serve import _serve

HEAD = "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\n"
GREY = [[50.0, 0.0, 0.0]] * 3


def _csv(n: int, prefix: str = "U", seed: int = 1) -> str:
    rng = np.random.default_rng(seed)
    rows = [HEAD.rstrip("\n")]
    for i in range(n):
        lab = (rng.uniform(20, 90), *rng.uniform(-40, 40, 2))
        rows.append(
            f"{prefix}-{i:05d},solid,{rng.uniform(10, 95):.4f}," + ",".join(f"{v:.4f}" for v in lab * 3)
        )
    return "\n".join(rows) + "\n"


@pytest.fixture(scope="module")
def small_library() -> Library:
    """A 240-paint SYNTHETIC library from the colorant model (seed 11)."""
    return generate_library(120, 80, 40, seed=11)


def _store(api: Api, lib: Library) -> None:
    from sqlalchemy import insert

    from db.models import LibraryPaint

    app = api.client.app
    with app.state.sessions() as session:  # type: ignore[attr-defined]
        session.execute(insert(LibraryPaint), library_rows(lib))
        session.commit()


def _upload(api: Api, text: str, name: str) -> httpx2.Response:
    return api.client.post(
        f"/api/v1/library/import?name={name}",
        content=text.encode(),
        headers={**api.auth(Role.CHEMIST), "Content-Type": "text/csv"},
    )


def test_snap_type_filter_one_library_and_per_match_synthetic(api: Api, small_library: Library) -> None:
    _store(api, small_library)  # synthetic, 120 solids / 80 metallics / 40 pearls
    assert _upload(api, HEAD + "MINE-1,solid,90,50,0,0,50,0,0,50,0,0\n", "mine").status_code == 201
    auth = api.auth(Role.CHEMIST)
    listed = api.client.get("/api/v1/library/libraries", headers=auth).json()
    assert {x["name"]: (x["paints"], x["synthetic"]) for x in listed} == {
        small_library.name: (len(small_library), True),
        "mine": (1, False),
    }
    snap = api.client.post("/api/v1/formulation/snap", json={"lab": GREY, "k": 2}, headers=auth).json()
    first = snap["matches"][0]
    assert (first["code"], first["library"], first["synthetic"], first["sum_de"]) == (
        "MINE-1",
        "mine",
        False,
        0.0,
    )
    assert (
        snap["matches"][1]["synthetic"] is True and snap["synthetic"] is True
    )  # any match synthetic says so
    assert snap["library_paints"] == len(small_library) + 1
    # a type filter searches those paints only: brute force over the metallics of the stored library
    body = {"lab": GREY, "k": 3, "types": ["metallic"]}
    got = api.client.post("/api/v1/formulation/snap", json=body, headers=auth).json()
    rows = np.flatnonzero(small_library.types == "metallic")
    sums = np.linalg.norm(small_library.angle_columns()[rows] - np.array(GREY), axis=-1).sum(axis=1)
    want = small_library.codes[rows[np.lexsort((rows, sums))[:3]]].tolist()
    assert [m["code"] for m in got["matches"]] == want
    assert {m["type"] for m in got["matches"]} == {"metallic"} and got["library_paints"] == rows.size
    # one library: the measured one only
    only = api.client.post(
        "/api/v1/formulation/snap", json={"lab": GREY, "k": 1, "library": "mine"}, headers=auth
    )
    assert only.json()["matches"][0]["code"] == "MINE-1" and only.json()["synthetic"] is False
    for bad, field in (({"library": "nope"}, "library"), ({"library": "mine", "types": ["pearl"]}, "types")):
        r = api.client.post("/api/v1/formulation/snap", json={"lab": GREY, **bad}, headers=auth)
        assert r.status_code == 422 and r.json()["detail"][0]["loc"][-1] == field


def test_upload_cap_is_its_own_and_a_refused_upload_stores_nothing(tmp_path: Path) -> None:
    text = _csv(40)
    url = f"sqlite:///{tmp_path / 's.sqlite3'}"
    for api in make_api(url, tmp_path, max_body_bytes=1024, library_upload_max_bytes=len(text) - 1):
        r = _upload(api, text, "big")
        assert r.status_code == 413 and str(len(text) - 1) in r.json()["detail"]
        listed = api.client.get("/api/v1/library/libraries", headers=api.auth(Role.CHEMIST))
        assert listed.status_code == 409  # still empty: nothing stored
        small = _csv(3)
        assert len(small) > 1024 or _upload(api, small, "small").status_code == 201
        # every other route keeps max_body_bytes
        r = api.client.post(
            "/api/v1/formulation/snap",
            content=b" " * 2048,
            headers={**api.auth(Role.CHEMIST), "Content-Type": "application/json"},
        )
        assert r.status_code == 413


@pytest.mark.slow
def test_fifty_thousand_paints_upload_over_real_http(tmp_path: Path) -> None:
    text = _csv(50_000)
    assert len(text) > 4 * 1_048_576  # far over the default 1 MiB body cap
    with _serve(tmp_path, "--simulators", "") as (base, token):
        auth = {"Authorization": f"Bearer {token}"}
        with httpx.Client(base_url=base, timeout=180) as client:
            r = client.post(
                "/api/v1/library/import?name=big",
                content=text.encode(),
                headers={**auth, "Content-Type": "text/csv"},
            )
            assert r.status_code == 201, r.text
            assert r.json()["paints"] == 50_000
            listed = client.get("/api/v1/library/libraries", headers=auth).json()
            assert listed == [
                {
                    "name": "big",
                    "paints": 50_000,
                    "types": {"solid": 50_000, "metallic": 0, "pearl": 0},
                    "synthetic": False,
                }
            ]
            page = client.get("/api/v1/library?code_prefix=U-4999&limit=100", headers=auth).json()
            assert page["count"] == 10  # U-49990 … U-49999
            assert [p["code"] for p in page["data"]] == [f"U-4999{i}" for i in range(10)]
