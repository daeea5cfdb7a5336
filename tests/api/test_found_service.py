"""Service items of the users' journeys: QA and chemist store designs (the QA → formulation hand-off
needs no admin), styling stays the stylist's; the API docs page works offline (bundled Swagger UI)."""

from __future__ import annotations

import re

import pytest

from db.models import Role
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_to_dict
from tests.api.conftest import Api

V1 = "/api/v1"
PAINT = FaceFlopTravelGloss((61.9, 15.2, 8.0), (5.0, 10.1, 4.2), 79.9, 90.0, "corrected for the fender")


@pytest.mark.parametrize("role", [Role.QA, Role.CHEMIST, Role.STYLIST])
def test_qa_and_chemist_store_designs(sqlite_api: Api, role: Role) -> None:
    c = sqlite_api.client
    r = c.post(
        f"{V1}/designs",
        json={"name": f"{role.value} design", "design": design_to_dict(PAINT)},
        headers=sqlite_api.auth(role),
    )
    assert r.status_code == 201, r.text
    got = c.get(f"{V1}/designs/{r.json()['id']}", headers=sqlite_api.auth(Role.CHEMIST)).json()
    assert got["name"] == f"{role.value} design" and got["design"]["face"] == pytest.approx(list(PAINT.face))
    styling = c.post(f"{V1}/styling/variations", json={}, headers=sqlite_api.auth(role))
    assert (styling.status_code == 403) == (role is not Role.STYLIST), styling.text


def test_docs_page_loads_its_files_from_the_service(sqlite_api: Api) -> None:
    c = sqlite_api.client
    page = c.get("/docs", headers=sqlite_api.auth(Role.TECHNICIAN))
    assert page.status_code == 200
    urls = re.findall(r"""(?:src|href)=["']([^"']+)["']""", page.text)
    assert urls and all(u.startswith("/docs-assets/") for u in urls), urls
    assert "cdn" not in page.text.lower() and "http://" not in page.text and "https://" not in page.text
    for u in urls:
        r = c.get(u)  # static files: no token needed
        assert r.status_code == 200 and len(r.content) > 500, u
    js = c.get("/docs-assets/swagger-ui-bundle.js")
    assert js.headers["content-type"].startswith("text/javascript") and b"SwaggerUIBundle" in js.content
    assert c.get("/docs-assets/../app.py").status_code == 404
    assert c.get("/docs-assets/index.html").status_code == 404


def test_redoc_and_the_front_door_work_offline(sqlite_api: Api) -> None:
    c = sqlite_api.client
    page = c.get("/redoc", headers=sqlite_api.auth(Role.TECHNICIAN))
    assert page.status_code == 200
    urls = re.findall(r"""(?:src|href)=["']([^"']+)["']""", page.text)
    assert urls and all(u.startswith("/docs-assets/") for u in urls), urls
    assert "http://" not in page.text and "https://" not in page.text  # no CDN, no web fonts
    js = c.get("/docs-assets/redoc.standalone.js")
    assert js.status_code == 200 and b"Redoc" in js.content
    front = c.get("/", follow_redirects=False)
    assert front.status_code == 307 and front.headers["location"] == "/docs"
