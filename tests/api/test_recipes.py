"""Recipes: ColorSnap through the service equals a brute-force scan of the library in the database."""

from __future__ import annotations

import numpy as np
from sqlalchemy import insert

from db.models import LibraryPaint
from station.api.schemas.designs import DESIGN_EXAMPLE as DESIGN
from station.api.services.library import library_rows
from station.formulate.demo import generate_library
from station.model.design_io import design_from_dict
from station.model.difference import delta_e
from tests.api.conftest import Api

V1 = "/api/v1"


def test_recipe_is_the_brute_force_nearest_paint(sqlite_api: Api) -> None:
    c = sqlite_api.client
    assert (
        c.post(f"{V1}/recipes", json={"design_id": 1}, headers=sqlite_api.auth("chemist")).status_code == 404
    )
    design = c.post(
        f"{V1}/designs", json={"name": "Blue", "design": DESIGN}, headers=sqlite_api.auth("stylist")
    ).json()
    empty = c.post(f"{V1}/recipes", json={"design_id": design["id"]}, headers=sqlite_api.auth("chemist"))
    assert empty.status_code == 409  # no library loaded yet
    lib = generate_library(n_solid=60, n_metallic=40, n_pearl=20, seed=3)
    rows = library_rows(lib)
    with c.app.state.sessions() as session:  # type: ignore[attr-defined]
        session.execute(insert(LibraryPaint), rows)
        session.commit()
    r = c.post(
        f"{V1}/recipes",
        json={"design_id": design["id"], "k": 3, "metric": "cie2000"},
        headers=sqlite_api.auth("chemist"),
    )
    assert r.status_code == 201, r.text
    job = r.json()
    # brute force, independently: summed CIEDE2000 over 15/45/110 against every paint
    target = design_from_dict(DESIGN).lab_at(np.array([15.0, 45.0, 110.0]))
    cols = [lib.angles_deg.index(a) for a in (15.0, 45.0, 110.0)]
    lab = np.array([[row["lab"][j] for j in cols] for row in rows])  # as stored (4 decimals)
    sums = delta_e(lab, target[None], method="cie2000").sum(axis=1)
    order = np.argsort(sums, kind="stable")[:3]
    assert [cand["code"] for cand in job["candidates"]] == [str(lib.codes[i]) for i in order]
    np.testing.assert_allclose([cand["sum_de"] for cand in job["candidates"]], sums[order], rtol=1e-9)
    assert job["recipe"] == rows[int(order[0])]["extra"]["recipe"]
    assert (
        c.get(f"{V1}/recipes/{job['id']}", headers=sqlite_api.auth("qa")).json()["candidates"]
        == job["candidates"]
    )
    listed = c.get(
        f"{V1}/recipes", params={"design_id": design["id"]}, headers=sqlite_api.auth("stylist")
    ).json()
    assert listed["count"] == 1
    events = c.get(f"{V1}/audit", params={"entity": "recipe"}, headers=sqlite_api.auth("admin")).json()[
        "data"
    ]
    assert events[0]["detail"]["best"] == job["candidates"][0]["code"]
