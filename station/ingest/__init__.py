"""Loss-free, exactly-once ingest of instrument readings into the measurement database.

:class:`Reading` is what a station sends; :func:`store_reading` writes it once inside a transaction;
:class:`Ingestor` adds the on-disk :class:`Outbox` used while the database is unreachable.
"""

from station.ingest.errors import ClientIdConflictError, IngestError, ReferenceNotFoundError
from station.ingest.ingestor import Ingestor, Receipt, is_unreachable
from station.ingest.outbox import Outbox, OutboxEntry
from station.ingest.schema import CalibrationRef, InstrumentRef, Reading
from station.ingest.store import StoreResult, store_reading

__all__ = [
    "CalibrationRef",
    "ClientIdConflictError",
    "IngestError",
    "Ingestor",
    "InstrumentRef",
    "Outbox",
    "OutboxEntry",
    "Reading",
    "Receipt",
    "ReferenceNotFoundError",
    "StoreResult",
    "is_unreachable",
    "store_reading",
]
