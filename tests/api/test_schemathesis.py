"""Property-based conformance against the service's own OpenAPI schema (schemathesis), authorised as admin.

For every operation, generated requests (including some that the schema allows but the appearance
model refuses) must never produce a 5xx, and every response must match the documented status codes,
content types and response schemas. The run is bounded (``MAX_EXAMPLES`` per operation) to stay well
under a minute here; ``SCHEMATHESIS_EXAMPLES`` raises it.

Each call may take up to ``REQUEST_TIMEOUT_S``. schemathesis's own default (10 s) cancelled, on a busy
machine, the first call of an operation that does one-time work (``POST /api/v1/recipes`` builds the
library's snap index and compiles the CIEDE2000 walk, ``POST /api/v1/analyses/seam`` fits): the
request went on in its worker thread behind the next cases, and Hypothesis, whose replay of the case
was fast, reported "unreliable results" (the ``ReadTimeout`` only inside the exception group, now
printed by :func:`_failure`). A hang is still caught, by pytest-timeout.
"""

from __future__ import annotations

import copy
import json
import math
import os
from typing import Any

import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from schemathesis.checks import not_a_server_error
from schemathesis.core.result import Err
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)
from sqlalchemy import insert

from db.models import LibraryPaint, Role
from station.api.services.library import library_rows
from station.formulate.demo import generate_library
from tests.api._hostile import CSV_BODIES, PY_VALUES
from tests.api.conftest import Api
from tests.ingest._readings import make_reading

MAX_EXAMPLES = int(os.environ.get("SCHEMATHESIS_EXAMPLES", "10"))
CHECKS = [not_a_server_error, status_code_conformance, content_type_conformance, response_schema_conformance]
REQUEST_TIMEOUT_S = 120.0


def _failure(operation: Any, exc: BaseException) -> str:
    """One failure line: the operation, the error, and the errors Hypothesis grouped under it (a flaky
    replay keeps the first call's error only there)."""
    text = f"{operation.method.upper()} {operation.path}: {str(exc)[:600]}"
    for sub in getattr(exc, "exceptions", ()):
        text += f"\n  {type(sub).__name__}: {str(sub)[:600]}"
    return text


def test_openapi_schema_is_complete(sqlite_api: Api) -> None:
    spec = sqlite_api.client.get("/openapi.json", headers=sqlite_api.auth(Role.ADMIN)).json()
    for path, ops in spec["paths"].items():
        for method, op in ops.items():
            assert op.get("summary") and op.get("description"), (method, path)
            if path != "/health":
                assert {"401", "403"} <= set(op["responses"]), (method, path)
                assert op.get("security") == [{"HTTPBearer": []}] or op.get("security"), (method, path)
            body = op.get("requestBody")
            if (
                body and "application/json" not in body["content"]
            ):  # a raw upload (image, CSV) says what it is
                assert body.get("description"), (method, path)
            elif body:  # every JSON request body documents an example
                name = body["content"]["application/json"]["schema"]["$ref"].rsplit("/", 1)[1]
                assert spec["components"]["schemas"][name].get("examples"), (method, path, name)


def _seed(sqlite_api: Api, headers: dict[str, str]) -> None:
    """Rows for id-addressed operations to reach their happy paths too."""
    app = sqlite_api.client.app
    c = sqlite_api.client
    c.post("/api/v1/panels", json={"job": "J", "part": "door"}, headers=headers)
    c.post(
        "/api/v1/designs",
        json={"name": "d", "design": {"face": [50, 1, 1], "flop": [30, 1, 1], "travel_deg": 60}},
        headers=headers,
    )
    for i in range(2):
        c.post("/api/v1/measurements", json=make_reading(51, i).model_dump(mode="json"), headers=headers)
    # a small SYNTHETIC library: snap, formulate and export reach their work
    with app.state.sessions() as session:  # type: ignore[attr-defined]
        session.execute(
            insert(LibraryPaint),
            library_rows(generate_library(n_solid=30, n_metallic=20, n_pearl=10, seed=5)),
        )
        session.commit()


@pytest.mark.slow
def test_schemathesis_conformance(sqlite_api: Api) -> None:
    app = sqlite_api.client.app
    headers = sqlite_api.auth(Role.ADMIN)
    schema = schemathesis.openapi.from_asgi("/openapi.json", app, headers=headers)  # the schema needs a token
    _seed(sqlite_api, headers)
    failures: list[str] = []
    for result in schema.get_all_operations():
        if isinstance(result, Err):
            raise result.err()
        operation = result.ok()
        if operation.path.endswith("/users/{user_id}"):  # deactivating user 1 would revoke our own token
            continue
        if operation.path.endswith("/tokens/{token_id}") and operation.method.upper() == "DELETE":
            continue  # revoking token 1 would revoke our own token (tests/api/test_tokens.py covers it)

        @settings(
            max_examples=MAX_EXAMPLES,
            deadline=None,
            database=None,
            derandomize=True,
            suppress_health_check=list(HealthCheck),
        )
        @given(case=operation.as_strategy())
        def run(case: schemathesis.Case) -> None:
            case.call_and_validate(headers=headers, checks=CHECKS, timeout=REQUEST_TIMEOUT_S)

        try:
            run()
        except Exception as exc:
            failures.append(_failure(operation, exc))
    assert not failures, "\n\n".join(failures)


def _members(node: object, path: tuple[object, ...] = ()) -> list[tuple[object, ...]]:
    out = [path]
    if isinstance(node, dict):
        for k, v in node.items():
            out += _members(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _members(v, (*path, i))
    return out


def _inject(body: object, pick: int, value: object) -> object:
    """*body* with the member number *pick* (pre-order, the body itself first) replaced by *value*."""
    members = _members(body)
    where = members[pick % len(members)]
    if not where:
        return value
    parent: Any = body
    for step in where[:-1]:
        parent = parent[step]
    parent[where[-1]] = value
    return body


@pytest.mark.slow
def test_schemathesis_with_hostile_values(sqlite_api: Api) -> None:
    """Schema-valid cases from schemathesis, each with one member replaced by a hostile value of issue 13
    (NaN, ±Infinity, lone surrogates, NUL, bool/str for numbers, year 1/9999 with an offset, CRLF,
    formulas), and the CSV upload replaced by a hostile CSV: never a 5xx, always a documented answer."""
    app = sqlite_api.client.app
    headers = sqlite_api.auth(Role.ADMIN)
    schema = schemathesis.openapi.from_asgi("/openapi.json", app, headers=headers)
    _seed(sqlite_api, headers)
    failures: list[str] = []
    for result in schema.get_all_operations():
        if isinstance(result, Err):
            raise result.err()
        operation = result.ok()
        media = [b.media_type for b in operation.body]
        if operation.path.endswith("/users/{user_id}") or not media:
            continue
        csv_upload = operation.path.endswith("/library/import")
        if not csv_upload and "application/json" not in media:
            continue  # image uploads: the fuzz test sends its hostile images

        @settings(
            max_examples=MAX_EXAMPLES,
            deadline=None,
            database=None,
            derandomize=True,
            suppress_health_check=list(HealthCheck),
            phases=(Phase.explicit, Phase.generate),  # a failure is reported as drawn, not shrunk
        )
        @given(
            case=operation.as_strategy(),
            value=st.sampled_from(PY_VALUES),
            csv_body=st.sampled_from(CSV_BODIES),
            pick=st.integers(min_value=0, max_value=10_000),
        )
        def run(case: schemathesis.Case, value: object, csv_body: bytes, pick: int) -> None:
            upload = case.operation.path.endswith("/library/import")
            if not upload:  # a copy: an explicit example's body is shared between cases
                # hostile values are not JSON values by design
                case.body = _inject(copy.deepcopy(case.body), pick, value)  # type: ignore[assignment]
            unencodable = (isinstance(value, float) and not math.isfinite(value)) or value == "\ud800"
            if upload or unencodable:
                # schemathesis's serialisers refuse NaN/±inf and lone surrogates (and CSV bytes): send the
                # same case as raw bytes (JSON with NaN / "\ud800" escapes, or the hostile CSV)
                raw = csv_body if upload else json.dumps(case.body, allow_nan=True).encode()
                r = sqlite_api.client.request(
                    case.method,
                    case.formatted_path,
                    params=case.query,
                    content=raw,
                    headers={**headers, "content-type": "text/csv" if upload else "application/json"},
                )
                assert r.status_code == 422, (case.formatted_path, r.status_code, r.text[:300])
                return
            case.call_and_validate(headers=headers, checks=CHECKS, timeout=REQUEST_TIMEOUT_S)

        try:
            run()
        except Exception as exc:
            failures.append(_failure(operation, exc))
    assert not failures, "\n\n".join(failures)


def test_documented_examples_validate() -> None:
    from station.api.schemas.analyses import GgIndexRequest, SeamQaCreate, SweepRequest, TrompeRequest
    from station.api.schemas.designs import DesignCreate, DesignUpdate
    from station.api.schemas.formulation import (
        ClosedLoopRequest,
        ExportRequest,
        FormulateRequest,
        SnapRequest,
    )
    from station.api.schemas.instruments import CalibrateRequest, ConnectRequest, MeasureRequest
    from station.api.schemas.measurements import CorrectionCreate
    from station.api.schemas.panels import PanelCreate
    from station.api.schemas.recipes import RecipeCreate
    from station.api.schemas.styling import RenderRequest, SwatchRequest, VariationsRequest
    from station.api.schemas.users import TokenCreate, UserCreate
    from station.ingest import Reading

    models = (
        Reading,
        PanelCreate,
        DesignCreate,
        DesignUpdate,
        UserCreate,
        TokenCreate,
        ConnectRequest,
        CalibrateRequest,
        MeasureRequest,
        CorrectionCreate,
        RecipeCreate,
        SeamQaCreate,
        GgIndexRequest,
        TrompeRequest,
        SweepRequest,
        VariationsRequest,
        SwatchRequest,
        SnapRequest,
        FormulateRequest,
        ExportRequest,
        ClosedLoopRequest,
        RenderRequest,
    )
    for model in models:
        examples = model.model_json_schema().get("examples")
        assert examples, model.__name__
        for example in examples:
            model.model_validate(example)
