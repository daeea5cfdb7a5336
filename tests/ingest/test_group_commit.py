"""Group commit (``station.ingest.group``): concurrent readings share one transaction, each stored once.

Real SQLite file and real PostgreSQL (``database_url``), real threads. The writer of the first group is
held inside its transaction until every other caller has queued, so the second group provably carries
all of them: fewer commits than readings, every reading stored once with one audit row, the hash chain
intact, and a refused reading failing only its own caller.
"""

from __future__ import annotations

import asyncio
import threading
import uuid
from typing import Any

import pytest
from sqlalchemy import event, func, select
from sqlalchemy.orm import Session

from db import chain_audit
from db.engine import make_engine, make_sessionmaker
from db.models import AuditEvent, Measurement
from station.ingest import ClientIdConflictError, Reading, StoreResult
from station.ingest.group import GroupCommit
from tests.ingest._readings import make_reading
from tests.waiting import wait_until

CALLERS = 8
WAIT_S = 60.0  # a deadline for the test's own hand-off, never a pass condition


def _run(
    url: str, readings: list[Reading], hold_first: bool = True
) -> tuple[list[Any], list[BaseException | None], int]:
    """Store *readings* from one thread each through one :class:`GroupCommit`; (answers, errors, commits)."""
    engine = make_engine(url, pool_size=len(readings) + 1)
    sessions = make_sessionmaker(engine)
    commits = 0

    @event.listens_for(engine, "commit")
    def _count(_conn: Any) -> None:
        nonlocal commits
        commits += 1

    group: GroupCommit[int] = GroupCommit("measurement.create")
    first_in = threading.Event()
    answers: list[Any] = [None] * len(readings)
    errors: list[BaseException | None] = [None] * len(readings)

    def answer(_session: Session, _reading: Reading, result: StoreResult) -> int:
        if hold_first and not first_in.is_set():
            first_in.set()  # the first writer waits, in its transaction, for everyone else to queue
            wait_until(lambda: group.queued >= len(readings) - 1, WAIT_S, 0.01, "the other writers queued")
        return result.measurement_id

    def call(k: int) -> None:
        with sessions() as session:
            try:
                answers[k] = group.store(session, readings[k], actor_id=None, answer=answer)
            except BaseException as exc:  # recorded for the assertions
                errors[k] = exc

    first = threading.Thread(target=call, args=(0,))
    first.start()
    if hold_first:
        assert first_in.wait(WAIT_S)
    else:
        first.join(WAIT_S)
    others = [threading.Thread(target=call, args=(k,)) for k in range(1, len(readings))]
    for t in others:
        t.start()
    for t in (first, *others):
        t.join(WAIT_S)
        assert not t.is_alive()
    engine.dispose()
    return answers, errors, commits


def _stored(url: str) -> tuple[list[str], int, list[chain_audit.Verdict]]:
    engine = make_engine(url)
    with engine.connect() as conn:
        ids = [str(c) for c in conn.execute(select(Measurement.client_id)).scalars()]
        audits = conn.execute(
            select(func.count()).select_from(AuditEvent).where(AuditEvent.entity == "measurement")
        ).scalar_one()
        verdicts = chain_audit.verify(conn)
    engine.dispose()
    return ids, int(audits), verdicts


def test_concurrent_readings_share_a_commit_and_are_stored_once(database_url: str) -> None:
    readings = [make_reading(41, i, serial=f"GC-{i % 3}") for i in range(CALLERS)]
    answers, errors, commits = _run(database_url, readings)
    assert errors == [None] * CALLERS
    assert all(isinstance(a, tuple) and a[1] is True for a in answers)
    assert len({a[0] for a in answers}) == CALLERS  # one row each
    assert commits == 2  # the held first reading, then the seven that queued behind it, together
    ids, audits, verdicts = _stored(database_url)
    assert sorted(ids) == sorted(str(r.client_id) for r in readings)
    assert audits == CALLERS
    assert [v.broken for v in verdicts] == [None, None]


def test_a_refused_reading_fails_only_its_caller(database_url: str) -> None:
    readings = [make_reading(42, i) for i in range(CALLERS)]
    first, _ = _run(database_url, readings[:1], hold_first=False)[:2]
    assert first[0][1] is True
    clash = readings[0].model_copy(update={"operator": "someone else"})  # same client id, other payload
    again = readings[1:4] + [clash] + readings[4:6] + [readings[1]]  # a re-send of a new one too
    answers, errors, _commits = _run(database_url, again)
    assert isinstance(errors[3], ClientIdConflictError)
    assert [e for k, e in enumerate(errors) if k != 3] == [None] * 6
    created = [a[1] for k, a in enumerate(answers) if k != 3]
    assert sorted(created) == [False] + [True] * 5  # readings[1] once stored, once a duplicate
    ids, audits, verdicts = _stored(database_url)
    assert sorted(ids) == sorted(str(r.client_id) for r in readings[:6])
    assert audits == 6
    assert [v.broken for v in verdicts] == [None, None]


def test_a_failed_commit_fails_every_caller_of_the_group(tmp_path: Any) -> None:
    url = f"sqlite:///{tmp_path / 'gone.sqlite3'}"  # never migrated: no tables to store into
    engine = make_engine(url)
    group: GroupCommit[int] = GroupCommit("measurement.create")
    with make_sessionmaker(engine)() as session, pytest.raises(Exception) as caught:
        group.store(
            session,
            make_reading(43, 0).model_copy(update={"client_id": uuid.uuid4()}),
            actor_id=None,
            answer=lambda _s, _r, res: res.measurement_id,
        )
    engine.dispose()
    assert "no such table" in str(caught.value)
    assert group.queued == 0


def test_a_group_with_stored_and_clashing_readings_matches_one_at_a_time(database_url: str) -> None:
    """Without a client id twice in the group (the batched path on PostgreSQL): a re-sent reading
    answers its stored row, a clash fails only its caller, the rest are stored once with their events."""
    readings = [make_reading(44, i, serial=f"GB-{i % 2}") for i in range(CALLERS)]
    stored_first = _run(database_url, readings[:2], hold_first=False)[0]
    clash = readings[1].model_copy(update={"operator": "someone else"})
    again = [readings[0], clash, *readings[2:]]  # a re-send, a clash, six new ones: no id twice
    answers, errors, _commits = _run(database_url, again)
    assert isinstance(errors[1], ClientIdConflictError)
    assert [e for k, e in enumerate(errors) if k != 1] == [None] * (CALLERS - 1)
    assert answers[0] == (stored_first[0][0], False)  # the stored row's id, not created again
    assert all(a[1] is True for a in answers[2:])
    assert len({a[0] for a in answers if a is not None}) == CALLERS - 1
    ids, audits, verdicts = _stored(database_url)
    assert sorted(ids) == sorted(str(r.client_id) for r in readings)
    assert audits == CALLERS  # one event per stored reading, none for the re-send or the clash
    assert [v.broken for v in verdicts] == [None, None]


def test_coroutine_and_thread_callers_share_groups(database_url: str) -> None:
    """store_async (the service's route) and store (threads) on one GroupCommit: each reading once,
    with one audit event, in fewer commits than readings, the chain intact."""
    engine = make_engine(database_url, pool_size=4)
    sessions = make_sessionmaker(engine)
    commits = 0

    @event.listens_for(engine, "commit")
    def _count(_conn: Any) -> None:
        nonlocal commits
        commits += 1

    group: GroupCommit[int] = GroupCommit("measurement.create")
    readings = [make_reading(45, i, serial=f"GA-{i % 3}") for i in range(3 * CALLERS)]

    def answer(_session: Session, _reading: Reading, result: StoreResult) -> int:
        return result.measurement_id

    async def coroutines() -> list[tuple[int, bool]]:
        return await asyncio.gather(
            *(group.store_async(sessions, r, actor_id=None, answer=answer) for r in readings[: CALLERS * 2])
        )

    threaded: list[tuple[int, bool] | BaseException] = []

    def thread_call(reading: Reading) -> None:
        with sessions() as session:
            try:
                threaded.append(group.store(session, reading, actor_id=None, answer=answer))
            except BaseException as exc:  # recorded for the assertions
                threaded.append(exc)

    threads = [threading.Thread(target=thread_call, args=(r,)) for r in readings[CALLERS * 2 :]]
    for t in threads:
        t.start()
    awaited = asyncio.run(coroutines())
    for t in threads:
        t.join(WAIT_S)
        assert not t.is_alive()
    engine.dispose()
    answers = [*awaited, *threaded]
    assert all(isinstance(a, tuple) and a[1] is True for a in answers)
    assert len({a[0] for a in answers if isinstance(a, tuple)}) == len(readings)
    assert commits < len(readings)
    assert group.queued == 0
    ids, audits, verdicts = _stored(database_url)
    assert sorted(ids) == sorted(str(r.client_id) for r in readings)
    assert audits == len(readings)
    assert [v.broken for v in verdicts] == [None, None]
