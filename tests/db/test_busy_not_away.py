"""A busy SQLite database is not an absent one (issue 24 Found 4), against a real ``station serve``.

One client loops the library CSV export (a big read of ~6000 demo paints) while another polls
``/health`` and scans panels through the simulated MA6: ``/health`` must never say the database is
away, every scan must be stored (never diverted to the outbox), and the database must then hold each
reading once. A competing writer holding the write lock from its own connection makes ``/health``
answer ``busy`` with status ``ok``; a database file that cannot be opened makes it ``unreachable``.
Deadlines bound every wait; nothing sleeps.
"""

from __future__ import annotations

import sqlite3
import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from sqlalchemy import text
from sqlalchemy.pool import NullPool

from db.engine import make_engine
from tests.serve_process import serving

REPO = Path(__file__).resolve().parents[2]
SCANS = 12
EXPORTS_AT_LEAST = 3  # the reader really ran beside the scans
START_TIMEOUT_S = 180.0
DEADLINE_S = 240.0


@pytest.fixture
def service(tmp_path: Path) -> Iterator[tuple[str, dict[str, str], Path]]:
    """``station serve`` on SQLite with the demo library and a simulated MA6: base URL, admin auth, file."""
    db = tmp_path / "station.sqlite3"
    with serving(
        tmp_path, "--database", f"sqlite:///{db}", "--simulators", "ma6", cwd=REPO, own_group=True,
        start_timeout_s=START_TIMEOUT_S,
    ) as svc:  # fmt: skip
        assert svc.token, svc.tail()
        yield svc.base, {"Authorization": f"Bearer {svc.token}"}, db


def _count(db: Path) -> tuple[int, int]:
    engine = make_engine(f"sqlite:///{db}", poolclass=NullPool)
    try:
        with engine.connect() as conn:
            row = conn.execute(text("SELECT count(*), count(DISTINCT client_id) FROM measurements")).one()
    finally:
        engine.dispose()
    return int(row[0]), int(row[1])


def test_a_reader_looping_the_library_export_neither_degrades_health_nor_diverts_scans(
    service: tuple[str, dict[str, str], Path],
) -> None:
    base, auth, db = service
    deadline = time.monotonic() + DEADLINE_S
    stop = threading.Event()
    exports: list[int] = []
    failures: list[str] = []

    def read_loop() -> None:
        with httpx.Client(base_url=base, timeout=60) as http:
            while not stop.is_set() and time.monotonic() < deadline:
                r = http.get("/api/v1/library/export.csv", headers=auth)
                if r.status_code != 200:
                    failures.append(f"export {r.status_code}: {r.text[:200]}")
                    return
                exports.append(len(r.content))

    with httpx.Client(base_url=base, timeout=60) as http:
        panel = http.post("/api/v1/panels", json={"job": "BUSY-1", "part": "door"}, headers=auth)
        assert panel.status_code == 201, panel.text
        inst = http.get("/api/v1/instruments", headers=auth).json()[0]["id"]
        reader = threading.Thread(target=read_loop, name="export-loop")
        reader.start()
        health: list[dict[str, object]] = []
        statuses: list[str] = []
        try:
            while len(exports) < 1 and not failures:  # the reader is under way before the first scan
                assert time.monotonic() < deadline, "no export finished in time"
                health.append(http.get("/health").json())
            for _ in range(SCANS):
                health.append(http.get("/health").json())
                r = http.post(
                    f"/api/v1/instruments/{inst}/measure",
                    json={"panel_id": panel.json()["id"], "client_id": str(uuid.uuid4())},
                    headers=auth,
                )
                assert r.status_code == 201, r.text
                statuses.append(str(r.json()["status"]))
                health.append(http.get("/health").json())
            while len(exports) < EXPORTS_AT_LEAST and not failures:
                assert time.monotonic() < deadline, f"only {len(exports)} exports in time"
                health.append(http.get("/health").json())
        finally:
            stop.set()
            reader.join(60)
    assert not failures, failures
    away = [h for h in health if h["status"] != "ok" or h["database"] == "unreachable"]
    assert not away, f"{len(away)} of {len(health)} polls said away: {away[:3]}"
    assert statuses == ["stored"] * SCANS, statuses
    assert all(h["queued"] == 0 for h in health), health
    assert _count(db) == (SCANS, SCANS)


def test_health_tells_a_held_write_lock_from_a_database_that_cannot_be_opened(
    service: tuple[str, dict[str, str], Path],
) -> None:
    base, _auth, db = service
    with httpx.Client(base_url=base, timeout=30) as http:
        assert http.get("/health").json()["database"] == "ok"
        holder = sqlite3.connect(db, isolation_level=None, timeout=5)
        try:
            holder.execute("BEGIN IMMEDIATE")
            t0 = time.monotonic()
            busy = http.get("/health")
            took = time.monotonic() - t0
        finally:
            holder.execute("ROLLBACK")
            holder.close()
        assert busy.status_code == 200 and took < 2.0, (busy.text, took)
        assert busy.json()["status"] == "ok" and busy.json()["database"] == "busy", busy.json()
        assert http.get("/health").json()["database"] == "ok"
        moved = db.with_name("moved.sqlite3")
        db.rename(moved)  # the service's open connections keep the old file; the probe opens the path
        try:
            gone = http.get("/health").json()
        finally:
            moved.rename(db)
        assert gone["status"] == "degraded" and gone["database"] == "unreachable", gone
