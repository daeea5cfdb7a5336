"""Where the viewer stores its scans: the measurement database, through the ingest layer (Qt-free).

Every reading is written to an on-disk :class:`station.ingest.Outbox` *before* anything is sent, then
the queue is drained oldest first: :class:`LocalSink` stores each queued reading with
:func:`station.ingest.store_reading` in the workstation's database (as ``station serve``:
``$CACAD_DATABASE_URL``, else SQLite in ``$CACAD_DATA_DIR`` or ``./var``; Alembic migrations applied on
first use), :class:`ServiceSink` posts it to ``POST /api/v1/measurements`` of a station service. The panel
(job, part, substrate, notes) is found by its metadata or created in the same transaction (local) or just before the reading (service), so a
retried reading names the same panel and, keyed by its client id, is stored once.

An unreachable database or service leaves the reading queued (retried on the next scan or on
"Retry queued"); a refusal (a bad reading, a client id conflict) moves it to the outbox's dead-letter
table with the error. Either way the reading stays on disk: nothing is lost.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import threading
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from station.errors import InputError, StationError
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg

if TYPE_CHECKING:  # SQLAlchemy, pydantic and the ORM load on first use (≈0.5 s off the viewer's start-up)
    from station.ingest import Outbox, Reading

OUTBOX_FILE = "viewer-outbox.sqlite3"
SERVICE_OUTBOX_FILE = "viewer-service-outbox.sqlite3"
_TEXT = re.compile(r"^[^\x00-\x1f]+$")
Status = Literal["stored", "duplicate", "queued", "refused"]


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

    @property
    def label(self) -> str:
        """``job part`` for lists."""
        return f"{self.job} {self.part}"


@dataclass(frozen=True)
class StoreReceipt:
    """What became of one reading; *message* says it plainly when it is not (yet) in the database."""

    client_id: str
    status: Status
    measurement_id: int | None = None
    message: str = ""


@dataclass(frozen=True)
class StoredMeasurement:
    """A measurement read back from the database or the service (angles in degrees, Lab D65/10°)."""

    id: int
    label: str
    measured_at: str
    geometries_deg: tuple[float, ...]
    lab: np.ndarray
    gloss_gu: float | None

    def design(self) -> FaceFlopTravelGloss | None:
        """FFTG fit of the positive aspecular angles (eqs 3.3.1–3.3.10), or ``None`` with fewer than 3."""
        keep = sorted((a, i) for i, a in enumerate(self.geometries_deg) if a > 0)
        if len(keep) < 3:
            return None
        angles = tuple(a for a, _ in keep)
        lab = self.lab[[i for _, i in keep]]
        try:
            return fit_fftg(AspecularMeasurements(angles, lab, self.gloss_gu)).design
        except InputError:
            return None


class _Unreachable(Exception):
    """The database or service is away: keep the reading queued."""


class _Refused(Exception):
    """The database or service refused the reading: move it to the dead-letter table."""


class MeasurementSink:
    """The outbox and its drain; subclasses send one queued reading (``_send``) and list stored ones."""

    default_outbox = OUTBOX_FILE

    def __init__(self, outbox_path: Path | str | None = None) -> None:
        self._outbox_path = Path(outbox_path) if outbox_path is not None else None
        self._outbox: Outbox | None = None

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

    @property
    def outbox(self) -> Outbox:
        """The on-disk queue (opened on first use)."""
        if self._outbox is None:
            from station.ingest import Outbox

            self._outbox = Outbox(self.outbox_path)
        return self._outbox

    def submit(self, panel: PanelInfo, reading: Reading) -> StoreReceipt:
        """Queue *reading* on disk, then drain the queue; the receipt of *reading*. Blocking."""
        panel = panel.validated()
        body = json.dumps(
            {"panel": asdict(panel), "reading": reading.model_dump(mode="json")}, sort_keys=True
        )
        cid = str(reading.client_id)
        self.outbox.put(cid, body)
        return self.flush().get(cid) or StoreReceipt(cid, "queued", None, self._queued_message(""))

    def flush(self) -> dict[str, StoreReceipt]:
        """Send queued readings oldest first; stop at the first "unreachable". Receipts by client id."""
        from station.ingest import Reading

        out: dict[str, StoreReceipt] = {}
        for entry in self.outbox.entries():
            try:
                doc = json.loads(entry.body)
                panel = PanelInfo(**doc["panel"]).validated()
                reading = Reading.model_validate(doc["reading"])
                measurement_id, created = self._send(panel, reading)
            except _Unreachable as exc:
                out[entry.client_id] = StoreReceipt(
                    entry.client_id, "queued", None, self._queued_message(str(exc))
                )
                break
            except (_Refused, InputError, ValueError, KeyError, TypeError) as exc:
                self.outbox.bury(entry, str(exc))
                out[entry.client_id] = StoreReceipt(
                    entry.client_id,
                    "refused",
                    None,
                    f"{self.where} refused the reading: {exc} (kept in the dead-letter table of {self.outbox_path})",
                )
            else:
                self.outbox.remove(entry.seq)
                out[entry.client_id] = StoreReceipt(
                    entry.client_id, "stored" if created else "duplicate", measurement_id
                )
        return out

    def _queued_message(self, why: str) -> str:
        return (
            f"{self.where} unreachable{': ' + why if why else ''} — the reading is kept in "
            f"{self.outbox_path} ({len(self.outbox)} queued) and sent on the next scan or retry"
        )

    def prepare(self) -> None:
        """Open the store on the calling (GUI) thread before a worker sends to it; no-op by default."""

    def pending(self) -> int:
        """Readings waiting in the outbox."""
        return len(self.outbox) if self._outbox is not None or self.outbox_path.exists() else 0

    def _send(self, panel: PanelInfo, reading: Reading) -> tuple[int, bool]:
        raise NotImplementedError

    def recent(self, limit: int = 50) -> list[StoredMeasurement]:
        """The newest stored measurements (raises :class:`StationError` with a plain message)."""
        raise NotImplementedError

    def close(self) -> None:
        """Close the outbox."""
        if self._outbox is not None:
            self._outbox.close()
            self._outbox = None


class LocalSink(MeasurementSink):
    """The workstation's database (default: SQLite in :func:`db.engine.data_dir`, migrated on first use)."""

    def __init__(self, url: str | None = None, outbox_path: Path | str | None = None) -> None:
        super().__init__(outbox_path)
        self._url = url
        self._lock = threading.Lock()  # the scan worker and the QA screen may both be first
        self._engine: Any = None
        self._sessions: Any = None

    @property
    def url(self) -> str:
        """The database URL: as ``station serve``, ``$CACAD_DATABASE_URL`` or ``station.sqlite3`` in
        :func:`db.engine.data_dir` (``$CACAD_DATA_DIR`` or ``./var``)."""
        if self._url is None:
            from db.engine import default_database_url

            self._url = os.environ.get("CACAD_DATABASE_URL") or default_database_url()
        return self._url

    @property
    def where(self) -> str:
        return f"database {self.url}"

    def prepare(self) -> None:
        """Open and migrate the database now, on the calling thread; an unreachable one is left to the worker.

        The viewer calls this on the GUI thread before a scan or retry worker starts. Opening and
        migrating the database for the first time from the worker thread crashed the process
        intermittently (SIGSEGV in the GUI thread while the worker was inside Alembic's first connect:
        4 of 6 runs of tests/ui/test_instruments.py); opening it here first made 0 of 14. The root cause
        is not identified.
        """
        try:
            self._ready()
        except _Unreachable:
            pass  # the worker queues the reading and says why

    def _ready(self) -> None:
        with self._lock:
            self._ready_locked()

    def _ready_locked(self) -> None:
        if self._engine is not None:
            return
        from db.engine import make_engine, make_sessionmaker
        from db.migrate import ensure_at_head

        try:
            ensure_at_head(self.url)
        except Exception as exc:  # a locked, unwritable or newer database: keep the reading, say why
            raise _Unreachable(f"{type(exc).__name__}: {exc}") from exc
        self._engine = make_engine(self.url)
        self._sessions = make_sessionmaker(self._engine)

    def _send(self, panel: PanelInfo, reading: Reading) -> tuple[int, bool]:
        from sqlalchemy import insert, select

        from db.base import utcnow
        from db.models import AuditEvent, Panel
        from station.ingest import IngestError, is_unreachable, store_reading

        self._ready()
        try:
            with self._sessions.begin() as session:
                panel_id = session.scalar(
                    select(Panel.id)
                    .where(
                        Panel.job == panel.job,
                        Panel.part == panel.part,
                        Panel.substrate == panel.substrate,
                        Panel.notes == panel.notes,
                    )
                    .order_by(Panel.id)
                    .limit(1)
                )
                if panel_id is None:
                    row = Panel(**asdict(panel))
                    session.add(row)
                    session.flush()
                    panel_id = row.id
                result = store_reading(session, reading.model_copy(update={"panel_id": panel_id}))
                if result.created:  # audited like the ingest loop's own writes (station account: no user)
                    session.execute(
                        insert(AuditEvent.__table__),
                        {
                            "at": utcnow(),
                            "actor_id": None,
                            "action": "measurement.ingest",
                            "entity": "measurement",
                            "entity_id": str(result.measurement_id),
                            "detail": {
                                "client_id": str(reading.client_id),
                                "operator": reading.operator,
                                "source": "viewer",
                            },
                        },
                    )
        except IngestError as exc:
            raise _Refused(str(exc)) from exc
        except Exception as exc:
            if is_unreachable(exc):
                raise _Unreachable(f"{type(exc).__name__}: {exc}") from exc
            raise
        return result.measurement_id, result.created

    def recent(self, limit: int = 50) -> list[StoredMeasurement]:
        from sqlalchemy import select

        from db.models import Measurement, Panel

        try:
            self._ready()
            with self._sessions() as session:
                rows = session.execute(
                    select(Measurement, Panel)
                    .outerjoin(Panel, Panel.id == Measurement.panel_id)
                    .order_by(Measurement.id.desc())
                    .limit(limit)
                ).all()
        except _Unreachable as exc:
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

    def close(self) -> None:
        super().close()
        if self._engine is not None:
            self._engine.dispose()
            self._engine = None


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
    """A station service: ``POST /api/v1/panels`` (when no panel has this metadata) and ``POST /api/v1/measurements``."""

    RETRY_LATER = frozenset({401, 403, 408, 425, 429})  # a token or load problem: keep the reading queued

    default_outbox = SERVICE_OUTBOX_FILE

    def __init__(self, client: Any, outbox_path: Path | str | None = None) -> None:
        super().__init__(outbox_path)
        self.client = client  # ui.models.service.ServiceClient

    @property
    def where(self) -> str:
        return f"service {self.client.url}"

    def _request(self, method: str, path: str, **kw: Any) -> Any:
        from ui.models.service import ServiceUnreachable

        try:
            r = self.client.request(method, path, **kw)
        except ServiceUnreachable as exc:
            raise _Unreachable(str(exc)) from exc
        if r.status_code >= 500 or r.status_code in self.RETRY_LATER:
            raise _Unreachable(f"{method} {path}: HTTP {r.status_code} {r.text[:200]}")
        if r.status_code >= 400:
            raise _Refused(f"{method} {path}: HTTP {r.status_code} {r.text[:300]}")
        return r

    def _send(self, panel: PanelInfo, reading: Reading) -> tuple[int, bool]:
        page = self._request(
            "GET", "/panels", params={"job": panel.job, "part": panel.part, "limit": 1000}
        ).json()
        same = [
            p
            for p in page["data"]
            if p.get("substrate", "") == panel.substrate and p.get("notes", "") == panel.notes
        ]
        if same:
            panel_id = min(int(p["id"]) for p in same)
        else:
            panel_id = int(self._request("POST", "/panels", json=asdict(panel)).json()["id"])
        body = reading.model_copy(update={"panel_id": panel_id}).model_dump(mode="json")
        r = self._request("POST", "/measurements", json=body)
        return int(r.json()["id"]), r.status_code == 201

    def recent(self, limit: int = 50) -> list[StoredMeasurement]:
        try:
            rows = self._request("GET", "/measurements", params={"limit": limit}).json()["data"]
            panels = {
                int(p["id"]): p
                for p in self._request("GET", "/panels", params={"limit": 1000}).json()["data"]
            }
        except (_Unreachable, _Refused) as exc:
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
