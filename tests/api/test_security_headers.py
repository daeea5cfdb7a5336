"""Security headers: ``X-Content-Type-Options: nosniff`` and ``Cache-Control: no-store`` on every
response — success, refusal and error alike — and on the responses that carry a new token."""

from __future__ import annotations

import pytest

from tests.api.conftest import Api

V1 = "/api/v1"


def _assert_protected(r: object) -> None:
    headers = r.headers  # type: ignore[attr-defined]
    assert headers["x-content-type-options"] == "nosniff", headers
    assert headers["cache-control"] == "no-store", headers
    assert headers["x-frame-options"] == "DENY"


def test_token_responses_are_no_store(sqlite_api: Api) -> None:
    api = sqlite_api
    made = api.client.post(f"{V1}/users", json={"name": "ann", "role": "qa"}, headers=api.auth("admin"))
    assert made.status_code == 201, made.text
    assert made.json()["token"].startswith("cst_")
    _assert_protected(made)
    uid = made.json()["user"]["id"]
    again = api.client.post(f"{V1}/users/{uid}/tokens", json={"label": "booth-2"}, headers=api.auth("admin"))
    assert again.status_code == 201, again.text
    _assert_protected(again)


@pytest.mark.parametrize(
    ("method", "path", "kwargs", "status"),
    [
        ("get", "/health", {}, 200),
        ("get", f"{V1}/me", {}, 401),
        ("get", f"{V1}/measurements/999999", {"role": "qa"}, 404),
        ("get", f"{V1}/users", {"role": "technician"}, 403),
        ("post", f"{V1}/panels", {"role": "technician", "json": {"job": 1}}, 422),
        ("post", f"{V1}/styling/eyedrop", {"role": "stylist", "content": b"\0" * (2 << 20)}, 413),
        ("get", "/openapi.json", {"role": "qa"}, 200),
        ("get", "/no-such-route", {}, 404),
    ],
)
def test_every_response_carries_the_headers(
    sqlite_api: Api, method: str, path: str, kwargs: dict, status: int
) -> None:
    role = kwargs.pop("role", None)
    headers = sqlite_api.auth(role) if role else {}
    r = getattr(sqlite_api.client, method)(path, headers=headers, **kwargs)
    assert r.status_code == status, r.text
    _assert_protected(r)
