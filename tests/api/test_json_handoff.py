"""A route of class ``ParsedJsonRoute`` validates the document ``StrictJsonBody`` parsed: the body is parsed once.

The guard parses every JSON body to find the values no route accepts; the measure route then reads that
document instead of parsing the same bytes again. What the route sees must be what a second parse gives,
and a body the guard did not hand on (not JSON) is still refused by FastAPI as before.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Body, FastAPI, Request
from fastapi.testclient import TestClient

from station.api.json_guard import PARSED_BODY, ParsedJsonRoute, StrictJsonBody


def _app() -> FastAPI:
    router = APIRouter(route_class=ParsedJsonRoute)

    @router.post("/echo")
    async def echo(request: Request, doc: Any = Body()) -> dict[str, Any]:  # noqa: B008 - the document as parsed
        held = request.scope.get(PARSED_BODY)
        return {"doc": doc, "handed_on": held is not None and held[1] is doc}

    app = FastAPI()
    app.include_router(router)
    app.add_middleware(StrictJsonBody)
    return app


def test_the_route_validates_the_document_the_guard_parsed() -> None:
    with TestClient(_app()) as client:
        sent = {"lab": [[50.0, -0.0, 1e-300]], "n": 12345678901234567890, "s": "é"}
        answer = client.post("/echo", json=sent)
        assert answer.status_code == 200, answer.text
        assert answer.json() == {"doc": sent, "handed_on": True}


def test_a_body_the_guard_did_not_parse_is_refused_as_before() -> None:
    with TestClient(_app()) as client:
        answer = client.post("/echo", content=b'{"lab": [', headers={"content-type": "application/json"})
        assert answer.status_code == 422
        assert answer.json()["detail"][0]["type"] == "json_invalid"
        answer = client.post("/echo", content=b'{"x": NaN}', headers={"content-type": "application/json"})
        assert answer.status_code == 422
        assert answer.json()["detail"][0]["loc"] == ["body", "x"]
