"""Where an :class:`~station.ingest.Ingestor` stores readings: the measurement database, or any other sink.

A destination stores one reading exactly once by its client id and says what happened
(:class:`Receipt`). It raises :class:`DestinationUnreachableError` (or a driver error that
:func:`is_unreachable` recognises) when it is away, so the reading stays queued, and an
:class:`IngestError` or ``ValueError`` when it refuses the reading, so the reading moves to the
outbox's dead-letter table.
"""

from __future__ import annotations

import threading
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

from sqlalchemy import Engine, select
from sqlalchemy.exc import DBAPIError, DisconnectionError, InterfaceError, OperationalError
from sqlalchemy.orm import Session, sessionmaker

from db.chain import append_audit
from db.engine import make_engine, make_sessionmaker
from db.models import GlossReading, Measurement
from station.ingest.errors import DestinationUnreachableError
from station.ingest.schema import Reading
from station.ingest.store import StoreResult, store_reading, store_readings

__all__ = [
    "DatabaseDestination",
    "Destination",
    "Receipt",
    "Status",
    "is_unreachable",
    "store_audited",
    "store_audited_many",
]

Status = Literal["stored", "duplicate", "queued", "refused"]
_UNREACHABLE = (
    DestinationUnreachableError,
    OperationalError,
    InterfaceError,
    DisconnectionError,
    ConnectionError,
    TimeoutError,
)


def is_unreachable(exc: BaseException) -> bool:
    """Whether *exc* means "the destination is away" (retry later) rather than "the reading is bad"."""
    if isinstance(exc, DBAPIError) and exc.connection_invalidated:
        return True
    return isinstance(exc, _UNREACHABLE)


@dataclass(frozen=True)
class Receipt:
    """What happened to a reading: stored now, already stored, queued on disk, or refused (dead letter).

    *message* says why a reading is queued or refused (empty when stored).
    """

    client_id: str
    status: Status
    measurement_id: int | None = None
    message: str = ""


class Destination(Protocol):
    """Stores one reading exactly once by client id."""

    @property
    def where(self) -> str:
        """Plain name of the destination, for messages."""
        ...

    def store(self, reading: Reading, *, actor_id: int | None = None, replayed: bool = False) -> Receipt:
        """Store *reading* once (``stored`` or ``duplicate``); raise when away or refused."""
        ...

    def find(self, client_id: uuid.UUID) -> int | None:
        """The stored measurement id of *client_id*, or ``None``."""
        ...

    def close(self) -> None:
        """Release connections."""
        ...


def store_audited(
    session: Session,
    reading: Reading,
    *,
    actor_id: int | None,
    action: str,
    source: str | None = None,
    instrument_cache: dict[str, int] | None = None,
) -> StoreResult:
    """:func:`store_reading` plus, when the row is new, its audit event, in the caller's transaction.

    The audit detail holds the client id, the operator and *source* (when given); *actor_id* is the
    acting user (``None``: the station account). Both rows join their hash chains (``db.chain``).
    """
    result = store_reading(session, reading, created_by_id=actor_id, instrument_cache=instrument_cache)
    if result.created:
        detail: dict[str, str] = {"client_id": str(reading.client_id), "operator": reading.operator}
        if source is not None:
            detail["source"] = source
        append_audit(
            session,
            {
                "actor_id": actor_id,
                "action": action,
                "entity": "measurement",
                "entity_id": str(result.measurement_id),
                "detail": detail,
            },
        )
    return result


def store_audited_many(
    session: Session,
    readings: Sequence[tuple[Reading, int | None]],
    *,
    action: str,
    instrument_cache: dict[str, int] | None = None,
) -> list[StoreResult]:
    """:func:`store_audited` of each ``(reading, actor_id)`` in turn, in the caller's transaction: the
    same rows, audit events and outcomes, with fewer round trips on PostgreSQL (the readings and their
    events through :func:`~station.ingest.store.store_readings`). Raises as :func:`store_audited` does
    for a refused reading.
    """

    def event(measurement_id: int, reading: Reading, actor_id: int | None) -> dict[str, Any]:
        return {
            "actor_id": actor_id,
            "action": action,
            "entity": "measurement",
            "entity_id": str(measurement_id),
            "detail": {"client_id": str(reading.client_id), "operator": reading.operator},
        }

    return store_readings(session, readings, instrument_cache=instrument_cache, audit=event)


class DatabaseDestination:
    """The measurement database at *engine* (an engine, or a URL opened on first use).

    With *migrate* the database is upgraded to the Alembic head when first opened; a database that
    cannot be opened or migrated (locked, unwritable, newer) is unreachable, so readings stay queued.
    Each stored reading commits with one audit row: *action* (or *replay_action* for a reading replayed
    from the outbox), the acting user's id when there is one, the client id, the operator and *source*.
    """

    def __init__(
        self,
        engine: Engine | str,
        *,
        migrate: bool = False,
        action: str = "measurement.ingest",
        replay_action: str | None = None,
        source: str | None = None,
    ) -> None:
        self._owns_engine = isinstance(engine, str)
        self._url = engine if isinstance(engine, str) else engine.url.render_as_string(hide_password=True)
        self._engine: Engine | None = None if isinstance(engine, str) else engine
        self._sessions: sessionmaker[Session] | None = (
            None if isinstance(engine, str) else make_sessionmaker(engine)
        )
        self._migrate = migrate
        self._lock = threading.Lock()
        self._instrument_ids: dict[str, int] = {}
        self.action = action
        self.replay_action = replay_action or action
        self.source = source

    @property
    def url(self) -> str:
        """The database URL (password hidden when given an engine)."""
        return self._url

    @property
    def where(self) -> str:
        return f"database {self.url}"

    @property
    def engine(self) -> Engine:
        """The engine (opened, and migrated when asked, on first use)."""
        return self.open()[0]

    def open(self) -> tuple[Engine, sessionmaker[Session]]:
        """Open (and migrate) the database now; :class:`DestinationUnreachableError` when it cannot be."""
        with self._lock:
            if self._engine is None or self._sessions is None:
                if self._migrate:
                    from db.migrate import ensure_at_head

                    try:
                        ensure_at_head(self._url)
                    except Exception as exc:  # locked, unwritable or newer: keep the reading, say why
                        raise DestinationUnreachableError(f"{type(exc).__name__}: {exc}") from exc
                # no pre-ping: a dead pooled connection fails one store, which then goes to the outbox
                # and is replayed on the next one (the pool drops invalidated connections)
                self._engine = make_engine(self._url, pool_pre_ping=False)
                self._sessions = make_sessionmaker(self._engine)
            return self._engine, self._sessions

    def sessions(self) -> sessionmaker[Session]:
        """The session factory bound to :attr:`engine`."""
        return self.open()[1]

    def store(self, reading: Reading, *, actor_id: int | None = None, replayed: bool = False) -> Receipt:
        """Store *reading* and its audit row in one transaction (``ON CONFLICT (client_id) DO NOTHING``).

        An instrument id learnt here is remembered only once the transaction is committed: a refused
        reading rolls its instrument row back too, and a remembered id of it would name no row (or,
        reused, another instrument).
        """
        seen = dict(self._instrument_ids)
        with self.sessions().begin() as session:
            result = store_audited(
                session,
                reading,
                actor_id=actor_id,
                action=self.replay_action if replayed else self.action,
                source=self.source,
                instrument_cache=seen,
            )
        self._instrument_ids.update(seen)
        status: Status = "stored" if result.created else "duplicate"
        return Receipt(str(reading.client_id), status, result.measurement_id)

    def find(self, client_id: uuid.UUID) -> int | None:
        """The measurement stored under *client_id*, or ``None``."""
        return self._stored_id(Measurement, client_id)

    def find_gloss(self, client_id: uuid.UUID) -> int | None:
        """The gloss reading stored under *client_id*, or ``None``."""
        return self._stored_id(GlossReading, client_id)

    def _stored_id(self, table: type[Measurement | GlossReading], client_id: uuid.UUID) -> int | None:
        with self.sessions()() as session:
            found = session.scalar(select(table.id).where(table.client_id == client_id))
        return None if found is None else int(found)

    def close(self) -> None:
        """Dispose of the engine when this object opened it from a URL."""
        with self._lock:
            if self._owns_engine and self._engine is not None:
                self._engine.dispose()
                self._engine = None
                self._sessions = None
