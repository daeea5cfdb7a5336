"""Tokens expire, can be revoked one by one (route and CLI), and keep working for a bounded time without the database.

Expectations are independent of the code under test: expiry instants are bracketed by the wall clock
read around the request, revocations are made through a second, separate connection or the CLI (as
another process would), and the offline window is driven by a fake monotonic clock.
"""

from __future__ import annotations

import datetime as dt
import json
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, select, update

from db.models import ApiToken, AuditEvent, Role
from station.api.security import TokenCache, TokenGrant
from station.cli import main
from tests.api.conftest import Api, make_api
from tests.waiting import wait_until


@pytest.fixture
def sqlite_file_api(tmp_path: Path) -> Iterator[Api]:
    yield from make_api(
        f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, token_ttl_days=2.0, token_recheck_s=0
    )


def _parse(at: str) -> dt.datetime:
    return dt.datetime.fromisoformat(at.replace("Z", "+00:00"))


def test_issued_tokens_expire_after_the_configured_lifetime(sqlite_file_api: Api) -> None:
    api = sqlite_file_api
    before = dt.datetime.now(dt.UTC)
    r = api.client.post(
        "/api/v1/users", json={"name": "ana", "role": "technician"}, headers=api.auth("admin")
    )
    after = dt.datetime.now(dt.UTC)
    assert r.status_code == 201, r.text
    expires = _parse(r.json()["expires_at"])
    assert before + dt.timedelta(days=2) - dt.timedelta(seconds=1) <= expires <= after + dt.timedelta(days=2)


def test_an_expired_token_is_a_401_saying_so(sqlite_file_api: Api, tmp_path: Path) -> None:
    api = sqlite_file_api
    assert api.client.get("/api/v1/me", headers=api.auth("qa")).status_code == 200
    engine = create_engine(f"sqlite:///{tmp_path / 'station.sqlite3'}")
    past = dt.datetime.now(dt.UTC) - dt.timedelta(seconds=1)
    with engine.begin() as conn:  # another process ages the token
        conn.execute(update(ApiToken).where(ApiToken.label == "").values(expires_at=past))
    engine.dispose()
    r = api.client.get("/api/v1/me", headers=api.auth("qa"))
    assert r.status_code == 401
    assert "expired" in r.json()["detail"]
    assert r.headers["www-authenticate"] == "Bearer"


def test_tokens_are_revoked_one_by_one_by_admin_or_owner(sqlite_file_api: Api) -> None:
    api, admin = sqlite_file_api, sqlite_file_api.auth("admin")
    ana = api.client.post("/api/v1/users", json={"name": "ana", "role": "technician"}, headers=admin).json()
    second = api.client.post(f"/api/v1/users/{ana['user']['id']}/tokens", json={"label": "b"}, headers=admin)
    first_auth = {"Authorization": f"Bearer {ana['token']}"}
    second_auth = {"Authorization": f"Bearer {second.json()['token']}"}
    # another (non-admin) user cannot see or revoke ana's token
    r = api.client.delete(f"/api/v1/tokens/{ana['token_id']}", headers=api.auth("qa"))
    assert r.status_code == 404
    # the owner revokes the first; the second keeps working
    r = api.client.delete(f"/api/v1/tokens/{ana['token_id']}", headers=first_auth)
    assert r.status_code == 200 and r.json()["revoked_at"] is not None
    r = api.client.get("/api/v1/me", headers=first_auth)
    assert r.status_code == 401 and "revoked" in r.json()["detail"]
    assert api.client.get("/api/v1/me", headers=second_auth).status_code == 200
    # the admin revokes the second
    assert api.client.delete(f"/api/v1/tokens/{second.json()['token_id']}", headers=admin).status_code == 200
    assert api.client.get("/api/v1/me", headers=second_auth).status_code == 401
    listed = api.client.get(f"/api/v1/users/{ana['user']['id']}/tokens", headers=admin).json()
    assert [t["revoked_at"] is not None for t in listed] == [True, True]
    audit = api.client.get("/api/v1/audit", params={"entity": "user"}, headers=admin).json()["data"]
    assert sorted(e["detail"]["token_id"] for e in audit if e["action"] == "token.revoke") == sorted(
        [ana["token_id"], second.json()["token_id"]]
    )


def test_cli_revokes_a_token_the_service_then_refuses(sqlite_file_api: Api, tmp_path: Path, capsys) -> None:
    api = sqlite_file_api
    assert api.client.get("/api/v1/me", headers=api.auth("chemist")).status_code == 200
    d = ["--data-dir", str(tmp_path), "--json"]
    assert main(["users", "tokens", "chemist-1", *d]) == 0
    (token,) = json.loads(capsys.readouterr().out)["tokens"]
    assert main(["users", "revoke-token", str(token["id"]), *d]) == 0
    assert json.loads(capsys.readouterr().out)["revoked_at"] is not None
    assert main(["users", "revoke-token", "x1", *d]) == 2
    assert "token_id" in capsys.readouterr().err
    r = api.client.get("/api/v1/me", headers=api.auth("chemist"))
    assert r.status_code == 401 and "revoked" in r.json()["detail"]


def _lock(path: Path) -> sqlite3.Connection:
    """A competing writer holding the database's write lock (``BEGIN EXCLUSIVE``)."""
    conn = sqlite3.connect(path, isolation_level=None, timeout=5)
    conn.execute("BEGIN EXCLUSIVE")
    return conn


def test_tokens_are_checked_while_another_writer_holds_the_lock_and_revocation_holds_after(
    tmp_path: Path,
) -> None:
    """Token checks only read: a competing writer's lock neither delays them nor makes them 503 (issue 24
    Found 4, first logins refused while someone wrote), and ``/health`` says ``busy``, not away."""
    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, token_offline_s=60)
    api = next(gen)
    try:
        tech = api.auth("technician")
        assert api.client.get("/api/v1/me", headers=tech).status_code == 200  # verified, cached
        lock = _lock(tmp_path / "station.sqlite3")
        try:
            for _ in range(3):
                t0 = time.monotonic()
                r = api.client.get("/api/v1/me", headers=tech)
                took = time.monotonic() - t0
                assert r.status_code == 200, r.text
                assert r.json()["name"] == "technician-1"
                assert took < 1.0, took  # a read does not wait for the writer's lock
            # a token this service never verified is checked all the same: the read needs no lock
            t0 = time.monotonic()
            r = api.client.get("/api/v1/me", headers=api.auth("stylist"))
            assert r.status_code == 200 and time.monotonic() - t0 < 1.0, r.text
            health = api.client.get("/health").json()
            assert health["status"] == "ok" and health["database"] == "busy", health
        finally:
            lock.execute("ROLLBACK")
            lock.close()
        engine = create_engine(f"sqlite:///{tmp_path / 'station.sqlite3'}")
        with engine.begin() as conn:  # revoked by another process once the database is back
            conn.execute(update(ApiToken).values(revoked_at=dt.datetime.now(dt.UTC)))
        engine.dispose()

        def answer() -> tuple[int, str]:
            r = api.client.get("/api/v1/me", headers=tech)
            return r.status_code, str(r.json().get("detail", ""))

        revoked = wait_until(lambda: (a := answer())[0] == 401 and a, 30, interval=0.5)
        assert revoked
        status, detail = revoked
        assert "revoked" in detail, (status, detail)
        assert api.client.get("/health").json()["status"] == "ok"
    finally:
        gen.close()


def test_a_revocation_made_elsewhere_applies_within_the_recheck_time(tmp_path: Path) -> None:
    recheck_s = 1.0
    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, token_recheck_s=recheck_s)
    api = next(gen)
    try:
        assert api.client.get("/api/v1/me", headers=api.auth("qa")).status_code == 200  # verified, cached
        engine = create_engine(f"sqlite:///{tmp_path / 'station.sqlite3'}")
        with engine.begin() as conn:  # another process (the CLI) revokes every token
            conn.execute(update(ApiToken).values(revoked_at=dt.datetime.now(dt.UTC)))
        engine.dispose()
        revoked_at = time.monotonic()

        def refused() -> bool:
            """One request; one sent more than the recheck time after the revocation (hence after the
            grant was cached) must be refused, however long the machine takes to answer it."""
            sent = time.monotonic()
            status = api.client.get("/api/v1/me", headers=api.auth("qa")).status_code
            assert status in (200, 401), status
            late = sent - revoked_at
            assert status == 401 or late <= recheck_s, f"still served {late:.2f} s after the revocation"
            return status == 401

        wait_until(refused, 30, what="the revocation to apply")
    finally:
        gen.close()


def _grant(user_id: int = 1) -> TokenGrant:
    now = dt.datetime.now(dt.UTC)
    return TokenGrant(1, user_id, "ana", Role.TECHNICIAN, True, now, now + dt.timedelta(days=1), None)


def test_the_cache_forgets_a_grant_after_the_offline_window(monkeypatch: pytest.MonkeyPatch) -> None:
    clock = [1000.0]
    monkeypatch.setattr("station.api.security.time.monotonic", lambda: clock[0])
    cache = TokenCache(offline_s=30.0)
    cache.put("h", _grant())
    clock[0] += 30.0
    assert cache.get("h") is not None
    clock[0] += 0.001
    assert cache.get("h") is None
    cache.put("h", _grant(7))
    cache.put("k", _grant(8))
    cache.drop(user_id=7)
    assert cache.get("h") is None and cache.get("k") is not None


def test_grant_refusals_name_the_reason() -> None:
    now = dt.datetime.now(dt.UTC)
    base = _grant()
    assert base.refusal(now) is None
    expired = TokenGrant(2, 1, "ana", Role.QA, True, now, now - dt.timedelta(seconds=1), None)
    assert "expired" in (expired.refusal(now) or "")
    revoked = TokenGrant(3, 1, "ana", Role.QA, True, now, None, now)
    assert "revoked" in (revoked.refusal(now) or "")
    inactive = TokenGrant(4, 1, "ana", Role.QA, False, now, None, None)
    assert "deactivated" in (inactive.refusal(now) or "")


def test_revoking_twice_keeps_the_first_time_and_one_audit_event(tmp_path: Path) -> None:
    """Revoking twice records one audit event (the first revocation time is kept)."""
    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        admin = api.auth("admin")
        users = api.client.get("/api/v1/users", headers=admin).json()
        qa = next(u for u in users if u["role"] == "qa")
        (token,) = api.client.get(f"/api/v1/users/{qa['id']}/tokens", headers=admin).json()
        first = api.client.delete(f"/api/v1/tokens/{token['id']}", headers=admin).json()
        again = api.client.delete(f"/api/v1/tokens/{token['id']}", headers=admin).json()
        assert first["revoked_at"] == again["revoked_at"]
        with api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
            n = len(session.scalars(select(AuditEvent).where(AuditEvent.action == "token.revoke")).all())
        assert n == 1
    finally:
        gen.close()
