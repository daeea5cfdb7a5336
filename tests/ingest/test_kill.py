"""SIGKILL a real ingesting process at random instants: nothing acknowledged is lost, nothing is stored twice.

Each round starts ``tests.ingest._child`` (a separate Python process writing through the real
``Ingestor``), kills it with SIGKILL once it has acknowledged a random number (0 included: killed while
starting) of further readings, counted in its acknowledgement file, so that a loaded machine cannot
make a round end before the child got going or after the stream was done; then checks the invariants: every reading the
child acknowledged is in the database or in the outbox, no client id is stored twice, every stored
row has the hash of the reading it claims to be, and rows reach the database in stream order. Some
rounds run with the database unreachable (PostgreSQL: a closed port; SQLite: another process holds the
write lock), so the outbox and its replay are killed too. A last round runs to completion and the
database must then hold the whole stream exactly once with an empty outbox.
"""

from __future__ import annotations

import os
import random
import signal
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest
from sqlalchemy import func, select

from db.engine import make_engine
from db.models import Measurement
from station.ingest import Outbox
from tests.ingest._readings import make_reading
from tests.processes import Child
from tests.waiting import wait_until

REPO = Path(__file__).resolve().parents[2]
COUNT = 900
ROUNDS = 5
SEED = 7
#: A round kills the child once it has acknowledged up to this many readings more (database up, away: a
#: round with the database away acknowledges one reading per busy wait, 150 ms, so it stays short).
ROUND_ACKS = (60, 8)
#: Seconds a round may take to reach its kill point before it fails.
ROUND_TIMEOUT_S = 120.0


def _spawn(url: str, outbox: Path, acks: Path, busy_ms: int) -> Child:
    argv = [sys.executable, "-m", "tests.ingest._child", url, str(outbox), str(acks), str(SEED), str(COUNT)]
    return Child([*argv, str(busy_ms)], cwd=REPO, stdout=subprocess.DEVNULL)


def _acked(acks: Path) -> set[str]:
    if not acks.exists():
        return set()
    return {line.split()[1] for line in acks.read_text().splitlines() if len(line.split()) == 3}


def _ack_lines(acks: Path) -> int:
    """Acknowledgements written so far (complete lines)."""
    return acks.read_text().count("\n") if acks.exists() else 0


def _check(url: str, outbox_path: Path, acks: Path) -> int:
    expected = {
        str(make_reading(SEED, i).client_id): (i, make_reading(SEED, i).payload_sha256())
        for i in range(COUNT)
    }
    engine = make_engine(url)
    with engine.connect() as conn:
        rows = conn.execute(
            select(Measurement.id, Measurement.client_id, Measurement.payload_sha256).order_by(Measurement.id)
        ).all()
        total = conn.execute(select(func.count()).select_from(Measurement)).scalar_one()
    engine.dispose()
    stored = [str(r.client_id) for r in rows]
    assert total == len(set(stored)), "a client id is stored twice"
    for r in rows:
        assert expected[str(r.client_id)][1] == r.payload_sha256, "stored row does not match its reading"
    order = [expected[c][0] for c in stored]
    assert order == sorted(order), "readings reached the database out of order"
    with Outbox(outbox_path) as box:
        queued = {e.client_id for e in box.entries()}
        assert box.dead_letters() == []
    lost = _acked(acks) - set(stored) - queued
    assert not lost, f"{len(lost)} acknowledged readings lost"
    return len(stored)


def _run_rounds(url: str, tmp_path: Path, hold_lock: _NoLock) -> None:
    rng = random.Random(int.from_bytes(os.urandom(4), "little"))
    outbox, acks = tmp_path / "outbox.sqlite3", tmp_path / "acks.txt"
    for round_no in range(ROUNDS):
        down = round_no % 3 == 1
        with hold_lock(down) as (child_url, busy_ms), _spawn(child_url, outbox, acks, busy_ms) as child:
            target = _ack_lines(acks) + rng.randint(0, ROUND_ACKS[down])

            def round_done(n: int = target, c: Child = child) -> bool:
                return _ack_lines(acks) >= n or c.poll() is not None

            wait_until(
                round_done,
                ROUND_TIMEOUT_S,
                interval=0.01,
                what=f"round {round_no}: {target} acknowledgements",
            )
            child.kill()
            status = child.wait(30)
            assert child.err is not None
            assert status in (-signal.SIGKILL, 0), child.err.text()
        stored = _check(url, outbox, acks)
        with Outbox(outbox) as box:
            print(
                f"round {round_no} down={down}: stored {stored}, queued {len(box)}, acked {len(_acked(acks))}"
            )
    with _spawn(url, outbox, acks, 30_000) as child:
        assert child.finish(300) == 0, child.err.text() if child.err else ""
    assert _check(url, outbox, acks) == COUNT
    with Outbox(outbox) as box:
        assert len(box) == 0


class _NoLock:
    def __init__(self, url: str, down_url: str) -> None:
        self.url, self.down_url = url, down_url

    def __call__(self, down: bool) -> _NoLock:
        self.down = down
        return self

    def __enter__(self) -> tuple[str, int]:
        return (self.down_url if self.down else self.url), 30_000

    def __exit__(self, *_exc: object) -> None:
        return None


class _SqliteWriteLock(_NoLock):
    """While "down", another process-level connection holds SQLite's write lock."""

    def __enter__(self) -> tuple[str, int]:
        self.conn = None
        if self.down:
            self.conn = sqlite3.connect(self.url.removeprefix("sqlite:///"), isolation_level=None)
            self.conn.execute("BEGIN EXCLUSIVE")
            return self.url, 150
        return self.url, 30_000

    def __exit__(self, *_exc: object) -> None:
        if self.conn is not None:
            self.conn.execute("ROLLBACK")
            self.conn.close()


def test_kill_during_ingest_sqlite(tmp_path: Path) -> None:
    from db.migrate import upgrade

    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    upgrade(url)
    _run_rounds(url, tmp_path, _SqliteWriteLock(url, url))


@pytest.mark.postgres
def test_kill_during_ingest_postgres(pg_url: str, tmp_path: Path) -> None:
    from db.migrate import upgrade

    upgrade(pg_url)
    down = "postgresql://postgres@127.0.0.1:1/unreachable"
    _run_rounds(pg_url, tmp_path, _NoLock(pg_url, down))
