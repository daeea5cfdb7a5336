"""Gloss readings: the record a station sends, stored once, and paired with a colour measurement.

A gloss meter (20/60/85°, ISO 2813) and a multi-angle spectrophotometer are separate instruments. A
panel measured on both gives one colour measurement (``measurements``) and one gloss reading
(``gloss_readings``); :func:`pair_gloss` joins them into one measurement view:

1. a gloss reading that names its colour measurement (``measurement_id``: taken together, e.g. by the
   service's measure with a gloss meter joined) pairs with that one;
2. a gloss-only reading of a panel pairs with the colour measurement of the same panel nearest in
   time, if within :data:`PAIR_WINDOW` of it; closest pairs first, each reading used once.

Units: gloss in gloss units (GU) per geometry, haze in haze units (HU, ASTM E430), log haze in log haze units,
DOI 0–100, Rspec in GU.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import uuid
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Annotated, Final, Protocol

from pydantic import BaseModel, Field, model_validator
from sqlalchemy import select
from sqlalchemy.orm import Session

from db.chain import append_audit, record_change
from db.models import GlossReading, Measurement
from station.ingest.errors import ClientIdConflictError, ReferenceNotFoundError
from station.ingest.schema import CalibrationRef, InstrumentRef, PanelRef, Text64, Timestamp
from station.ingest.store import StoreResult, _calibration_id, _insert, _instrument_id, _panel_id
from station.schema_config import strict_config

__all__ = [
    "GLOSS_GEOMETRIES",
    "PAIR_WINDOW",
    "GlossMeterLike",
    "GlossRecord",
    "GlossRow",
    "gloss_of_measurements",
    "gloss_record_from_reading",
    "pair_gloss",
    "store_gloss",
]

#: The geometries of a gloss meter (degrees from the normal, ISO 2813).
GLOSS_GEOMETRIES: Final = (20, 60, 85)
#: A gloss-only reading pairs with a colour measurement of its panel taken at most this far apart.
PAIR_WINDOW: Final = dt.timedelta(minutes=30)
#: Upper bound of any gloss value (GU): the envelope of the ingest record's ``gloss_gu``.
GLOSS_GU_MAX: Final = 2000.0

GU = Annotated[float, Field(strict=True, ge=0.0, le=GLOSS_GU_MAX, allow_inf_nan=False)]


class GlossRecord(BaseModel):
    """One gloss meter reading as sent to ingest; ``client_id`` makes re-sending idempotent.

    At least one of ``gloss_20_gu``, ``gloss_60_gu``, ``gloss_85_gu``. The panel is ``panel_id``,
    ``panel`` (metadata, found or created as for a colour reading), or, with ``measurement_id``
    alone, the panel of that measurement.
    """

    model_config = strict_config(
        examples=[
            {
                "client_id": "6c1d9b65-4a8f-4e67-8b64-1e2f5d2a8b21",
                "instrument": {"serial": "SIM-GL-0001", "model": "gloss simulator", "kind": "gloss"},
                "panel_id": 1,
                "operator": "ana",
                "measured_at": "2026-11-23T08:31:00Z",
                "gloss_20_gu": 81.2,
                "gloss_60_gu": 90.5,
                "gloss_85_gu": 97.0,
                "haze_hu": 12.0,
                "doi": 88.0,
            }
        ]
    )

    client_id: uuid.UUID
    instrument: InstrumentRef
    calibration: CalibrationRef | None = None
    panel_id: Annotated[int, Field(strict=True, ge=1, le=2**31 - 1)] | None = None
    panel: PanelRef | None = None
    measurement_id: Annotated[int, Field(strict=True, ge=1, le=2**31 - 1)] | None = None
    operator: Text64
    measured_at: Timestamp
    gloss_20_gu: GU | None = None
    gloss_60_gu: GU | None = None
    gloss_85_gu: GU | None = None
    haze_hu: Annotated[float, Field(strict=True, ge=0.0, le=2000.0, allow_inf_nan=False)] | None = None
    log_haze: Annotated[float, Field(strict=True, ge=0.0, le=2000.0, allow_inf_nan=False)] | None = None
    doi: Annotated[float, Field(strict=True, ge=0.0, le=100.0, allow_inf_nan=False)] | None = None
    rspec_gu: GU | None = None

    @model_validator(mode="after")
    def _consistent(self) -> GlossRecord:
        if self.gloss_20_gu is None and self.gloss_60_gu is None and self.gloss_85_gu is None:
            raise ValueError("gloss_60_gu: expected at least one of gloss_20_gu, gloss_60_gu, gloss_85_gu")
        if self.panel_id is not None and self.panel is not None:
            raise ValueError("panel: expected panel_id or panel metadata, not both")
        return self

    def gloss_gu(self) -> dict[int, float]:
        """Gloss (GU) by geometry (degrees), the geometries measured only."""
        values = (self.gloss_20_gu, self.gloss_60_gu, self.gloss_85_gu)
        return {g: v for g, v in zip(GLOSS_GEOMETRIES, values, strict=True) if v is not None}

    def canonical_json(self) -> str:
        """The record as compact JSON with sorted keys."""
        return json.dumps(self.model_dump(mode="json"), sort_keys=True, separators=(",", ":"))

    def payload_sha256(self) -> str:
        """SHA-256 of :meth:`canonical_json` (tells a re-sent reading from another under the same id)."""
        return hashlib.sha256(self.canonical_json().encode()).hexdigest()


class GlossMeterLike(Protocol):
    """What the conversion reads of a gloss meter reading (``station.drivers.readings.GlossReading``)."""

    @property
    def gloss_gu(self) -> Mapping[int, float]: ...
    @property
    def haze_hu(self) -> float: ...
    @property
    def log_haze(self) -> float: ...
    @property
    def doi(self) -> float: ...
    @property
    def rspec(self) -> float: ...
    @property
    def serial(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def calibration_id(self) -> str: ...
    @property
    def time(self) -> dt.datetime: ...


def gloss_record_from_reading(
    reading: GlossMeterLike,
    *,
    operator: str,
    client_id: uuid.UUID | None = None,
    panel_id: int | None = None,
    panel: PanelRef | None = None,
    measurement_id: int | None = None,
) -> GlossRecord:
    """The ingest record of a gloss meter reading (validated by :class:`GlossRecord`).

    Geometries other than 20/60/85° are left out; the calibration is keyed by
    :func:`station.ingest.calibration_client_id` as for a colour reading.
    """
    from station.ingest.records import calibration_client_id

    gloss = {int(g): float(v) for g, v in reading.gloss_gu.items()}
    serial = reading.serial or "unknown"
    calibration = (
        CalibrationRef(
            client_id=calibration_client_id(serial, reading.calibration_id), performed_at=reading.time
        )
        if reading.calibration_id
        else None
    )
    return GlossRecord(
        client_id=client_id or uuid.uuid4(),
        instrument=InstrumentRef(serial=serial, model=reading.model or "unknown", kind="gloss"),
        calibration=calibration,
        panel_id=panel_id,
        panel=panel,
        measurement_id=measurement_id,
        operator=operator,
        measured_at=reading.time,
        gloss_20_gu=gloss.get(20),
        gloss_60_gu=gloss.get(60),
        gloss_85_gu=gloss.get(85),
        haze_hu=float(reading.haze_hu),
        log_haze=float(reading.log_haze),
        doi=float(reading.doi),
        rspec_gu=float(reading.rspec),
    )


def store_gloss(session: Session, record: GlossRecord, *, created_by_id: int | None = None) -> StoreResult:
    """Store *record* once inside the caller's transaction (the caller commits), with its audit event.

    With ``measurement_id`` the measurement must exist and, when both name a panel, be of the same
    panel (:class:`ReferenceNotFoundError` otherwise); its panel is the reading's when the record names
    none. A client id taken by a different payload raises :class:`ClientIdConflictError`.
    """
    sha = record.payload_sha256()
    existing = session.execute(
        select(GlossReading.id, GlossReading.payload_sha256).where(GlossReading.client_id == record.client_id)
    ).first()
    if existing is not None:
        if existing.payload_sha256 != sha:
            raise ClientIdConflictError(str(record.client_id), existing.payload_sha256, sha)
        return StoreResult(int(existing.id), created=False)
    panel_id = _panel_id(session, record, created_by_id)
    if record.measurement_id is not None:
        m_panel = session.execute(
            select(Measurement.id, Measurement.panel_id).where(Measurement.id == record.measurement_id)
        ).first()
        if m_panel is None:
            raise ReferenceNotFoundError(f"measurement_id {record.measurement_id} does not exist")
        if panel_id is None:
            panel_id = m_panel.panel_id
        elif m_panel.panel_id is not None and m_panel.panel_id != panel_id:
            raise ReferenceNotFoundError(
                f"measurement_id {record.measurement_id} is of panel {m_panel.panel_id}, not panel {panel_id}"
            )
    instrument_id = _instrument_id(session, record, None)
    calibration_id = _calibration_id(session, record, instrument_id)
    # every field of the record but its references is a column of the same name
    values = record.model_dump(exclude={"instrument", "calibration", "panel", "panel_id"}) | dict(
        panel_id=panel_id,
        instrument_id=instrument_id,
        calibration_id=calibration_id,
        received_at=dt.datetime.now(dt.UTC),
        payload_sha256=sha,
        created_by_id=created_by_id,
    )
    stmt = (
        _insert(session, GlossReading.__table__)
        .values(**values)
        .on_conflict_do_nothing(index_elements=["client_id"])
        .returning(GlossReading.__table__.c.id)
    )
    new_id = session.execute(stmt).scalar()
    if new_id is None:  # a concurrent writer stored it first
        row = session.execute(
            select(GlossReading.id, GlossReading.payload_sha256).where(
                GlossReading.client_id == record.client_id
            )
        ).one()
        if row.payload_sha256 != sha:
            raise ClientIdConflictError(str(record.client_id), row.payload_sha256, sha)
        return StoreResult(int(row.id), created=False)
    record_change(session, "gloss_readings", int(new_id), "insert")
    append_audit(
        session,
        {
            "actor_id": created_by_id,
            "action": "gloss.create",
            "entity": "gloss_reading",
            "entity_id": str(new_id),
            "detail": {"client_id": str(record.client_id), "operator": record.operator},
        },
    )
    return StoreResult(int(new_id), created=True)


@dataclass(frozen=True)
class GlossRow:
    """What :func:`pair_gloss` reads of a colour measurement or a gloss reading."""

    id: int
    panel_id: int | None
    measured_at: dt.datetime
    measurement_id: int | None = None


def pair_gloss(
    colour: Iterable[GlossRow], gloss: Iterable[GlossRow], window: dt.timedelta = PAIR_WINDOW
) -> dict[int, int]:
    """Colour measurement id → gloss reading id, by the rules of the module docstring.

    Each colour measurement gets at most one gloss reading and each gloss reading pairs at most once.
    Among several gloss readings naming the same measurement the latest measured wins; the rest of the
    pairing is greedy by time distance (ties by ids), which is the closest pairing of each panel when
    readings alternate colour, gloss, colour, gloss.
    """
    colours = {c.id: c for c in colour}
    glosses = list(gloss)
    paired: dict[int, int] = {}
    used: set[int] = set()
    for g in sorted(glosses, key=lambda r: (r.measured_at, r.id), reverse=True):
        if g.measurement_id is not None and g.measurement_id in colours and g.measurement_id not in paired:
            paired[g.measurement_id] = g.id
            used.add(g.id)
    candidates: list[tuple[dt.timedelta, int, int]] = []
    for g in glosses:
        if g.id in used or g.measurement_id is not None or g.panel_id is None:
            continue
        for c in colours.values():
            if c.panel_id == g.panel_id and c.id not in paired:
                gap = abs(c.measured_at - g.measured_at)
                if gap <= window:
                    candidates.append((gap, c.id, g.id))
    for _gap, c_id, g_id in sorted(candidates):
        if c_id not in paired and g_id not in used:
            paired[c_id] = g_id
            used.add(g_id)
    return paired


def gloss_of_measurements(session: Session, measurement_ids: Iterable[int]) -> dict[int, GlossReading]:
    """Measurement id → its paired gloss reading row (:func:`pair_gloss`), for the given measurements.

    The pairing runs over every colour measurement and gloss reading of their panels (and the gloss
    readings naming them), so a measurement gets the same gloss reading whichever others are asked for.
    """
    ids = set(measurement_ids)
    if not ids:
        return {}
    panel_ids = set(
        session.scalars(
            select(Measurement.panel_id).where(Measurement.id.in_(ids), Measurement.panel_id.is_not(None))
        )
    )
    colour = session.execute(
        select(Measurement.id, Measurement.panel_id, Measurement.measured_at).where(
            Measurement.panel_id.in_(panel_ids) | Measurement.id.in_(ids)
        )
    ).all()
    gloss = session.scalars(
        select(GlossReading).where(
            GlossReading.panel_id.in_(panel_ids) | GlossReading.measurement_id.in_(ids)
        )
    ).all()
    pairs = pair_gloss(
        [GlossRow(r.id, r.panel_id, r.measured_at) for r in colour],
        [GlossRow(g.id, g.panel_id, g.measured_at, g.measurement_id) for g in gloss],
    )
    by_id = {g.id: g for g in gloss}
    return {m: by_id[g] for m, g in pairs.items() if m in ids}
