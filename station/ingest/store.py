"""Write one reading exactly once: instrument and calibration upserted, measurement inserted by client id.

All three statements run in one transaction with ``INSERT … ON CONFLICT DO NOTHING`` on the unique
keys (instrument serial, calibration client id, measurement client id), so a reading sent twice, or
replayed after a crash that hit between the database commit and the outbox acknowledgement, is stored
once. A second reading under a stored client id but with a different payload hash is refused.
A new row is appended to the measurement hash chain (``db.chain``) under the chain's lock, held until
the caller commits.
"""

from __future__ import annotations

import datetime as dt
import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Final, Protocol

from sqlalchemy import Table, select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from db import chain
from db.models import CalibrationRecord, Instrument, Measurement, Panel
from station.ingest.errors import ClientIdConflictError, ReferenceNotFoundError
from station.ingest.schema import CalibrationRef, InstrumentRef, PanelRef, Reading


class Provenance(Protocol):
    """What the instrument, calibration and panel upserts read of a record (a colour or a gloss reading)."""

    @property
    def instrument(self) -> InstrumentRef: ...
    @property
    def calibration(self) -> CalibrationRef | None: ...
    @property
    def panel(self) -> PanelRef | None: ...
    @property
    def panel_id(self) -> int | None: ...
    @property
    def operator(self) -> str: ...
    @property
    def measured_at(self) -> dt.datetime: ...


@dataclass(frozen=True)
class StoreResult:
    """Outcome of :func:`store_reading`: the row id, whether this call created it and, when it did,
    the column values it inserted (``row``: what the stored row reads, its id aside)."""

    measurement_id: int
    created: bool
    row: Mapping[str, Any] | None = field(default=None, compare=False, repr=False)


def _insert(session: Session, table: Table) -> Any:
    dialect = session.get_bind().dialect.name
    if dialect == "postgresql":
        return postgresql.insert(table)
    if dialect == "sqlite":
        return sqlite.insert(table)
    raise NotImplementedError(f"ingest supports sqlite and postgresql, not {dialect}")


def _instrument_id(session: Session, reading: Provenance, cache: dict[str, int] | None) -> int:
    ref = reading.instrument
    if cache is not None and ref.serial in cache:
        return cache[ref.serial]
    table = Instrument.__table__
    created = session.execute(
        _insert(session, table)
        .values(
            serial=ref.serial,
            model=ref.model,
            kind=ref.kind,
            firmware=ref.firmware,
            created_at=reading.measured_at,
        )
        .on_conflict_do_nothing(index_elements=["serial"])
        .returning(table.c.id)
    ).scalar()
    if created is not None:
        chain.record_change(session, "instruments", int(created), "insert")
    instrument_id = session.scalars(select(Instrument.id).where(Instrument.serial == ref.serial)).one()
    if cache is not None:
        cache[ref.serial] = instrument_id
    return instrument_id


def _calibration_id(session: Session, reading: Provenance, instrument_id: int) -> int | None:
    cal = reading.calibration
    if cal is None:
        return None
    created = session.execute(
        _insert(session, CalibrationRecord.__table__)
        .values(
            client_id=cal.client_id,
            instrument_id=instrument_id,
            performed_at=cal.performed_at,
            operator=reading.operator,
            reference=cal.reference,
            passed=cal.passed,
            result={},
        )
        .on_conflict_do_nothing(index_elements=["client_id"])
        .returning(CalibrationRecord.__table__.c.id)
    ).scalar()
    if created is not None:
        chain.record_change(session, "calibration_records", int(created), "insert")
    return session.scalars(
        select(CalibrationRecord.id).where(CalibrationRecord.client_id == cal.client_id)
    ).one()


@functools.cache
def _measurement_insert(dialect: str) -> Any:
    """``INSERT … ON CONFLICT (client_id) DO NOTHING RETURNING id``, built once per dialect (parameters bound per call)."""
    table = Measurement.__table__
    stmt = postgresql.insert(table) if dialect == "postgresql" else sqlite.insert(table)
    return stmt.on_conflict_do_nothing(index_elements=["client_id"]).returning(Measurement.id)


def _panel_id(session: Session, reading: Provenance, created_by_id: int | None) -> int | None:
    """The panel of *reading*: ``panel_id`` (which must exist), or the panel its metadata names (found or created)."""
    if reading.panel is None:
        if reading.panel_id is not None and session.get(Panel, reading.panel_id) is None:
            raise ReferenceNotFoundError(f"panel_id {reading.panel_id} does not exist")
        return reading.panel_id
    ref = reading.panel
    found = session.scalar(
        select(Panel.id)
        .where(
            Panel.job == ref.job,
            Panel.part == ref.part,
            Panel.substrate == ref.substrate,
            Panel.notes == ref.notes,
        )
        .order_by(Panel.id)
        .limit(1)
    )
    if found is not None:
        return int(found)
    row = Panel(
        job=ref.job, part=ref.part, substrate=ref.substrate, notes=ref.notes, created_by_id=created_by_id
    )
    session.add(row)
    session.flush()
    return int(row.id)


def store_reading(
    session: Session,
    reading: Reading,
    *,
    created_by_id: int | None = None,
    supersedes_id: int | None = None,
    correction_reason: str | None = None,
    instrument_cache: dict[str, int] | None = None,
) -> StoreResult:
    """Store *reading* once inside the caller's transaction (the caller commits).

    Raises :class:`ClientIdConflictError` when the client id is taken by a different payload and
    :class:`ReferenceNotFoundError` when ``panel_id`` names no panel; a reading with panel metadata
    (``panel``) names the lowest-id panel with the same job, part, substrate and notes, created in this
    transaction when there is none. *instrument_cache* (serial → id,
    owned by the caller) saves the instrument upsert for instruments already seen; instrument rows are
    never deleted, so an entry cannot go stale. The common case is then one ``INSERT … RETURNING``.
    """
    values = _values(
        session,
        reading,
        created_by_id=created_by_id,
        supersedes_id=supersedes_id,
        correction_reason=correction_reason,
        instrument_cache=instrument_cache,
    )
    sha = values["payload_sha256"]
    head = chain.lock_head(session, "measurements")  # serialises appends until the caller commits
    received_at = chain.chain_time(head)
    values["received_at"] = received_at
    row_sha256, link = chain.seal("measurements", head, values)
    values["row_sha256"], values["chain_sha256"] = row_sha256, link
    try:
        new_id = session.execute(_measurement_insert(session.get_bind().dialect.name), values).scalar()
    except IntegrityError as exc:  # e.g. supersedes_id already superseded, or a vanished reference
        raise ReferenceNotFoundError(f"reading refused by a database constraint: {exc.orig}") from exc
    if new_id is not None:
        chain.advance(session, "measurements", head, link, received_at)
    if new_id is None:  # stored before (a re-send, a replay, or a concurrent writer)
        row = session.execute(
            select(Measurement.id, Measurement.payload_sha256).where(
                Measurement.client_id == reading.client_id
            )
        ).one()
        if row.payload_sha256 != sha:
            raise ClientIdConflictError(str(reading.client_id), row.payload_sha256, sha)
        return StoreResult(row.id, created=False)
    return StoreResult(new_id, created=True, row=values)


#: The stored rows among some client ids, and ids for new rows from the table's sequence (PostgreSQL text).
_PG_STORED = "SELECT client_id, id, payload_sha256 FROM measurements WHERE client_id = ANY(%(ids)s)"
_PG_NEW_IDS = "SELECT nextval(pg_get_serial_sequence('measurements', 'id')) FROM generate_series(1, %(n)s)"

#: What :func:`store_readings` appends with each new reading: a row of another chain (the audit event),
#: from the new measurement id, the reading and its ``created_by_id``.
Companion = Callable[[int, Reading, "int | None"], Mapping[str, Any]]


def store_readings(
    session: Session,
    readings: Sequence[tuple[Reading, int | None]],
    *,
    instrument_cache: dict[str, int] | None = None,
    audit: Companion | None = None,
) -> list[StoreResult]:
    """Store each ``(reading, created_by_id)`` once inside the caller's transaction, in order, and with
    each new one its audit event (*audit*: the event's columns, appended to the ``audit_events`` chain):
    the outcomes of :func:`store_reading` (and :func:`db.chain.append_audit`) called on each in turn,
    with the same rows and chains.

    On PostgreSQL, three round trips in all, however many readings: the heads are locked, the client
    ids already stored looked up and ids for the new rows drawn from the table's sequence in one; every
    new row, event and head move appended in a second (:func:`db.chain.append_many`); the caller's
    commit. Raises as :func:`store_reading` does for a refused reading (the caller rolls back). A
    client id twice among *readings* is stored one reading at a time.
    """
    ids = [reading.client_id for reading, _ in readings]
    if session.get_bind().dialect.name != "postgresql" or len(set(ids)) != len(ids):
        results: list[StoreResult] = []
        for reading, by in readings:
            result = store_reading(session, reading, created_by_id=by, instrument_cache=instrument_cache)
            if result.created and audit is not None:
                chain.append_audit(session, audit(result.measurement_id, reading, by))
            results.append(result)
        return results
    values = [
        _values(session, reading, created_by_id=by, instrument_cache=instrument_cache)
        for reading, by in readings
    ]
    # the look-up runs once the heads are locked: no writer can store one of these ids meanwhile
    _head, (found, drawn) = chain.lock_head_with(
        session, "measurements", [(_PG_STORED, {"ids": ids}), (_PG_NEW_IDS, {"n": len(readings)})]
    )
    stored = {client_id: (int(row_id), sha) for client_id, row_id, sha in found}
    new_ids = iter(sorted(int(row_id) for (row_id,) in drawn))
    fresh: list[dict[str, Any]] = []
    events: list[Mapping[str, Any]] = []
    for (reading, by), row in zip(readings, values, strict=True):
        old = stored.get(reading.client_id)
        if old is not None:
            if old[1] != row["payload_sha256"]:
                raise ClientIdConflictError(str(reading.client_id), old[1], row["payload_sha256"])
            continue
        row["id"] = next(new_ids)
        fresh.append(row)
        if audit is not None:
            events.append(audit(row["id"], reading, by))
    try:
        appended = chain.append_many(session, {"measurements": fresh, "audit_events": events})
    except IntegrityError as exc:  # e.g. a vanished reference, as store_reading says it
        raise ReferenceNotFoundError(f"reading refused by a database constraint: {exc.orig}") from exc
    rows = iter(appended.get("measurements", []))
    results = []
    for reading, _by in readings:
        old = stored.get(reading.client_id)
        if old is not None:
            results.append(StoreResult(old[0], created=False))
        else:
            new_id, row = next(rows)
            del row["id"]  # the row as store_reading reports it: its id aside
            results.append(StoreResult(new_id, created=True, row=row))
    return results


#: The fields of a :class:`Reading` that are not ``measurements`` columns of the same name: references the
#: store resolves (panel, instrument, calibration) and the raw payload (in the hash, not kept).
_NOT_COLUMNS: Final = {"instrument", "calibration", "panel_id", "panel", "raw_payload_b64"}


def reading_columns(reading: Reading) -> dict[str, Any]:
    """The ``measurements`` columns that *reading* fills by itself (its panel, instrument, calibration,
    chain and correction columns aside): client id, operator, instant, colorimetric conditions, Lab,
    spectra, gloss, illumination block, texture and the payload hash."""
    return reading.model_dump(exclude=_NOT_COLUMNS) | {"payload_sha256": reading.payload_sha256()}


def _values(
    session: Session,
    reading: Reading,
    *,
    created_by_id: int | None,
    supersedes_id: int | None = None,
    correction_reason: str | None = None,
    instrument_cache: dict[str, int] | None,
) -> dict[str, Any]:
    """The measurement row of *reading* before the chain dates and seals it (panel, instrument and
    calibration resolved: found, or created in this transaction)."""
    panel_id = _panel_id(session, reading, created_by_id)
    instrument_id = _instrument_id(session, reading, instrument_cache)
    calibration_id = _calibration_id(session, reading, instrument_id)
    return dict(
        **reading_columns(reading),
        panel_id=panel_id,
        instrument_id=instrument_id,
        calibration_id=calibration_id,
        supersedes_id=supersedes_id,
        correction_reason=correction_reason,
        created_by_id=created_by_id,
    )
