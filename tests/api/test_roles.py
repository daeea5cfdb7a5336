"""Every route refuses a missing or wrong token (401) and each role what it must not do (403).

The expected table is written out here by hand from the issue ("a technician measures; a chemist
formulates; only admin manages users"), independently of ``station.api.security.ROLE_SCOPES``, and the
test fails when the app grows a route the table does not list.
"""

from __future__ import annotations

import re

import pytest

from db.models import Role
from tests.api.conftest import Api

T, Q, S, C, A = Role.TECHNICIAN, Role.QA, Role.STYLIST, Role.CHEMIST, Role.ADMIN
ALL = frozenset(Role)
V1 = "/api/v1"

EXPECTED: dict[tuple[str, str], frozenset[Role]] = {
    ("GET", f"{V1}/instruments"): frozenset({T, Q, A}),
    ("POST", f"{V1}/instruments/connect"): frozenset({T, A}),
    ("DELETE", f"{V1}/instruments/{{instrument_id}}"): frozenset({T, A}),
    ("POST", f"{V1}/instruments/{{instrument_id}}/calibrate"): frozenset({T, A}),
    ("POST", f"{V1}/instruments/calibrations"): frozenset({T, A}),
    ("GET", f"{V1}/instruments/calibrations/{{session_id}}"): frozenset({T, A}),
    ("POST", f"{V1}/instruments/calibrations/{{session_id}}/step"): frozenset({T, A}),
    ("POST", f"{V1}/instruments/calibrations/{{session_id}}/cancel"): frozenset({T, A}),
    ("POST", f"{V1}/instruments/{{instrument_id}}/measure"): frozenset({T, A}),
    ("POST", f"{V1}/panels"): frozenset({T, A}),
    ("GET", f"{V1}/panels"): ALL,
    ("GET", f"{V1}/panels/{{panel_id}}"): ALL,
    ("POST", f"{V1}/measurements"): frozenset({T, A}),
    ("GET", f"{V1}/measurements"): ALL,
    ("GET", f"{V1}/measurements/export.csv"): ALL,
    ("GET", f"{V1}/measurements/{{measurement_id}}"): ALL,
    ("POST", f"{V1}/measurements/{{measurement_id}}/corrections"): frozenset({T, Q, A}),
    ("GET", f"{V1}/qc/measurements"): ALL,
    ("GET", f"{V1}/qc/measurements/{{measurement_id}}"): ALL,
    ("POST", f"{V1}/qc/gloss"): frozenset({T, A}),
    ("GET", f"{V1}/qc/gloss"): ALL,
    ("GET", f"{V1}/qc/gloss/{{gloss_id}}"): ALL,
    ("POST", f"{V1}/qc/gloss/measure"): frozenset({T, A}),
    ("POST", f"{V1}/qc/check"): ALL,
    ("GET", f"{V1}/qc/jobs"): ALL,
    ("PUT", f"{V1}/qc/jobs/{{job}}/standards/{{part}}"): frozenset({Q, A}),
    ("GET", f"{V1}/qc/jobs/{{job}}/standards/{{part}}"): ALL,
    ("GET", f"{V1}/qc/jobs/{{job}}/summary"): ALL,
    ("GET", f"{V1}/qc/jobs/{{job}}/report.pdf"): ALL,
    ("GET", f"{V1}/qc/jobs/{{job}}/report.csv"): ALL,
    ("GET", f"{V1}/qc/jobs/{{job}}/spc"): ALL,
    ("GET", f"{V1}/qc/jobs/{{job}}/spc.png"): ALL,
    ("POST", f"{V1}/qc/jobs/{{job}}/summary"): ALL,
    ("POST", f"{V1}/qc/jobs/{{job}}/report.pdf"): ALL,
    ("POST", f"{V1}/qc/jobs/{{job}}/report.csv"): ALL,
    ("POST", f"{V1}/qc/jobs/{{job}}/spc"): ALL,
    ("POST", f"{V1}/qc/metamerism"): ALL,
    ("POST", f"{V1}/qc/repeats"): ALL,
    ("POST", f"{V1}/booth"): ALL,
    ("GET", f"{V1}/booth/illuminants"): ALL,
    ("POST", f"{V1}/analyses/seam"): frozenset({Q, A}),
    ("POST", f"{V1}/analyses/gg-index"): frozenset({Q, A}),
    ("POST", f"{V1}/analyses/gg-index/environment"): frozenset({Q, A}),
    ("POST", f"{V1}/analyses/trompe-loeil"): frozenset({Q, A}),
    ("POST", f"{V1}/analyses/sweep"): frozenset({Q, A}),
    ("GET", f"{V1}/analyses"): ALL,
    ("GET", f"{V1}/analyses/{{analysis_id}}"): ALL,
    ("GET", f"{V1}/analyses/{{analysis_id}}/report.png"): ALL,
    ("POST", f"{V1}/designs"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/designs"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/designs/{{design_id}}"): frozenset({Q, S, C, A}),
    ("PUT", f"{V1}/designs/{{design_id}}"): frozenset({Q, S, C, A}),
    ("DELETE", f"{V1}/designs/{{design_id}}"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/designs/{{design_id}}/versions"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/designs/{{design_id}}/versions/{{version}}"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/library"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/library/{{code}}"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/library/export.csv"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/library/browse"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/library/libraries"): frozenset({Q, S, C, A}),
    ("POST", f"{V1}/library/import"): frozenset({C, A}),
    ("POST", f"{V1}/styling/variations"): frozenset({S, A}),
    ("POST", f"{V1}/styling/swatch"): frozenset({S, A}),
    ("POST", f"{V1}/styling/render"): frozenset({S, A}),
    ("POST", f"{V1}/styling/render/upload"): frozenset({S, A}),
    ("POST", f"{V1}/styling/eyedrop"): frozenset({S, A}),
    ("POST", f"{V1}/styling/sketch-fit"): frozenset({S, A}),
    ("POST", f"{V1}/formulation/snap"): frozenset({Q, C, A}),
    ("POST", f"{V1}/formulation/formulate"): frozenset({Q, C, A}),
    ("POST", f"{V1}/formulation/export"): frozenset({Q, C, A}),
    ("POST", f"{V1}/formulation/closed-loop"): frozenset({C, A}),
    ("POST", f"{V1}/recipes"): frozenset({C, A}),
    ("GET", f"{V1}/recipes"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/recipes/{{recipe_id}}"): frozenset({Q, S, C, A}),
    ("GET", f"{V1}/me"): ALL,
    ("GET", f"{V1}/users"): frozenset({A}),
    ("POST", f"{V1}/users"): frozenset({A}),
    ("POST", f"{V1}/users/{{user_id}}/tokens"): frozenset({A}),
    ("DELETE", f"{V1}/users/{{user_id}}"): frozenset({A}),
    ("GET", f"{V1}/users/{{user_id}}/tokens"): frozenset({A}),
    ("DELETE", f"{V1}/tokens/{{token_id}}"): ALL,  # one's own token; another user's is a 404
    ("GET", f"{V1}/audit"): frozenset({Q, A}),
}
PUBLIC = {("GET", "/health")}


def _concrete(path: str) -> str:
    return re.sub(
        r"\{[a-z_]+\}",
        lambda m: (
            "ma6-nothing"
            if m.group() == "{instrument_id}"
            else ("NOPE" if m.group() == "{code}" else "424242")
        ),
        path,
    )


def _routes(api: Api) -> set[tuple[str, str]]:
    paths = api.client.app.openapi()["paths"]  # type: ignore[attr-defined]
    return {(method.upper(), path) for path, ops in paths.items() for method in ops}


def test_table_covers_every_route(sqlite_api: Api) -> None:
    assert _routes(sqlite_api) - PUBLIC == set(EXPECTED)


def test_every_route_refuses_missing_and_wrong_tokens(sqlite_api: Api) -> None:
    for method, path in EXPECTED:
        url = _concrete(path)
        for headers in (
            {},
            {"Authorization": "Bearer cst_not-a-real-token"},
            {"Authorization": "Basic Zm9vOmJhcg=="},
            {"Authorization": f"Bearer {sqlite_api.tokens[A]}x"},
        ):
            r = sqlite_api.client.request(method, url, headers=headers, json={})
            assert r.status_code == 401, (method, path, headers, r.status_code, r.text)
            assert r.headers.get("www-authenticate") == "Bearer"


@pytest.mark.parametrize("role", list(Role), ids=lambda r: r.value)
def test_each_role_is_refused_what_it_must_not_do(sqlite_api: Api, role: Role) -> None:
    for (method, path), allowed in EXPECTED.items():
        r = sqlite_api.client.request(method, _concrete(path), headers=sqlite_api.auth(role), json={})
        if role in allowed:
            assert r.status_code not in (401, 403), (role, method, path, r.status_code, r.text)
        else:
            assert r.status_code == 403, (role, method, path, r.status_code, r.text)


@pytest.mark.parametrize("path", ["/docs", "/redoc", "/openapi.json"])
def test_docs_need_a_token_by_default(sqlite_api: Api, path: str) -> None:
    assert sqlite_api.client.get(path).status_code == 401
    assert sqlite_api.client.get(path, headers={"Authorization": "Bearer cst_wrong"}).status_code == 401
    r = sqlite_api.client.get(path, headers=sqlite_api.auth(T))  # any role may read the schema
    assert r.status_code == 200
    assert sqlite_api.client.get("/health").status_code == 200


def test_docs_can_be_opened(tmp_path) -> None:
    from tests.api.conftest import make_api

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, public_docs=True)
    api = next(gen)
    try:
        for path in ("/docs", "/redoc", "/openapi.json"):
            assert api.client.get(path).status_code == 200
    finally:
        gen.close()
