"""Fuzz every JSON route and upload of the service with the hostile values of issue 13: 0 responses ≥ 500.

The routes come from the app's own OpenAPI schema. For a JSON body the documented example is taken and
hypothesis picks one member (any depth) and one raw token from :data:`tests.api._hostile.JSON_TOKENS`
(NaN, ±Infinity, 1e309, lone surrogates, NUL, bool/str for numbers, year 1/9999 with an offset …) to
put there, or adds it under a new member; uploads get the hostile CSV and image bodies. Every answer
must be < 500 and, when it says JSON, parse as JSON. Bounded: ``FUZZ_EXAMPLES`` (default 12) per route.
"""

from __future__ import annotations

import copy
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sqlalchemy import insert

from db.models import LibraryPaint, Role
from station.api import Settings, create_app
from station.api.services.library import library_rows
from station.formulate.demo import generate_library
from tests.api._hostile import CSV_BODIES, IMAGE_BODIES, JSON_TOKENS
from tests.api.conftest import Api, make_api
from tests.ingest._readings import make_reading

MAX_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "12"))
MARK = "__hostile__"
PATH_VALUES = {"instrument_id": "ma6-sim00001", "code": "SYN-S-0001"}


def _operations() -> list[tuple[str, str, dict[str, Any]]]:
    app = create_app(Settings(simulators=(), load_demo_library=False, public_docs=True))
    spec = app.openapi()
    ops = []
    for path, methods in spec["paths"].items():
        for method, op in methods.items():
            if op.get("requestBody") and not path.endswith("/users/{user_id}"):
                ops.append((method.upper(), path, spec))
    return ops


OPERATIONS = _operations()


@pytest.fixture(scope="module")
def fapi(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Api]:
    tmp = tmp_path_factory.mktemp("fuzz")
    for api in make_api(f"sqlite:///{tmp / 'station.sqlite3'}", Path(tmp)):
        h = api.auth(Role.ADMIN)
        api.client.post("/api/v1/panels", json={"job": "J", "part": "door"}, headers=h)
        api.client.post(
            "/api/v1/designs",
            json={"name": "d", "design": {"face": [50, 1, 1], "flop": [30, 1, 1], "travel_deg": 60}},
            headers=h,
        )
        for i in range(2):
            api.client.post(
                "/api/v1/measurements", json=make_reading(61, i).model_dump(mode="json"), headers=h
            )
        app = api.client.app
        with app.state.sessions() as session:  # type: ignore[attr-defined]
            lib = generate_library(n_solid=20, n_metallic=10, n_pearl=5, seed=5)
            session.execute(insert(LibraryPaint), library_rows(lib))
            session.commit()
        yield api


def _members(node: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield path
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _members(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _members(v, (*path, i))


def _example(spec: dict[str, Any], op: dict[str, Any]) -> Any:
    schema = op["requestBody"]["content"]["application/json"]["schema"]
    name = schema["$ref"].rsplit("/", 1)[1]
    return spec["components"]["schemas"][name]["examples"][0]


def _with_token(example: Any, where: tuple[Any, ...], token: bytes, add: bool) -> bytes:
    doc = copy.deepcopy(example)
    if not where:
        return token
    parent = doc
    for step in where[:-1]:
        parent = parent[step]
    if add and isinstance(parent, dict):
        parent[f"{where[-1]}_extra"] = MARK
    else:
        parent[where[-1]] = MARK
    text = json.dumps(doc).encode()
    return text.replace(json.dumps(MARK).encode(), token, 1)


def _url(path: str, op: dict[str, Any]) -> tuple[str, dict[str, str]]:
    for param in op.get("parameters", []):
        if param["in"] == "path":
            path = path.replace("{" + param["name"] + "}", PATH_VALUES.get(param["name"], "1"))
    query = {}
    for param in op.get("parameters", []):
        if param["in"] == "query" and param.get("required"):
            schema = param.get("schema", {})
            query[param["name"]] = str(schema.get("default", schema.get("minimum", 1)))
    return path, query


def _check(response: Any) -> str | None:
    if response.status_code >= 500:
        return f"{response.status_code}: {response.text[:300]}"
    if response.headers.get("content-type", "").startswith("application/json"):
        try:
            response.json()
        except ValueError:
            return f"{response.status_code}: body is not JSON"
    return None


@pytest.mark.parametrize(("method", "path", "spec"), OPERATIONS, ids=[f"{m} {p}" for m, p, _ in OPERATIONS])
def test_no_hostile_value_gets_a_5xx(fapi: Api, method: str, path: str, spec: dict[str, Any]) -> None:
    op = spec["paths"][path][method.lower()]
    url, query = _url(path, op)
    content = op["requestBody"]["content"]
    headers = fapi.auth(Role.ADMIN)
    failures: list[str] = []

    if "application/json" in content:
        example = _example(spec, op)
        members = list(_members(example))

        @settings(
            max_examples=MAX_EXAMPLES,
            deadline=None,
            database=None,
            derandomize=True,
            suppress_health_check=list(HealthCheck),
        )
        @given(where=st.sampled_from(members), token=st.sampled_from(JSON_TOKENS), add=st.booleans())
        def run(where: tuple[Any, ...], token: bytes, add: bool) -> None:
            body = _with_token(example, where, token, add)
            r = fapi.client.request(
                method,
                url,
                params=query,
                content=body,
                headers={**headers, "content-type": "application/json"},
            )
            fault = _check(r)
            if fault:
                failures.append(f"{where} <- {token[:40]!r}: {fault}")

    else:
        media = next(iter(content))
        bodies = CSV_BODIES if media == "text/csv" else IMAGE_BODIES

        @settings(
            max_examples=MAX_EXAMPLES,
            deadline=None,
            database=None,
            derandomize=True,
            suppress_health_check=list(HealthCheck),
        )
        @given(body=st.sampled_from(bodies), junk=st.binary(max_size=64))
        def run(body: bytes, junk: bytes) -> None:
            for payload in (body, body + junk):
                r = fapi.client.request(
                    method, url, params=query, content=payload, headers={**headers, "content-type": media}
                )
                fault = _check(r)
                if fault:
                    failures.append(f"{payload[:40]!r}: {fault}")

    run()
    assert not failures, "\n".join(failures[:10])


def test_every_upload_body_is_also_sent_whole(fapi: Api) -> None:
    """Each hostile CSV once, independent of what hypothesis drew: all < 500."""
    h = {**fapi.auth(Role.ADMIN), "content-type": "text/csv"}
    statuses = [
        fapi.client.post("/api/v1/library/import", content=b, headers=h).status_code for b in CSV_BODIES
    ]
    assert all(s < 500 for s in statuses), statuses
