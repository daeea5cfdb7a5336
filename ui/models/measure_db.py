"""Where the viewer stores its scans: the measurement database or a service, through ``station.ingest.Ingestor`` (Qt-free).

Each sink is a :class:`station.ingest.Ingestor` in ``queue_first`` mode: every reading is written to the
on-disk outbox *before* anything is sent, then the queue is drained oldest first into the sink's
destination. :class:`LocalSink`: a :class:`station.ingest.DatabaseDestination` on the workstation's
database (as ``station serve``: ``$CACAD_DATABASE_URL``, else SQLite in ``$CACAD_DATA_DIR`` or
``./var``; Alembic migrations applied on first use). :class:`ServiceSink`: ``POST /api/v1/measurements``
of a station service. The panel metadata (job, part, substrate, notes) travels in the record
(:class:`station.ingest.PanelRef`) and ``station.ingest.store_reading`` finds or creates the panel in
the reading's transaction, so a retried reading names the same panel and, keyed by its client id, is
stored once.

An unreachable database or service leaves the reading queued (retried on the next scan or on
"Retry queued"); a refusal (a bad reading, a client id conflict) moves it to the outbox's dead-letter
table with the error. Either way the reading stays on disk: nothing is lost.
"""

from __future__ import annotations

import datetime as dt
import json
import re
import uuid
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import InputError, StationError
from station.model import AspecularMeasurements, FaceFlopTravelGloss, FitResult, fit_fftg
from station.model.domain import DEFAULT_GLOSS_GU, ILLUMINATION_DEG
from ui.models.local_db import DatabaseLocation

if TYPE_CHECKING:  # SQLAlchemy, pydantic and the ORM load on first use (≈0.5 s off the viewer's start-up)
    from station.ingest import (
        DatabaseDestination,
        Destination,
        GlossRecord,
        Ingestor,
        Outbox,
        PanelRef,
        Reading,
        Receipt,
    )
    from station.scan import GlossReceipt, GlossStatus

RECENT_DEFAULT = 50
"""Stored measurements offered by default (newest first)."""
RECENT_MAX = 1000
"""Most stored measurements one request returns: the service's page-size bound (``limit`` ≤ 1000)."""
OUTBOX_FILE = "viewer-outbox.sqlite3"
SERVICE_OUTBOX_FILE = "viewer-service-outbox.sqlite3"
_TEXT = re.compile(r"^[^\x00-\x1f]+$")


def gloss_warning(labels: list[str]) -> str:
    """The visible line for designs whose gloss nobody measured, or ``""`` when every gloss was measured.

    *labels* name those designs (``#12``, ``B′``). Their gloss shows the thesis's default
    (:data:`station.model.domain.DEFAULT_GLOSS_GU`) and formulation keeps full gloss for them.
    """
    if not labels:
        return ""
    return (
        f"\nwarning: gloss not measured for {', '.join(labels)}: the default {DEFAULT_GLOSS_GU:g} GU is shown, "
        "and formulation adds no matting agent (measure or type a gloss target)"
    )


def recent_limit(limit: object) -> int:
    """*limit* as a row count, or :class:`InputError` naming ``limit`` and ``1 ≤ limit ≤ RECENT_MAX``.

    A ``bool`` is refused, not read as 0 or 1: a button's ``checked`` flag is not a row count.
    """
    if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= RECENT_MAX:
        raise InputError("limit", f"an integer number of measurements, 1 ≤ limit ≤ {RECENT_MAX}", limit)
    return limit


@dataclass(frozen=True)
class PanelInfo:
    """Panel metadata stored with a reading: job, car part (one of ``db.models.PARTS``), substrate, notes."""

    job: str
    part: str
    substrate: str = ""
    notes: str = ""

    def validated(self) -> PanelInfo:
        """The same metadata stripped, or :class:`InputError` naming the field (the database's limits)."""
        from db.models import PARTS

        p = PanelInfo(self.job.strip(), self.part.strip(), self.substrate.strip(), self.notes.strip())
        if not p.job or len(p.job) > 64 or not _TEXT.match(p.job):
            raise InputError("job", "1–64 printable characters", self.job)
        if p.part not in PARTS:
            raise InputError("part", " | ".join(PARTS), self.part)
        if len(p.substrate) > 64:
            raise InputError("substrate", "at most 64 characters", self.substrate)
        if len(p.notes) > 4000:
            raise InputError("notes", "at most 4000 characters", f"{len(p.notes)} characters")
        return p

    def ref(self) -> PanelRef:
        """The validated metadata as the ingest record carries it."""
        from station.ingest import PanelRef

        p = self.validated()
        return PanelRef(job=p.job, part=p.part, substrate=p.substrate, notes=p.notes)

    @property
    def label(self) -> str:
        """``job part`` for lists."""
        return f"{self.job} {self.part}"


@dataclass(frozen=True)
class StoredMeasurement:
    """A measurement read back from the database or the service (angles in degrees, Lab D65/10°)."""

    id: int
    label: str
    measured_at: str
    geometries_deg: tuple[float, ...]
    lab: np.ndarray
    gloss_gu: float | None

    def fit(self) -> FitResult | None:
        """FFTG fit of the positive aspecular angles (eqs 3.3.1–3.3.10), or ``None`` with fewer than 3.

        The result keeps the fit's warnings (a gloss not measured among them: its design then has
        ``gloss_measured`` False, so formulation adds no matting agent for it).
        """
        keep = sorted((a, i) for i, a in enumerate(self.geometries_deg) if a > 0)
        if len(keep) < 3:
            return None
        angles = tuple(a for a, _ in keep)
        lab = self.lab[[i for _, i in keep]]
        try:
            return fit_fftg(AspecularMeasurements(angles, lab, self.gloss_gu))
        except InputError:
            return None

    def design(self) -> FaceFlopTravelGloss | None:
        """The design of :meth:`fit`, or ``None`` when there is none."""
        result = self.fit()
        return None if result is None else result.design


def _decode_entry(body: str) -> Reading:
    """An outbox body: a record, or the earlier viewer layout ``{"panel": {...}, "reading": {...}}``
    (queued by a viewer of the previous release), whose panel metadata moves into the record."""
    from station.ingest import Reading

    doc = json.loads(body)
    if isinstance(doc, dict) and set(doc) == {"panel", "reading"}:
        return Reading.model_validate({**doc["reading"], "panel_id": None, "panel": doc["panel"]})
    return Reading.model_validate(doc)


class MeasurementSink:
    """An :class:`~station.ingest.Ingestor` (outbox first) over a destination; subclasses name the destination.

    Nothing is opened or created before the first scan, retry or :meth:`pending` of an existing outbox.
    """

    default_outbox = OUTBOX_FILE

    def __init__(self, outbox_path: Path | str | None = None) -> None:
        self._outbox_path = Path(outbox_path) if outbox_path is not None else None
        self._ingestor: Ingestor | None = None

    @property
    def where(self) -> str:
        """Plain name of the store (for messages)."""
        return ""

    @property
    def outbox_path(self) -> Path:
        """The outbox file (default: in :func:`db.engine.data_dir`)."""
        if self._outbox_path is None:
            from db.engine import data_dir

            self._outbox_path = data_dir() / self.default_outbox
        return self._outbox_path

    def _destination(self) -> Destination:
        raise NotImplementedError

    @property
    def ingestor(self) -> Ingestor:
        """The ingest loop (opened on first use)."""
        if self._ingestor is None:
            from station.ingest import Ingestor

            self._ingestor = Ingestor(
                self._destination(), self.outbox_path, queue_first=True, decode=_decode_entry
            )
        return self._ingestor

    @property
    def outbox(self) -> Outbox:
        """The on-disk queue (opened on first use)."""
        return self.ingestor.outbox

    def submit(self, panel: PanelInfo, reading: Reading) -> Receipt:
        """Queue *reading* with *panel*'s metadata on disk, then drain the queue; the receipt of *reading*. Blocking."""
        record = reading.model_copy(update={"panel": panel.ref(), "panel_id": None})
        return self._receipt(self.ingestor.submit(record))

    def submit_gloss(self, panel: PanelInfo, record: GlossRecord) -> GlossReceipt:
        """Store a gloss record once, not queued: a gloss-only one on *panel*, a paired one on the panel of
        the measurement it names. Raises when the store is away or refuses it. Blocking."""
        if record.measurement_id is None:
            record = record.model_copy(update={"panel": panel.ref(), "panel_id": None})
        return self._submit_gloss(record)

    def _submit_gloss(self, record: GlossRecord) -> GlossReceipt:
        raise NotImplementedError

    def flush(self) -> dict[str, Receipt]:
        """Send queued readings oldest first; stop at the first "unreachable". Receipts by client id."""
        return {r.client_id: self._receipt(r) for r in self.ingestor.drain()}

    def _receipt(self, r: Receipt) -> Receipt:
        if r.status == "queued":
            message = (
                f"{self.where} unreachable{': ' + r.message if r.message else ''} — the reading is kept in "
                f"{self.outbox_path} ({len(self.outbox)} queued) and sent on the next scan or retry"
            )
        elif r.status == "refused":
            message = (
                f"{self.where} refused the reading: {r.message} "
                f"(kept in the dead-letter table of {self.outbox_path})"
            )
        else:
            message = ""
        return replace(r, message=message)

    def prepare(self) -> None:
        """Open the store on the calling (GUI) thread before a worker sends to it; no-op by default."""

    def pending(self) -> int:
        """Readings waiting in the outbox."""
        return len(self.outbox) if self._ingestor is not None or self.outbox_path.exists() else 0

    def recent(self, limit: int = RECENT_DEFAULT) -> list[StoredMeasurement]:
        """The newest *limit* stored measurements (:func:`recent_limit` checks it; raises
        :class:`StationError` with a plain message)."""
        raise NotImplementedError

    def close(self) -> None:
        """Close the outbox and the destination."""
        if self._ingestor is not None:
            self._ingestor.close()
            self._ingestor.destination.close()
            self._ingestor = None


class LocalSink(DatabaseLocation, MeasurementSink):
    """The workstation's database (default: SQLite in :func:`db.engine.data_dir`, migrated on first use)."""

    def __init__(self, url: str | None = None, outbox_path: Path | str | None = None) -> None:
        super().__init__(outbox_path)
        self._url = url
        self._db: DatabaseDestination | None = None

    def _destination(self) -> DatabaseDestination:
        if self._db is None:
            from station.ingest import DatabaseDestination

            self._db = DatabaseDestination(self.url, migrate=True, source="viewer")
        return self._db

    def prepare(self) -> None:
        """Open and migrate the database now, on the calling thread; an unreachable one is left to the worker.

        The viewer calls this on the GUI thread before a scan or retry worker starts. Opening and
        migrating the database for the first time from the worker thread crashed the process
        intermittently (SIGSEGV in the GUI thread while the worker was inside Alembic's first connect:
        4 of 6 runs of tests/ui/test_instruments.py); opening it here first made 0 of 14. The root cause
        is not identified.
        """
        from station.ingest import DestinationUnreachableError

        try:
            self._destination().open()
        except DestinationUnreachableError:
            pass  # the worker queues the reading and says why

    def recent(self, limit: int = RECENT_DEFAULT) -> list[StoredMeasurement]:
        limit = recent_limit(limit)
        from sqlalchemy import select

        from db.models import Measurement, Panel
        from station.ingest import DestinationUnreachableError

        try:
            with self._destination().sessions()() as session:
                rows = session.execute(
                    select(Measurement, Panel)
                    .outerjoin(Panel, Panel.id == Measurement.panel_id)
                    .where(Measurement.illumination_deg == ILLUMINATION_DEG)  # the 45° block only
                    .order_by(Measurement.id.desc())
                    .limit(limit)
                ).all()
        except DestinationUnreachableError as exc:
            raise StationError(f"{self.where} unreachable: {exc}") from exc
        except Exception as exc:
            raise StationError(f"{self.where}: {type(exc).__name__}: {exc}") from exc
        return [
            _stored(
                m.id,
                f"{p.job} {p.part}" if p is not None else "no panel",
                m.measured_at,
                m.geometries_deg,
                m.lab,
                m.gloss_gu,
            )
            for m, p in rows
        ]

    def _submit_gloss(self, record: GlossRecord) -> GlossReceipt:
        """``station.ingest.store_gloss`` in the workstation's database (through ``station.scan``)."""
        from station.scan import DatabaseTarget

        return DatabaseTarget(self.ingestor).submit_gloss(record)

    def close(self) -> None:
        super().close()
        self._db = None


def _stored(
    mid: int,
    label: str,
    when: dt.datetime | str,
    geometries: list[float],
    lab: list[list[float]],
    gloss: float | None,
) -> StoredMeasurement:
    when_s = when if isinstance(when, str) else when.isoformat(timespec="seconds")
    return StoredMeasurement(
        int(mid),
        label,
        when_s,
        tuple(float(a) for a in geometries),
        np.asarray(lab, float).reshape(-1, 3),
        None if gloss is None else float(gloss),
    )


class ServiceSink(MeasurementSink):
    """A station service: ``POST /api/v1/measurements`` with the record (panel metadata included)."""

    RETRY_LATER = frozenset({401, 403, 408, 425, 429})  # a token or load problem: keep the reading queued

    default_outbox = SERVICE_OUTBOX_FILE

    def __init__(self, client: Any, outbox_path: Path | str | None = None) -> None:
        super().__init__(outbox_path)
        self.client = client  # ui.models.service.ServiceClient

    @property
    def where(self) -> str:
        return f"service {self.client.url}"

    def _destination(self) -> Destination:
        return _ServiceDestination(self)

    def _request(self, method: str, path: str, **kw: Any) -> Any:
        from station.ingest import DestinationUnreachableError, ReadingRefusedError
        from ui.models.service import ServiceUnreachable

        try:
            r = self.client.request(method, path, **kw)
        except ServiceUnreachable as exc:
            raise DestinationUnreachableError(str(exc)) from exc
        if r.status_code >= 500 or r.status_code in self.RETRY_LATER:
            raise DestinationUnreachableError(f"{method} {path}: HTTP {r.status_code} {r.text[:200]}")
        if r.status_code >= 400:
            raise ReadingRefusedError(f"{method} {path}: HTTP {r.status_code} {r.text[:300]}")
        return r

    def _submit_gloss(self, record: GlossRecord) -> GlossReceipt:
        """``POST /qc/gloss``: 201 stored, 200 already stored (the service's token names the actor)."""
        from station.scan import GlossReceipt

        r = self._request("POST", "/qc/gloss", json=record.model_dump(mode="json"))
        status: GlossStatus = "stored" if r.status_code == 201 else "duplicate"
        return GlossReceipt(str(record.client_id), status, int(r.json()["id"]))

    def recent(self, limit: int = RECENT_DEFAULT) -> list[StoredMeasurement]:
        limit = recent_limit(limit)
        from station.ingest import IngestError

        try:
            params = {"limit": limit, "illumination_deg": ILLUMINATION_DEG}  # the 45° block only
            rows = self._request("GET", "/measurements", params=params).json()["data"]
            panels = {
                int(p["id"]): p
                for p in self._request("GET", "/panels", params={"limit": 1000}).json()["data"]
            }
        except IngestError as exc:
            raise StationError(f"{self.where}: {exc}") from exc
        out = []
        for m in rows:
            p = panels.get(m.get("panel_id") or -1)
            label = (
                f"{p['job']} {p['part']}"
                if p
                else ("panel " + str(m["panel_id"]) if m.get("panel_id") else "no panel")
            )
            out.append(
                _stored(m["id"], label, m["measured_at"], m["geometries_deg"], m["lab"], m.get("gloss_gu"))
            )
        return out


class _ServiceDestination:
    """The :class:`~station.ingest.Destination` of a :class:`ServiceSink` (its current client, looked up per call)."""

    def __init__(self, sink: ServiceSink) -> None:
        self._sink = sink

    @property
    def where(self) -> str:
        return self._sink.where

    def store(self, reading: Reading, *, actor_id: int | None = None, replayed: bool = False) -> Receipt:
        """``POST /measurements``: 201 stored, 200 already stored (the service's token names the actor)."""
        from station.ingest import Receipt

        r = self._sink._request("POST", "/measurements", json=reading.model_dump(mode="json"))
        return Receipt(
            str(reading.client_id), "stored" if r.status_code == 201 else "duplicate", int(r.json()["id"])
        )

    def find(self, client_id: uuid.UUID) -> int | None:
        """Not asked of a service: a re-sent reading is answered 200 with the stored row."""
        return None

    def close(self) -> None:
        """Nothing to release (the client belongs to the viewer)."""
