"""docs/api.md is generated from the app and lists every route; its roles column is what the service
enforces (checked by calling each route without a token and with a role the table leaves out)."""

from __future__ import annotations

import re

from fastapi import routing

from db.models import Role
from station.api import docgen
from tests.api.conftest import Api

ROW = re.compile(r"^\| (GET|POST|PUT|PATCH|DELETE) \| `([^`]+)` \| ([^|]+) \| ([^|]+) \|", re.M)


def _rows() -> list[tuple[str, str, str, str]]:
    text = docgen.OUTPUT.read_text(encoding="utf-8")
    return [(m[1], m[2], m[3].strip(), m[4].strip()) for m in ROW.finditer(text)]


def test_committed_api_docs_equal_the_generated_ones() -> None:
    assert docgen.main(["--check"]) == 0, "docs/api.md is stale: run python -m station.api.docgen"


def test_every_route_is_listed_once(sqlite_api: Api) -> None:
    app = sqlite_api.client.app
    served = {
        (method, str(ctx.path_format))
        for ctx in routing.iter_route_contexts(app.routes)  # type: ignore[attr-defined]
        if isinstance(ctx.original_route, routing.APIRoute)
        for method in ctx.methods or ()
    }
    listed = [(m, p) for m, p, _r, _c in _rows()]
    assert len(listed) == len(set(listed))
    assert set(listed) == served
    protected = [r for r in _rows() if r[2] != docgen.PUBLIC]
    assert len([r for r in protected if r[1].startswith("/api/v1/")]) == len(
        [s for s in served if s[1].startswith("/api/v1/")]
    )


def _concrete(path: str) -> str:
    return re.sub(r"\{[^}]+\}", "1", path)


def test_roles_column_is_what_the_service_enforces(sqlite_api: Api) -> None:
    api = sqlite_api
    for method, path, roles, codes in _rows():
        url = _concrete(path)
        r = api.client.request(method, url, follow_redirects=False)  # the route itself, not where it leads
        if roles == docgen.PUBLIC:
            assert r.status_code != 401, (method, path)
            continue
        assert r.status_code == 401, (method, path, r.status_code)
        assert "401" in codes
        allowed = {x.strip() for x in roles.split(",")} if roles != "every role" else {x.value for x in Role}
        refused = [role for role in Role if role.value not in allowed]
        for role in refused:
            r = api.client.request(method, url, headers=api.auth(role))
            assert r.status_code == 403, (method, path, role, r.status_code)
            assert "403" in codes


def test_check_fails_on_a_stale_document(tmp_path) -> None:
    stale = tmp_path / "api.md"
    stale.write_text(docgen.OUTPUT.read_text(encoding="utf-8").replace("| GET | `/health`", "| GET | `/hea`"))
    assert docgen.main(["--check", "--output", str(stale)]) == 1
    assert docgen.main(["--output", str(stale)]) == 0
    assert stale.read_text(encoding="utf-8") == docgen.OUTPUT.read_text(encoding="utf-8")
