"""SIGKILL a real ``station serve`` while a client drives the measure route: nothing lost, nothing stored twice.

The service runs as its own process group (uvicorn, the app, a simulated MA6 subprocess), exactly as
shipped. A client measures a stream of readings, each under its own client id, through
``POST /api/v1/instruments/{id}/measure``; a timer SIGKILLs the whole group at a random instant
(during a measurement, a database commit, a response, or between requests). The client then restarts
the service and retries the same client id until it gets an answer, as a station would. At the end the
database holds every reading of the stream exactly once, under the measurement id the client was
given, with one audit row each, and the service's outbox is empty.
"""

from __future__ import annotations

import os
import random
import threading
import time
import uuid
from pathlib import Path

import httpx
import pytest
from sqlalchemy import create_engine, func, select

from db.models import AuditEvent, Measurement
from station.ingest import Outbox
from tests.serve_process import ServeProcess, ServeStartError

REPO = Path(__file__).resolve().parents[2]
NAMESPACE = uuid.UUID("2c4e6a80-1b3d-4f5a-9c7e-0d2f4b6a8c13")
READINGS = 16
KILLS = 4
START_TIMEOUT_S = 90.0
TEST_BUDGET_S = 240.0


class _Service(ServeProcess):
    """``station serve`` with a simulated MA6 in its own process group; started, killed and restarted."""

    def __init__(self, data_dir: Path, database_url: str | None) -> None:
        args: tuple[str, ...] = ("--database", database_url) if database_url is not None else ()
        args += ("--no-demo-library", "--simulators", "ma6")
        super().__init__(data_dir, args, cwd=REPO, own_group=True, start_timeout_s=START_TIMEOUT_S)

    def start(self) -> _Service:
        try:
            super().start()
        except ServeStartError as exc:
            pytest.fail(str(exc))
        return self


def _instrument(http: httpx.Client, auth: dict[str, str]) -> str:
    instruments = http.get("/api/v1/instruments", headers=auth).json()
    assert [i["model"] for i in instruments] == ["MA6"], instruments
    return str(instruments[0]["id"])


def _drive(service: _Service, rng: random.Random) -> tuple[dict[str, int], dict[str, int]]:
    """Measure READINGS readings through kills and restarts; ``({client_id: measurement_id}, status counts)``."""
    service.start()
    assert service.token, "bootstrap admin token not printed on first start"
    auth = {"Authorization": f"Bearer {service.token}"}
    acked: dict[str, int] = {}
    statuses = dict.fromkeys(("stored", "duplicate", "queued", "restarts", "in_flight", "between"), 0)
    last_request_s = 0.5
    kills_left = KILLS
    timer: threading.Timer | None = None
    t_end = time.monotonic() + TEST_BUDGET_S
    with httpx.Client(timeout=60) as http:
        http.base_url = httpx.URL(service.base)
        panel = http.post("/api/v1/panels", json={"job": "K-1", "part": "door"}, headers=auth).json()["id"]
        inst = _instrument(http, auth)
        for i in range(READINGS):
            cid = str(uuid.uuid5(NAMESPACE, f"{rng.random()}/{i}"))
            while True:
                assert time.monotonic() < t_end, f"over budget; stored so far {len(acked)}"
                alive = service.proc is not None and service.proc.poll() is None
                if (
                    timer is None
                    and kills_left > 0
                    and alive
                    and service.proc is not None
                    and rng.random() < 0.4
                ):
                    # armed as the request leaves: mostly lands inside it (measuring, committing, answering)
                    delay = rng.uniform(0.0, 1.3 * last_request_s)
                    timer = threading.Timer(delay, service.kill, args=(service.proc,))
                    timer.start()
                    kills_left -= 1
                sent = time.monotonic()
                try:
                    r = http.post(
                        f"/api/v1/instruments/{inst}/measure",
                        json={"client_id": cid, "panel_id": panel},
                        headers=auth,
                    )
                except httpx.TransportError as exc:  # killed under us: restart and retry the same client id
                    statuses["in_flight" if not isinstance(exc, httpx.ConnectError) else "between"] += 1
                    if timer is not None:
                        timer.join()
                    if (
                        service.proc is not None
                    ):  # a transport error we did not cause (a timeout): same treatment
                        service.kill(service.proc)
                        service.proc.wait(20)
                    timer = None
                    statuses["restarts"] += 1
                    service.start()
                    http.base_url = httpx.URL(service.base)
                    inst = _instrument(http, auth)
                    continue
                assert r.status_code in (200, 201), r.text
                last_request_s = time.monotonic() - sent
                body = r.json()
                assert body["client_id"] == cid
                statuses[body["status"]] += 1
                if body["status"] == "queued":  # SQLite is never away here; a queued reading must land later
                    continue
                acked[cid] = int(body["measurement"]["id"])
                if timer is not None and not timer.is_alive():
                    if service.proc is not None and service.proc.poll() is not None:
                        service.proc.wait()
                    timer = None
                break
    if timer is not None:
        timer.cancel()
    return acked, statuses


def _check(url: str, outbox_path: Path, acked: dict[str, int]) -> None:
    engine = create_engine(url)
    try:
        with engine.connect() as conn:
            rows = conn.execute(select(Measurement.id, Measurement.client_id)).all()
            audits = conn.execute(
                select(AuditEvent.entity_id, func.count())
                .where(AuditEvent.entity == "measurement")
                .group_by(AuditEvent.entity_id)
            ).all()
    finally:
        engine.dispose()
    stored = {str(r.client_id): int(r.id) for r in rows}
    assert len(rows) == len(stored), "a client id is stored twice"
    assert len(acked) == READINGS
    assert stored == acked, "the database does not hold exactly the acknowledged readings"
    assert sorted(int(e) for e, _n in audits) == sorted(stored.values())
    assert all(n == 1 for _e, n in audits), "a reading was audited twice"
    with Outbox(outbox_path) as box:
        assert len(box) == 0 and box.dead_letters() == []


def _run(tmp_path: Path, database_url: str | None) -> None:
    seed = int.from_bytes(os.urandom(4), "little")
    service = _Service(tmp_path, database_url)
    try:
        acked, statuses = _drive(service, random.Random(seed))
    except BaseException:
        print(f"seed {seed}; station serve output (tail):\n" + "".join(service.log[-60:]))
        raise
    finally:
        service.stop()
    print(f"seed {seed}: {statuses}")
    assert statuses["restarts"] >= 1, "no kill landed"
    url = database_url or f"sqlite:///{tmp_path / 'station.sqlite3'}"
    _check(url, tmp_path / "outbox.sqlite3", acked)


@pytest.mark.slow
def test_kill_station_serve_during_measure_sqlite(tmp_path: Path) -> None:
    _run(tmp_path, None)


@pytest.mark.slow
@pytest.mark.postgres
def test_kill_station_serve_during_measure_postgres(pg_url: str, tmp_path: Path) -> None:
    _run(tmp_path, pg_url)
