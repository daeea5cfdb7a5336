"""Scanning through a real database outage against a real ``station serve``: nothing lost, nothing twice.

PostgreSQL sits behind a TCP forwarder on 127.0.0.1 that the test closes (connections reset, new
ones refused); SQLite is held by a competing writer (``BEGIN EXCLUSIVE`` on its own connection).
With the database away a technician, whose token the service verified before, scans ``PANELS``
panels: every measure answers ``queued`` within a bounded time (the instrument is read, the reading
goes to the outbox), a retry under the same ``Idempotency-Key`` queues nothing new, and ``/health``
answers ``degraded`` at once. Once the database is back the service drains the outbox by itself: the
database then holds every reading exactly once, each with exactly one audit row, and the outbox is
empty. The expectation is the list of keys the test sent, counted in the database directly.
"""

from __future__ import annotations

import sqlite3
import time
import uuid
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from sqlalchemy import create_engine, func, select

from db.engine import SQLITE_BUSY_TIMEOUT_MS
from db.models import AuditEvent, Measurement
from station.ingest import Outbox
from tests.api._proxy import TcpProxy
from tests.ingest.test_serve_kill import _Service
from tests.waiting import wait_until

PANELS = 6
#: A measure with the database away takes one bounded busy wait (``SQLITE_BUSY_TIMEOUT_MS``) plus the
#: measurement itself; the measurement's share is bounded by REQUEST_WORK_FACTOR times a measure with the
#: database present, timed in the same run (so that a loaded machine moves the bound with it), plus
#: REQUEST_MARGIN_S.
REQUEST_WORK_FACTOR = 2.0
REQUEST_MARGIN_S = 1.5
HEALTH_BOUND_S = 3.0
DRAIN_TIMEOUT_S = 60.0


def _measure(
    http: httpx.Client, inst: str, panel: int, key: str, auth: dict[str, str]
) -> tuple[httpx.Response, float]:
    t0 = time.monotonic()
    r = http.post(
        f"/api/v1/instruments/{inst}/measure",
        json={"panel_id": panel},
        headers={**auth, "Idempotency-Key": key},
    )
    return r, time.monotonic() - t0


def _scan_through_outage(
    service: _Service, url: str, take_away: Callable[[], None], bring_back: Callable[[], None]
) -> None:
    service.start()
    admin = {"Authorization": f"Bearer {service.token}"}
    with httpx.Client(base_url=service.base, timeout=30) as http:
        tech = http.post("/api/v1/users", json={"name": "tec", "role": "technician"}, headers=admin)
        assert tech.status_code == 201, tech.text
        auth = {"Authorization": f"Bearer {tech.json()['token']}"}
        panels: list[int] = []
        for i in range(PANELS):
            r = http.post("/api/v1/panels", json={"job": f"OUT-{i}", "part": "test_panel"}, headers=auth)
            assert r.status_code == 201, r.text
            panels.append(int(r.json()["id"]))
        inst = http.get("/api/v1/instruments", headers=auth).json()[0]["id"]
        keys = [str(uuid.uuid4()) for _ in range(PANELS)]
        client_ids: list[str] = []  # the service derives each reading's id from the user and the key
        stored_before: list[str] = []  # two readings with the database present: the second is timed
        for i in range(2):
            r = http.post("/api/v1/panels", json={"job": f"OUT-base-{i}", "part": "test_panel"}, headers=auth)
            assert r.status_code == 201, r.text
            r, base_s = _measure(http, inst, int(r.json()["id"]), str(uuid.uuid4()), auth)
            assert r.status_code == 201 and r.json()["status"] == "stored", r.text
            stored_before.append(str(r.json()["measurement"]["id"]))
        bound_s = SQLITE_BUSY_TIMEOUT_MS / 1000 + REQUEST_WORK_FACTOR * base_s + REQUEST_MARGIN_S

        take_away()
        try:
            took: list[float] = []
            for panel, key in zip(panels, keys, strict=True):
                r, dt_s = _measure(http, inst, panel, key, auth)
                assert r.status_code == 201, r.text
                assert r.json()["status"] == "queued" and r.json()["measurement"] is None
                client_ids.append(r.json()["client_id"])
                took.append(dt_s)
            r, dt_s = _measure(http, inst, panels[0], keys[0], auth)  # a client retry: nothing new queued
            assert r.status_code == 201 and r.json()["status"] == "queued", r.text
            assert r.json()["client_id"] == client_ids[0]
            took.append(dt_s)
            print(f"measure seconds, database present {base_s:.2f}, away: {[round(t, 2) for t in took]}")
            assert max(took) < bound_s, (took, base_s, bound_s)
            t0 = time.monotonic()
            health = http.get("/health").json()
            assert time.monotonic() - t0 < HEALTH_BOUND_S
            assert health["status"] == "degraded" and health["database"] == "unreachable"
            assert health["queued"] == PANELS
        finally:
            bring_back()

        wait_until(
            lambda: (h := http.get("/health").json())["status"] == "ok" and h["queued"] == 0,
            DRAIN_TIMEOUT_S,
            interval=0.3,
            what="the outbox to drain (/health ok, queued 0)",
        )
        r, _ = _measure(http, inst, panels[0], keys[0], auth)  # the retry now finds the stored reading
        assert r.status_code == 200 and r.json()["status"] == "duplicate", r.text

    expected = {uuid.UUID(c) for c in client_ids}
    assert len(expected) == PANELS
    engine = create_engine(url)
    try:
        with engine.connect() as conn:
            rows = conn.execute(
                select(Measurement.id, Measurement.client_id).where(
                    Measurement.id.not_in([int(i) for i in stored_before])
                )
            ).all()
            audits = dict(
                conn.execute(
                    select(AuditEvent.entity_id, func.count())
                    .where(AuditEvent.entity == "measurement", AuditEvent.entity_id.not_in(stored_before))
                    .group_by(AuditEvent.entity_id)
                ).all()
            )
    finally:
        engine.dispose()
    assert len(rows) == PANELS, rows
    assert {r.client_id for r in rows} == expected
    assert sorted(int(e) for e in audits) == sorted(r.id for r in rows)
    assert set(audits.values()) == {1}
    with Outbox(service.data_dir / "outbox.sqlite3") as box:
        assert len(box) == 0 and box.dead_letters() == []


def _run(service: _Service, url: str, take_away: Callable[[], None], bring_back: Callable[[], None]) -> None:
    try:
        _scan_through_outage(service, url, take_away, bring_back)
    except BaseException:
        print("station serve output (tail):\n" + "".join(service.log[-60:]))
        raise
    finally:
        service.stop()


@pytest.mark.slow
def test_scan_through_a_locked_sqlite_database(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CACAD_OUTBOX_REPLAY_S", "0.5")
    db_file = tmp_path / "station.sqlite3"
    held: list[sqlite3.Connection] = []

    def take_away() -> None:
        conn = sqlite3.connect(db_file, isolation_level=None, timeout=10)
        conn.execute("BEGIN EXCLUSIVE")
        held.append(conn)

    def bring_back() -> None:
        for conn in held:
            conn.execute("ROLLBACK")
            conn.close()
        held.clear()

    _run(_Service(tmp_path, None), f"sqlite:///{db_file}", take_away, bring_back)


@pytest.mark.slow
@pytest.mark.postgres
def test_scan_through_a_postgresql_outage(
    pg_url: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CACAD_OUTBOX_REPLAY_S", "0.5")
    host_port = pg_url.split("@", 1)[1].split("/", 1)[0]
    host, port = host_port.rsplit(":", 1)
    proxy = TcpProxy((host, int(port)))
    proxy.open()
    via_proxy = pg_url.replace(f"@{host_port}/", f"@127.0.0.1:{proxy.port}/")
    try:
        _run(_Service(tmp_path, via_proxy), pg_url, proxy.close, proxy.open)
    finally:
        proxy.close()
