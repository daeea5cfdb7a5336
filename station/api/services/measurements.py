"""Measurements: ingest through the API, corrections (append-only), queries and CSV export."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from typing import Any

from sqlalchemy import Select, func, select
from sqlalchemy.orm import Session, aliased

from db.models import Instrument, Measurement, Panel, User
from station.api.errors import ConflictError, NotFoundError
from station.api.schemas.measurements import CorrectionCreate, MeasurementPublic, MeasurementQuery
from station.api.services import audit
from station.csv_cells import escape_cell
from station.ingest import Reading, ReferenceNotFoundError, store_audited, store_reading

_Successor = aliased(Measurement)

CSV_COLUMNS = (
    "measurement_id",
    "client_id",
    "panel_id",
    "job",
    "part",
    "instrument_serial",
    "operator",
    "measured_at",
    "illumination_deg",
    "aspecular_deg",
    "L",
    "a",
    "b",
    "gloss_gu",
    "gloss_geometry_deg",
    "illuminant",
    "observer",
    "supersedes_id",
    "payload_sha256",
)


def _base() -> Select[Measurement, str, int, str, str]:
    return (
        select(Measurement, Instrument.serial, _Successor.id, Panel.job, Panel.part)
        .join(Instrument, Instrument.id == Measurement.instrument_id)
        .outerjoin(Panel, Panel.id == Measurement.panel_id)
        .outerjoin(_Successor, _Successor.supersedes_id == Measurement.id)
    )


def _public(row: Any) -> MeasurementPublic:
    m, serial, successor = row[0], row[1], row[2]
    data = {c: getattr(m, c) for c in MeasurementPublic.model_fields if hasattr(m, c)}
    return MeasurementPublic(**data, instrument_serial=serial, superseded_by_id=successor)


def get_measurement(*, session: Session, measurement_id: int) -> MeasurementPublic:
    """Measurement *measurement_id* or :class:`NotFoundError`."""
    row = session.execute(_base().where(Measurement.id == measurement_id)).first()
    if row is None:
        raise NotFoundError(f"measurement {measurement_id} not found")
    return _public(row)


def _refuse_if_superseded(session: Session, measurement_id: int) -> None:
    """:class:`NotFoundError` for a missing measurement, :class:`ConflictError` for a corrected one."""
    original = get_measurement(session=session, measurement_id=measurement_id)
    if original.superseded_by_id is not None:
        raise ConflictError(
            f"measurement {measurement_id} is already superseded by {original.superseded_by_id}"
        )


def ingest(*, session: Session, actor: User, reading: Reading) -> tuple[MeasurementPublic, bool]:
    """Store *reading* once with its audit row (``station.ingest.store_audited``, the writer the
    :class:`~station.ingest.Ingestor` uses); ``(measurement, created)`` (a re-sent reading returns the stored row)."""
    result = store_audited(session, reading, actor_id=actor.id, action="measurement.create")
    stored = get_measurement(session=session, measurement_id=result.measurement_id)  # same transaction
    session.commit()
    return stored, result.created


def correct(
    *, session: Session, actor: User, measurement_id: int, correction: CorrectionCreate
) -> MeasurementPublic:
    """Store a corrected reading that supersedes *measurement_id*, with who and why.

    Optimistic: the "already superseded?" check runs first, and the unique ``supersedes_id`` decides a
    race between two corrections. The loser's insert is refused by that constraint; it is then told
    which correction won (:class:`ConflictError`, 409), not that the measurement is missing.
    """
    _refuse_if_superseded(session, measurement_id)
    existing = session.scalar(
        select(Measurement.id).where(Measurement.client_id == correction.reading.client_id)
    )
    if existing is not None:
        raise ConflictError(
            f"client_id {correction.reading.client_id} is already stored (measurement {existing})"
        )
    try:
        result = store_reading(
            session,
            correction.reading,
            created_by_id=actor.id,
            supersedes_id=measurement_id,
            correction_reason=correction.reason,
        )
    except ReferenceNotFoundError:
        session.rollback()  # the refused insert aborted the transaction; look again in a fresh one
        _refuse_if_superseded(session, measurement_id)
        raise
    audit.record(
        session=session,
        actor=actor,
        action="measurement.correct",
        entity="measurement",
        entity_id=result.measurement_id,
        supersedes_id=measurement_id,
        reason=correction.reason,
    )
    session.commit()
    return get_measurement(session=session, measurement_id=result.measurement_id)


def _filtered(q: MeasurementQuery) -> Select[Measurement, str, int, str, str]:
    query = _base()
    if q.job:
        query = query.where(Panel.job == q.job)
    if q.part:
        query = query.where(Panel.part == q.part)
    if q.panel_id is not None:
        query = query.where(Measurement.panel_id == q.panel_id)
    if q.instrument:
        query = query.where(Instrument.serial == q.instrument)
    if q.since is not None:
        query = query.where(Measurement.measured_at >= q.since)
    if q.until is not None:
        query = query.where(Measurement.measured_at < q.until)
    if q.illumination_deg is not None:
        query = query.where(Measurement.illumination_deg == q.illumination_deg)
    if not q.include_superseded:
        query = query.where(_Successor.id.is_(None))
    return query


def query(
    *, session: Session, q: MeasurementQuery, limit: int, offset: int
) -> tuple[list[MeasurementPublic], int]:
    """Measurements matching *q*, newest first (corrected rows hidden unless asked for)."""
    base = _filtered(q)
    total = session.scalar(
        select(func.count()).select_from(base.with_only_columns(Measurement.id).subquery())
    )
    rows = session.execute(
        base.order_by(Measurement.measured_at.desc(), Measurement.id.desc()).limit(limit).offset(offset)
    ).all()
    return [_public(r) for r in rows], total or 0


def export_csv(*, session: Session, q: MeasurementQuery, max_rows: int = 100_000) -> Iterator[str]:
    """CSV text, one line per measurement and geometry (long format), oldest first.

    Free-text cells (job, part, instrument serial, operator) that a spreadsheet would evaluate as a
    formula get a leading single quote (:func:`station.csv_cells.escape_cell`); numbers are written as
    numbers (``-1.5`` stays ``-1.5``).
    """
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    yield buf.getvalue()
    rows = session.execute(
        _filtered(q).order_by(Measurement.measured_at, Measurement.id).limit(max_rows)
    ).all()
    for m, serial, _succ, job, part in rows:
        buf.seek(0)
        buf.truncate()
        for angle, (L, a, b) in zip(m.geometries_deg, m.lab, strict=True):
            writer.writerow(
                [
                    m.id,
                    m.client_id,
                    m.panel_id or "",
                    escape_cell(job or ""),
                    escape_cell(part or ""),
                    escape_cell(serial),
                    escape_cell(m.operator),
                    m.measured_at.isoformat(),
                    m.illumination_deg,
                    angle,
                    L,
                    a,
                    b,
                    "" if m.gloss_gu is None else m.gloss_gu,
                    "" if m.gloss_geometry_deg is None else m.gloss_geometry_deg,
                    m.illuminant,
                    m.observer,
                    m.supersedes_id or "",
                    m.payload_sha256,
                ]
            )
        yield buf.getvalue()
