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

import asyncio
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

    A thread caller (:meth:`GroupCommit.store`) waits on *wake*, set when it has its outcome (*done*)
    or is to write the next group; a coroutine caller (:meth:`GroupCommit.store_async`) awaits
    *future* (resolved on its *loop*), and its group is written by a worker thread with a session
    from *sessions*."""

    reading: Reading
    actor_id: int | None
    answer: Callable[[Session, Reading, StoreResult], T]
    done: bool = False
    value: tuple[T, bool] | None = None
    error: BaseException | None = field(default=None, repr=False)
    wake: threading.Event | None = field(default=None, repr=False)
    future: asyncio.Future[None] | None = field(default=None, repr=False)
    loop: asyncio.AbstractEventLoop | None = field(default=None, repr=False)
    sessions: Callable[[], Session] | None = field(default=None, repr=False)

    def outcome(self) -> tuple[T, bool]:
        """What became of the reading: ``(answer, created)``, or the error raised."""
        if self.error is not None:
            raise self.error
        assert self.value is not None  # noqa: S101 - a finished entry holds a value or an error
        return self.value


def _resolve(group: list[_Pending[T]]) -> None:
    """Wake the coroutine callers of *group* (on their loop's thread)."""
    for pending in group:
        if pending.future is not None and not pending.future.done():
            pending.future.set_result(None)


class GroupCommit(Generic[T]):
    """Store concurrent callers' readings in shared transactions (see the module docstring).

    Thread-safe; one per database (the service keeps one on ``app.state``). *action* is the audit
    action of each stored reading; *max_batch* the most readings one transaction carries. The
    instrument ids seen are remembered (instrument rows are never deleted), so a known instrument
    costs no upsert. Once a group is written the writer hands the next one to the first caller still
    queued: a thread caller writes it itself; for a coroutine caller a worker thread goes on writing
    groups while coroutine callers are first in the queue. Only the group's callers and the next
    writer wake, and a coroutine caller costs its event loop one wake-up per group, not a thread each.
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

    def _enqueue(self, pending: _Pending[T]) -> bool:
        """Queue *pending*; whether its caller is to write (no write in progress)."""
        with self._lock:
            self._queue.append(pending)
            writer = not self._writing
            self._writing = True
        return writer

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
        mine: _Pending[T] = _Pending(reading, actor_id, answer, wake=threading.Event())
        if not self._enqueue(mine):
            assert mine.wake is not None  # noqa: S101 - made just above
            mine.wake.wait()  # done by another writer, or handed the next group (first in the queue)
        if not mine.done:
            successor = self._write_next(session)
            if successor is not None:  # a coroutine caller is next: a worker thread of its loop writes
                loop = successor.loop
                assert loop is not None  # noqa: S101 - a coroutine caller's entry holds its loop
                loop.call_soon_threadsafe(self._start_drain, successor)
        return mine.outcome()

    async def store_async(
        self,
        sessions: Callable[[], Session],
        reading: Reading,
        *,
        actor_id: int | None,
        answer: Callable[[Session, Reading, StoreResult], T],
    ) -> tuple[T, bool]:
        """:meth:`store` for a coroutine: the same outcome, written by a worker thread of the running
        loop with a session from *sessions* (closed after each group); the caller waits without a
        thread of its own. The reading is stored even if the caller is cancelled meanwhile."""
        loop = asyncio.get_running_loop()
        mine: _Pending[T] = _Pending(
            reading, actor_id, answer, future=loop.create_future(), loop=loop, sessions=sessions
        )
        if self._enqueue(mine):
            self._start_drain(mine)
        assert mine.future is not None  # noqa: S101 - made just above
        await asyncio.shield(mine.future)
        return mine.outcome()

    def _start_drain(self, first: _Pending[T]) -> None:
        """On *first*'s loop: write groups in a worker thread, starting with *first*'s."""
        assert first.loop is not None  # noqa: S101 - a coroutine caller's entry holds its loop
        first.loop.run_in_executor(None, self._drain, first)

    def _drain(self, first: _Pending[T]) -> None:
        """Write groups while a coroutine caller is first in the queue (*first* to begin with)."""
        successor: _Pending[T] | None = first
        while successor is not None:
            assert successor.sessions is not None  # noqa: S101 - a coroutine caller's entry
            with successor.sessions() as session:
                successor = self._write_next(session)

    def _write_next(self, session: Session) -> _Pending[T] | None:
        """Write the group at the head of the queue on *session*, wake its callers and hand over: a
        thread caller next is woken to write; a coroutine caller next is returned (its writer is
        the caller's to start or be)."""
        with self._lock:
            group = [self._queue.popleft() for _ in range(min(len(self._queue), self.max_batch))]
        try:
            self._write(session, group)
        finally:
            with self._lock:
                for pending in group:
                    pending.done = True
                successor = self._queue[0] if self._queue else None
                self._writing = successor is not None
            loops: dict[asyncio.AbstractEventLoop, list[_Pending[T]]] = {}
            for pending in group:
                if pending.wake is not None:
                    pending.wake.set()
                elif pending.loop is not None:
                    loops.setdefault(pending.loop, []).append(pending)
            for loop, waiting in loops.items():
                loop.call_soon_threadsafe(_resolve, waiting)
        if successor is not None and successor.wake is not None:
            successor.wake.set()
            return None
        return successor

    def _write(self, session: Session, group: list[_Pending[T]]) -> None:
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
                    pending.value = (pending.answer(session, pending.reading, result), result.created)
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
            self._write(session, [pending])
