"""Group commit: readings that arrive together are stored in one transaction, one commit, one sync.

Every store into the measurement database is serialised twice over: by the write lock (SQLite's
``BEGIN IMMEDIATE``) and by the hash chain's head row, which each appended row must read and move
(``db.chain``). Stored one transaction per reading, concurrent writers queue on that lock and each
pays a commit (an fsync) while the others wait. :class:`GroupCommit` lets concurrent callers share
the transaction instead: the first caller that finds no write in progress becomes the writer, takes
every reading queued so far (at most ``max_batch``), stores them one after the other, commits
once and hands each caller its own outcome; callers that arrived meanwhile form the next group.
Nothing waits for a group to fill: a caller alone is stored at once, so no timer decides a result.

Each caller still gets an answer only after its reading is committed (durable), and each reading is
stored exactly once by client id, as :func:`~station.ingest.destination.store_audited` stores it
(the group through :func:`~station.ingest.destination.store_audited_many`: on PostgreSQL the chain's
head is locked and the stored client ids are looked up once per group, and the group's rows and head
moves travel in one pipeline per chain). A
reading the database refuses (a client-id conflict, a missing panel) raises in its own caller only
(the group is then stored again one reading per transaction); a failed commit (the database away,
locked, full) raises in every caller of the group, none of whose readings is then stored.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Generic, TypeVar

from sqlalchemy.orm import Session

from station.ingest.destination import is_unreachable, store_audited_many
from station.ingest.schema import Reading
from station.ingest.store import StoreResult

__all__ = ["MAX_GROUP", "GroupCommit"]

#: Most readings one commit carries (bounds the transaction and the first caller's wait).
MAX_GROUP = 64

T = TypeVar("T")


@dataclass(eq=False)
class _Pending(Generic[T]):
    """One caller's reading and, once its group is written, what became of it.

    *wake* is set when the caller has its outcome (*done*) or is to write the next group."""

    reading: Reading
    actor_id: int | None
    done: bool = False
    value: tuple[T, bool] | None = None
    error: BaseException | None = field(default=None, repr=False)
    wake: threading.Event = field(default_factory=threading.Event, repr=False)


class GroupCommit(Generic[T]):
    """Store concurrent callers' readings in shared transactions (see the module docstring).

    Thread-safe; one per database (the service keeps one on ``app.state``). *action* is the audit
    action of each stored reading; *max_batch* the most readings one transaction carries. The
    instrument ids seen are remembered (instrument rows are never deleted), so a known instrument
    costs no upsert. A writer hands over to the first caller still queued once its group is written:
    only that caller and the group's callers wake, not every waiting one.
    """

    def __init__(self, action: str, *, max_batch: int = MAX_GROUP) -> None:
        if max_batch < 1:
            raise ValueError(f"max_batch: expected ≥ 1, got {max_batch}")
        self.action = action
        self.max_batch = max_batch
        self._lock = threading.Lock()
        self._queue: deque[_Pending[T]] = deque()
        self._writing = False
        self._instrument_ids: dict[str, int] = {}

    @property
    def queued(self) -> int:
        """Readings waiting for a group (not yet taken by a writer)."""
        with self._lock:
            return len(self._queue)

    def store(
        self,
        session: Session,
        reading: Reading,
        *,
        actor_id: int | None,
        answer: Callable[[Session, Reading, StoreResult], T],
    ) -> tuple[T, bool]:
        """Store *reading* once (in a group with whatever else is queued); ``(answer, created)``.

        *session* is the caller's; it writes the group when this caller becomes the writer and must
        have no transaction of its own open. *answer* turns the stored row into the caller's reply
        inside the transaction (called in the writer's thread). Raises what storing this reading
        raised, or what the group's commit raised.
        """
        mine: _Pending[T] = _Pending(reading, actor_id)
        with self._lock:
            self._queue.append(mine)
            writer = not self._writing
            self._writing = True
        if not writer:
            mine.wake.wait()  # done by another writer, or handed the next group (first in the queue)
        if not mine.done:
            with self._lock:
                group = [self._queue.popleft() for _ in range(min(len(self._queue), self.max_batch))]
            try:
                self._write(session, group, answer)
            finally:
                with self._lock:
                    for pending in group:
                        pending.done = True
                    successor = self._queue[0] if self._queue else None
                    self._writing = successor is not None
                for pending in group:
                    pending.wake.set()
                if successor is not None:
                    successor.wake.set()
        if mine.error is not None:
            raise mine.error
        assert mine.value is not None  # noqa: S101 - a finished entry holds a value or an error
        return mine.value

    def _write(
        self, session: Session, group: list[_Pending[T]], answer: Callable[[Session, Reading, StoreResult], T]
    ) -> None:
        """Store *group* in one transaction on *session* with one commit.

        The readings go to :func:`~station.ingest.destination.store_audited_many` together (on
        PostgreSQL a few round trips for the whole group, not several per reading). No savepoints:
        when the database refuses a reading, the transaction is rolled back and each reading of the
        group is stored again in a transaction of its own, so the refusal reaches only its caller.
        Instrument ids learnt in the group are remembered only once it is committed (a rolled-back
        upsert must not leave the id of a row that was never stored).
        """
        learnt = dict(self._instrument_ids)
        refused: Exception | None = None
        try:
            try:
                results = store_audited_many(
                    session,
                    [(pending.reading, pending.actor_id) for pending in group],
                    action=self.action,
                    instrument_cache=learnt,
                )
                for pending, result in zip(group, results, strict=True):
                    pending.value = (answer(session, pending.reading, result), result.created)
            except Exception as exc:
                if is_unreachable(exc):
                    raise  # the database, not a reading: the whole group fails below
                refused = exc
            if refused is None:
                session.commit()
            else:
                session.rollback()
        except BaseException as exc:
            try:
                session.rollback()
            finally:
                for pending in group:
                    pending.value = None
                    pending.error = exc
            if not isinstance(exc, Exception):
                raise
            return
        if refused is None:
            self._instrument_ids.update(learnt)
            return
        for pending in group:
            pending.value = None  # rolled back
        if len(group) == 1:
            group[0].error = refused
            return
        for pending in group:
            self._write(session, [pending], answer)
