"""ColorSnap restricted to one named stored library keeps that library's exact index between requests
(counted builds), drops it when the rows change, and still returns the brute-force top-k of that library."""

from __future__ import annotations

import numpy as np
import pytest
from sqlalchemy import insert

from db.models import LibraryPaint
from station.api.services.library import library_rows
from station.formulate.demo import generate_library
from station.model.design_io import design_from_dict
from station.model.difference import delta_e
from tests.api.conftest import Api

V1 = "/api/v1"
ANGLES = (15.0, 45.0, 110.0)
DESIGN = {"face": [62.0, -4.0, -38.0], "flop": [24.0, 1.0, -20.0], "travel_deg": 70.0, "gloss_gu": 88.0}
CSV = "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\nR-1,solid,90,40,50,30,40,50,30,40,50,30\n"


@pytest.fixture
def two_books(sqlite_api: Api) -> tuple[Api, list[dict]]:
    """Two stored libraries, "book A" and "book B" (SYNTHETIC, with recipes)."""
    book_b: list[dict] = []
    for name, seed in (("book A", 3), ("book B", 4)):
        rows = library_rows(generate_library(n_solid=30, n_metallic=20, n_pearl=10, seed=seed))
        for r in rows:
            r["code"] = r["name"] = f"{name[-1]}-{r['code']}"
            r["extra"]["library"] = name
        with sqlite_api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
            session.execute(insert(LibraryPaint), rows)
            session.commit()
        book_b = rows
    return sqlite_api, book_b


def _snap(api: Api, k: int, library: str = "book B") -> dict:
    r = api.client.post(
        f"{V1}/formulation/snap",
        json={"design": DESIGN, "k": k, "library": library, "metric": "cie2000"},
        headers=api.auth("chemist"),
    )
    assert r.status_code == 200, r.text
    return r.json()


def test_a_named_library_index_is_built_once_and_dropped_with_the_rows(
    two_books: tuple[Api, list[dict]],
) -> None:
    api, rows = two_books
    got = [_snap(api, k) for k in (3, 4, 5)]
    cache = api.client.app.state.library_cache  # type: ignore[attr-defined]
    assert cache.builds == 1 and cache.named_builds == 1  # the second and third request reuse the index
    target = design_from_dict(DESIGN).lab_at(np.array(ANGLES))
    lab = np.array([[r["lab"][[float(a) for a in r["angles_deg"]].index(a)] for a in ANGLES] for r in rows])
    sums = delta_e(np.broadcast_to(target, lab.shape), lab, method="cie2000").sum(axis=1)
    order = np.argsort(sums, kind="stable")[:5]  # brute force over book B only
    assert [m["code"] for m in got[-1]["matches"]] == [rows[i]["code"] for i in order]
    assert {m["library"] for m in got[-1]["matches"]} == {"book B"} and got[-1]["library_paints"] == len(rows)
    _snap(api, 2, "book A")
    assert cache.named_builds == 2  # one index per name
    assert (
        api.client.post(f"{V1}/library/import", content=CSV, headers=api.auth("chemist")).status_code == 201
    )
    again = _snap(api, 5)
    assert cache.builds == 2 and cache.named_builds == 3  # rows changed: rebuilt once, then kept
    assert [m["code"] for m in again["matches"]] == [m["code"] for m in got[-1]["matches"]]
    _snap(api, 1)
    assert cache.named_builds == 3


def test_an_unknown_library_is_refused_naming_the_field(two_books: tuple[Api, list[dict]]) -> None:
    api, _ = two_books
    r = api.client.post(
        f"{V1}/formulation/snap", json={"design": DESIGN, "library": "book C"}, headers=api.auth("chemist")
    )
    assert r.status_code == 422 and "library" in r.text and "book A | book B" in r.text
