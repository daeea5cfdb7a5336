"""Loss-free, exactly-once ingest of instrument readings into the measurement database.

:class:`Reading` is what a station sends; :func:`store_reading` writes it once inside a transaction;
:class:`Ingestor` adds the on-disk :class:`Outbox` used while the destination is unreachable;
:func:`record_from_reading` turns an instrument reading into a :class:`Reading` (the one conversion);
:class:`GlossRecord` is a gloss meter reading, stored by :func:`store_gloss` and joined to a colour
measurement by :func:`pair_gloss`. Vendor measurement files (CxF3, CGATS.17, MA-T12 workbooks, the CSV
template) and the watch folder live in :mod:`station.ingest.formats`; their readings go through the
same :class:`Ingestor`.
"""

from station.ingest.destination import (
    DatabaseDestination,
    Destination,
    Receipt,
    is_unreachable,
    store_audited,
)
from station.ingest.errors import (
    ClientIdConflictError,
    DestinationUnreachableError,
    IngestError,
    ReadingRefusedError,
    ReferenceNotFoundError,
)
from station.ingest.gloss import (
    PAIR_WINDOW,
    GlossRecord,
    GlossRow,
    gloss_of_measurements,
    gloss_record_from_reading,
    pair_gloss,
    store_gloss,
)
from station.ingest.ingestor import Ingestor
from station.ingest.outbox import Outbox, OutboxEntry
from station.ingest.records import calibration_client_id, operator_name, record_from_reading
from station.ingest.schema import CalibrationRef, InstrumentRef, PanelRef, Reading, TextureValue
from station.ingest.store import StoreResult, store_reading

__all__ = [
    "PAIR_WINDOW",
    "CalibrationRef",
    "ClientIdConflictError",
    "DatabaseDestination",
    "Destination",
    "DestinationUnreachableError",
    "GlossRecord",
    "GlossRow",
    "IngestError",
    "Ingestor",
    "InstrumentRef",
    "Outbox",
    "OutboxEntry",
    "PanelRef",
    "Reading",
    "ReadingRefusedError",
    "Receipt",
    "ReferenceNotFoundError",
    "StoreResult",
    "TextureValue",
    "calibration_client_id",
    "gloss_of_measurements",
    "gloss_record_from_reading",
    "is_unreachable",
    "operator_name",
    "pair_gloss",
    "record_from_reading",
    "store_audited",
    "store_gloss",
    "store_reading",
]
