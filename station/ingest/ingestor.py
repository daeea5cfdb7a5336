"""The station-side ingest loop: store once, or queue on disk and replay in order.

``submit`` first drains the outbox (so readings reach the database in the order they were taken),
then stores the new reading. When the database is unreachable the reading goes to the outbox and
``submit`` returns ``"queued"``: the reading is on disk either way when ``submit`` returns, so a
process killed at any instant loses nothing it acknowledged. A crash between the database commit and
the outbox acknowledgement replays a reading already stored; the client id makes that a no-op.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from sqlalchemy import Engine, insert
from sqlalchemy.exc import DBAPIError, DisconnectionError, InterfaceError, OperationalError
from sqlalchemy.orm import Session, sessionmaker

from db.base import utcnow
from db.engine import make_engine, make_sessionmaker
from db.models import AuditEvent
from station.ingest.errors import IngestError
from station.ingest.outbox import Outbox
from station.ingest.schema import Reading
from station.ingest.store import store_reading

log = logging.getLogger(__name__)

_AUDIT_INSERT = insert(AuditEvent.__table__)
_UNREACHABLE = (OperationalError, InterfaceError, DisconnectionError, ConnectionError, TimeoutError)


def is_unreachable(exc: BaseException) -> bool:
    """Whether *exc* means "the database is away" (retry later) rather than "the reading is bad"."""
    if isinstance(exc, DBAPIError) and exc.connection_invalidated:
        return True
    return isinstance(exc, _UNREACHABLE)


@dataclass(frozen=True)
class Receipt:
    """What happened to a submitted reading: stored now, already stored, or queued on disk."""

    client_id: str
    status: Literal["stored", "duplicate", "queued"]
    measurement_id: int | None = None


class Ingestor:
    """Store readings into the database behind *engine*, with an on-disk outbox at *outbox_path*."""

    def __init__(self, engine: Engine | str, outbox_path: Path | str) -> None:
        self._own_engine = isinstance(engine, str)
        # no pre-ping: a dead pooled connection fails one submit, which then goes to the outbox and is
        # replayed on the next one (the pool drops invalidated connections), saving a round trip per reading
        self.engine = make_engine(engine, pool_pre_ping=False) if isinstance(engine, str) else engine
        self._sessions: sessionmaker[Session] = make_sessionmaker(self.engine)
        self.outbox = Outbox(outbox_path)
        self._instrument_ids: dict[str, int] = {}

    def close(self) -> None:
        """Close the outbox (and the engine when this object created it)."""
        self.outbox.close()
        if self._own_engine:
            self.engine.dispose()

    def __enter__(self) -> Ingestor:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def _store(self, reading: Reading) -> Receipt:
        with self._sessions.begin() as session:
            result = store_reading(session, reading, instrument_cache=self._instrument_ids)
            if result.created:  # the audit row commits with the reading (station account: no user)
                session.execute(
                    _AUDIT_INSERT,
                    {
                        "at": utcnow(),
                        "actor_id": None,
                        "action": "measurement.ingest",
                        "entity": "measurement",
                        "entity_id": str(result.measurement_id),
                        "detail": {"client_id": str(reading.client_id), "operator": reading.operator},
                    },
                )
        status: Literal["stored", "duplicate"] = "stored" if result.created else "duplicate"
        return Receipt(str(reading.client_id), status, result.measurement_id)

    def replay(self) -> int:
        """Store queued readings oldest first; stop at the first unreachable error. Returns how many left the queue."""
        done = 0
        for entry in self.outbox.entries():
            try:
                reading = Reading.model_validate_json(entry.body)
                self._store(reading)
            except Exception as exc:
                if is_unreachable(exc):
                    log.info("database unreachable; %d readings stay queued", len(self.outbox))
                    return done
                if not isinstance(exc, (IngestError, ValueError)):
                    raise
                log.error("outbox entry %s refused: %s", entry.client_id, exc)
                self.outbox.bury(entry, str(exc))
            else:
                self.outbox.remove(entry.seq)
            done += 1
        return done

    def submit(self, reading: Reading) -> Receipt:
        """Store *reading* (after draining the queue), or queue it when the database is away."""
        if len(self.outbox):
            self.replay()
        if len(self.outbox):
            self.outbox.put(str(reading.client_id), reading.canonical_json())
            return Receipt(str(reading.client_id), "queued")
        try:
            return self._store(reading)
        except Exception as exc:
            if not is_unreachable(exc):
                raise
            log.info("database unreachable (%s); reading %s queued", type(exc).__name__, reading.client_id)
            self.outbox.put(str(reading.client_id), reading.canonical_json())
            return Receipt(str(reading.client_id), "queued")
