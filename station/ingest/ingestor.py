"""The one ingest loop: store once, or queue on disk and replay in order.

``submit`` first drains the outbox (so readings reach the destination in the order they were taken),
then stores the new reading. When the destination is unreachable the reading goes to the outbox and
``submit`` returns ``"queued"``: the reading is on disk either way when ``submit`` returns, so a
process killed at any instant loses nothing it acknowledged. A crash between the destination's commit
and the outbox acknowledgement replays a reading already stored; the client id makes that a no-op.

With ``queue_first`` (the viewer) every reading is written to the outbox *before* it is sent, so a
reading taken is on disk even if the process dies while sending, and a refused reading gets a
``"refused"`` receipt (it moves to the dead-letter table) instead of an exception.

The service's measure route, the viewer's scans and ``station measure --store`` all store through this
class; the destination is a :class:`~station.ingest.destination.DatabaseDestination` or, for the
viewer in service mode, an HTTP destination that posts to the service.
"""

from __future__ import annotations

import logging
import threading
import uuid
from collections.abc import Callable
from pathlib import Path

from sqlalchemy import Engine

from station.closing import Closing
from station.ingest.destination import DatabaseDestination, Destination, Receipt, is_unreachable
from station.ingest.errors import IngestError
from station.ingest.outbox import Outbox
from station.ingest.schema import Reading

log = logging.getLogger(__name__)

__all__ = ["Ingestor", "Receipt", "is_unreachable"]


class Ingestor(Closing):
    """Store readings into *destination* (a destination, an engine or a database URL), with an outbox at *outbox_path*.

    Thread-safe: one lock serialises submits and replays, so readings keep their order.
    """

    def __init__(
        self,
        destination: Destination | Engine | str,
        outbox_path: Path | str,
        *,
        queue_first: bool = False,
        decode: Callable[[str], Reading] = Reading.model_validate_json,
    ) -> None:
        self._own_destination = isinstance(destination, str)
        if isinstance(destination, (Engine, str)):
            destination = DatabaseDestination(destination)
        self.destination: Destination = destination
        self.outbox = Outbox(outbox_path)
        self.queue_first = queue_first
        self._decode = decode  # outbox body → reading (a front may accept an older body layout)
        self._lock = threading.RLock()

    @property
    def engine(self) -> Engine:
        """The database engine (a :class:`DatabaseDestination` only)."""
        if not isinstance(self.destination, DatabaseDestination):
            raise TypeError(f"{self.destination.where} is not a database")
        return self.destination.engine

    def close(self) -> None:
        """Close the outbox (and the destination when this object created it from a URL)."""
        self.outbox.close()
        if self._own_destination:
            self.destination.close()

    def drain(self) -> list[Receipt]:
        """Store queued readings oldest first; stop at the first unreachable error. One receipt per entry tried.

        A reading the destination refuses moves to the dead-letter table (receipt ``"refused"`` with
        the error); the one that met an unreachable destination stays queued (receipt ``"queued"``).
        """
        receipts: list[Receipt] = []
        with self._lock:
            for entry in self.outbox.entries():
                try:
                    reading = self._decode(entry.body)
                    receipt = self.destination.store(reading, replayed=True)
                except Exception as exc:
                    if is_unreachable(exc):
                        log.info(
                            "%s unreachable; %d readings stay queued",
                            self.destination.where,
                            len(self.outbox),
                        )
                        receipts.append(Receipt(entry.client_id, "queued", None, str(exc)))
                        return receipts
                    if not isinstance(exc, (IngestError, ValueError)):
                        raise
                    log.error("outbox entry %s refused: %s", entry.client_id, exc)
                    self.outbox.bury(entry, str(exc))
                    receipts.append(Receipt(entry.client_id, "refused", None, str(exc)))
                else:
                    self.outbox.remove(entry.seq)
                    receipts.append(receipt)
        return receipts

    def replay(self) -> int:
        """Store queued readings oldest first; stop at the first unreachable error. Returns how many left the queue."""
        return sum(1 for r in self.drain() if r.status != "queued")

    def find(self, client_id: uuid.UUID) -> Receipt | None:
        """What became of *client_id* so far: ``"queued"`` in the outbox, ``"duplicate"`` (stored), or ``None``.

        Raises what the destination raises when it is unreachable and the reading is not queued.
        """
        cid = str(client_id)
        with self._lock:
            if any(e.client_id == cid for e in self.outbox.entries()):
                return Receipt(cid, "queued", None, "kept in the outbox")
            stored = self.destination.find(client_id)
        return None if stored is None else Receipt(cid, "duplicate", stored)

    def find_queued(self, client_id: uuid.UUID) -> Receipt | None:
        """``"queued"`` when *client_id* waits in the outbox, else ``None`` (the destination is not asked)."""
        cid = str(client_id)
        with self._lock:
            if any(e.client_id == cid for e in self.outbox.entries()):
                return Receipt(cid, "queued", None, "kept in the outbox")
        return None

    def enqueue(self, reading: Reading, reason: str = "destination away") -> Receipt:
        """Queue *reading* without trying the destination (known to be away); durable on return."""
        cid = str(reading.client_id)
        with self._lock:
            self.outbox.put(cid, reading.canonical_json())
        return Receipt(cid, "queued", None, reason)

    def submit(self, reading: Reading, *, actor_id: int | None = None) -> Receipt:
        """Store *reading* (after draining the queue), or queue it when the destination is away.

        *actor_id* (the acting user) is recorded when the reading is stored now; a reading replayed
        from the outbox is recorded without one. Without ``queue_first`` a refusal raises.
        """
        cid = str(reading.client_id)
        with self._lock:
            if self.queue_first:
                self.outbox.put(cid, reading.canonical_json())
                got = {r.client_id: r for r in self.drain()}
                return got.get(cid) or Receipt(cid, "queued", None, "readings ahead of it are still queued")
            if len(self.outbox):
                self.replay()
            if len(self.outbox):
                self.outbox.put(cid, reading.canonical_json())
                return Receipt(cid, "queued", None, "readings ahead of it are still queued")
            try:
                return self.destination.store(reading, actor_id=actor_id)
            except Exception as exc:
                if not is_unreachable(exc):
                    raise
                log.info(
                    "%s unreachable (%s); reading %s queued", self.destination.where, type(exc).__name__, cid
                )
                self.outbox.put(cid, reading.canonical_json())
                return Receipt(cid, "queued", None, str(exc))
