"""Store or queue: a scan's records go through the one writer (``station.ingest``), and a retry is
answered from what the first attempt left.

* The colour record goes through a :class:`station.ingest.Ingestor` (exactly once by client id; kept in
  the on-disk outbox while the destination is away, or at once with ``away``).
* The gloss record is stored by ``station.ingest.store_gloss`` (or the service's ``POST /qc/gloss``):
  a gloss-only reading on its panel, or, with a colour reading, naming the colour measurement once that
  is stored. Gloss records are not queued: while the destination is away a gloss-only reading raises
  (the fronts say so), and a paired one's receipt says ``not stored`` (its 60° value travels in the
  colour record all the same).
"""

from __future__ import annotations

import logging
import uuid
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Protocol

from station.scan.result import GlossReceipt, GlossStatus, ScanResult

if TYPE_CHECKING:
    from station.ingest import DatabaseDestination, GlossRecord, Ingestor, Reading, Receipt

__all__ = ["DatabaseTarget", "ScanTarget", "prior", "store"]

log = logging.getLogger(__name__)


class ScanTarget(Protocol):
    """Where a scan is stored: the ingest loop for colour records, the database (or service) for gloss ones."""

    @property
    def where(self) -> str:
        """Plain name of the store, for messages."""
        ...

    def submit(self, reading: Reading, *, actor_id: int | None = None) -> Receipt:
        """Store or queue a colour record (``station.ingest.Ingestor.submit``)."""
        ...

    def enqueue(self, reading: Reading, reason: str) -> Receipt:
        """Queue a colour record without trying the destination (known to be away)."""
        ...

    def submit_gloss(self, record: GlossRecord, *, actor_id: int | None = None) -> GlossReceipt:
        """Store a gloss record once (``stored`` or ``duplicate``); raise when away or refused."""
        ...


class DatabaseTarget:
    """A :class:`ScanTarget` over an :class:`~station.ingest.Ingestor` whose destination is a
    :class:`~station.ingest.DatabaseDestination`: colour through the ingestor, gloss straight into the
    same database. *on_unreachable* hears the error when :meth:`prior` finds the database away."""

    def __init__(
        self, ingestor: Ingestor, on_unreachable: Callable[[BaseException], None] | None = None
    ) -> None:
        self.ingestor = ingestor
        self._on_unreachable = on_unreachable

    @property
    def where(self) -> str:
        return self.ingestor.destination.where

    def submit(self, reading: Reading, *, actor_id: int | None = None) -> Receipt:
        return self.ingestor.submit(reading, actor_id=actor_id)

    def enqueue(self, reading: Reading, reason: str) -> Receipt:
        return self.ingestor.enqueue(reading, reason)

    def _database(self) -> DatabaseDestination:
        from station.ingest import DatabaseDestination

        destination = self.ingestor.destination
        if not isinstance(destination, DatabaseDestination):
            raise TypeError(f"{destination.where} is not a database")
        return destination

    def submit_gloss(self, record: GlossRecord, *, actor_id: int | None = None) -> GlossReceipt:
        from station.ingest import store_gloss

        with self._database().sessions().begin() as session:
            result = store_gloss(session, record, created_by_id=actor_id)
        status: GlossStatus = "stored" if result.created else "duplicate"
        return GlossReceipt(str(record.client_id), status, result.measurement_id)

    def find_gloss(self, client_id: uuid.UUID) -> int | None:
        """The gloss reading stored under *client_id*, or ``None``."""
        return self._database().find_gloss(client_id)

    def prior(self, client_id: uuid.UUID, *, away: bool = False) -> Receipt | GlossReceipt | None:
        """What an earlier attempt under *client_id* left: the colour reading stored (``duplicate``) or
        queued, or a gloss-only reading stored (``duplicate``); ``None`` when nothing.

        The outbox is replayed first. With *away* (or when the database proves away, told to
        *on_unreachable*) only the outbox is asked: a reading stored before the database went away is
        not seen then, and measured again its second body is refused on replay (same client id, other
        payload), so the stored one stays the only one.
        """
        from station.ingest import is_unreachable

        if not away:
            try:
                self.ingestor.replay()
                found = self.ingestor.find(client_id)
                if found is not None:
                    return found
                gloss_id = self.find_gloss(client_id)
                return None if gloss_id is None else GlossReceipt(str(client_id), "duplicate", gloss_id)
            except Exception as exc:
                if not is_unreachable(exc):
                    raise
                if self._on_unreachable is not None:
                    self._on_unreachable(exc)
        return self.ingestor.find_queued(client_id)


def prior(
    target: DatabaseTarget, client_id: uuid.UUID | None, *, away: bool = False
) -> Receipt | GlossReceipt | None:
    """:meth:`DatabaseTarget.prior` of *client_id*, or ``None`` without one (a fresh scan)."""
    return None if client_id is None else target.prior(client_id, away=away)


def store(
    result: ScanResult, target: ScanTarget, *, actor_id: int | None = None, away: str | None = None
) -> ScanResult:
    """Store *result*'s records in *target*; *result* with its receipts.

    Colour: submitted (or, with *away* — why the destination is known to be away — queued at once);
    once stored (or found stored) the gloss record joins it by ``measurement_id``; a gloss record that
    cannot be stored then is logged and its receipt says why (the colour record holds the 60° gloss).
    Gloss alone: stored through :meth:`ScanTarget.submit_gloss`; what it raises (database away, client id
    conflict, unknown panel) reaches the caller. A result without records is returned unchanged.
    """
    if result.record is None:
        if result.gloss_record is None:
            return result
        return replace(result, gloss_receipt=target.submit_gloss(result.gloss_record, actor_id=actor_id))
    if away is not None:
        receipt = target.enqueue(result.record, away)
    else:
        receipt = target.submit(result.record, actor_id=actor_id)
    stored = replace(result, receipt=receipt)
    if result.gloss_record is None:
        return stored
    gloss_cid = str(result.gloss_record.client_id)
    if receipt.measurement_id is None or receipt.status not in ("stored", "duplicate"):
        why = f"the colour reading is {receipt.status}; its 60° gloss travels in it"
        return replace(stored, gloss_receipt=GlossReceipt(gloss_cid, "not stored", None, why))
    joined = result.gloss_record.model_copy(update={"measurement_id": receipt.measurement_id})
    try:
        gloss_receipt = target.submit_gloss(joined, actor_id=actor_id)
    except Exception as exc:  # the colour reading (with its 60° gloss) is stored; say why the row is not
        log.warning("gloss reading of measurement %s not stored: %s", receipt.measurement_id, exc)
        gloss_receipt = GlossReceipt(gloss_cid, "not stored", None, f"{type(exc).__name__}: {exc}")
    return replace(stored, gloss_record=joined, gloss_receipt=gloss_receipt)
