"""Hash chains over the append-only tables (measurements, audit events): append and verify.

Each row carries ``row_sha256``, the SHA-256 of its canonical payload (every column but the id and the
two hashes, as sorted-key JSON with UTC ISO timestamps and numbers in JSON and float columns as floats), and
``chain_sha256`` = SHA-256(previous row's ``chain_sha256`` ‖ ``row_sha256``), hex strings, the first row
chaining from :data:`GENESIS`. The chain runs in id order. The table ``ledger_heads`` holds one row per
chain with its length, last hash and last timestamp; it is the lock every writer takes before appending
(``SELECT … FOR UPDATE`` on PostgreSQL; on SQLite ``BEGIN IMMEDIATE`` already serialises writers), so
concurrent writers form one chain. Timestamps written by the chain (``received_at``, ``at``) never go
backwards along it: a writer whose clock is behind the last row takes the last row's time.

:func:`verify` recomputes both chains and names the first broken link: a changed row (payload hash
differs), a removed or inserted row (link differs), a back-dated row (time earlier than its
predecessor; rows written before the chain existed are
exempt, their times are as they were) or a truncated tail (the head says more rows than the table holds).

The payload columns are fixed here (:data:`PAYLOAD_COLUMNS`), not read from the models: a column added
to a chained table later does not change the hash of the rows already written. Columns added later that
enter the hash are :data:`OPTIONAL_COLUMNS`: each is hashed only when its value differs from the value every
row written before it exists reads (``measurements.illumination_deg`` 45°, ``measurements.texture`` null,
revision 0008), so the rows written before keep their hashes and a changed value still breaks the link.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import uuid
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from sqlalchemy import Connection, Float, Integer, String, Text, Uuid, column, select, table, update
from sqlalchemy.orm import Session
from sqlalchemy.sql.expression import TableClause

from db.base import JSONType, UTCDateTime, utcnow
from station.model.domain import ILLUMINATION_DEG

Chain = Literal["measurements", "audit_events"]
CHAINS: tuple[Chain, ...] = ("audit_events", "measurements")  # lock order: always audit first
GENESIS = "0" * 64
#: The column of each chain that the chain keeps monotonic (the write time).
TIME_COLUMN: dict[Chain, str] = {"measurements": "received_at", "audit_events": "at"}
#: The JSON-typed payload columns; their numbers are hashed as floats (JSON number round-trips differ).
JSON_COLUMNS = frozenset({"geometries_deg", "lab", "wavelengths_nm", "spectra", "texture", "detail"})
#: Floating-point payload columns: hashed as floats whether the writer passed 60 or 60.0.
FLOAT_COLUMNS = frozenset({"gloss_gu", "gloss_geometry_deg", "illumination_deg"})

_TYPES: dict[str, Any] = {
    "id": Integer,
    "client_id": Uuid,
    "panel_id": Integer,
    "instrument_id": Integer,
    "calibration_id": Integer,
    "operator": String,
    "measured_at": UTCDateTime,
    "received_at": UTCDateTime,
    "illuminant": String,
    "observer": String,
    "geometries_deg": JSONType,
    "lab": JSONType,
    "wavelengths_nm": JSONType,
    "spectra": JSONType,
    "gloss_gu": Float,
    "gloss_geometry_deg": Float,
    "illumination_deg": Float,
    "texture": JSONType,
    "payload_sha256": String,
    "supersedes_id": Integer,
    "correction_reason": Text,
    "created_by_id": Integer,
    "at": UTCDateTime,
    "actor_id": Integer,
    "action": String,
    "entity": String,
    "entity_id": String,
    "detail": JSONType,
    "row_sha256": String,
    "chain_sha256": String,
}

PAYLOAD_COLUMNS: dict[Chain, tuple[str, ...]] = {
    "measurements": (
        "client_id",
        "panel_id",
        "instrument_id",
        "calibration_id",
        "operator",
        "measured_at",
        "received_at",
        "illuminant",
        "observer",
        "geometries_deg",
        "lab",
        "wavelengths_nm",
        "spectra",
        "gloss_gu",
        "gloss_geometry_deg",
        "payload_sha256",
        "supersedes_id",
        "correction_reason",
        "created_by_id",
    ),
    "audit_events": ("at", "actor_id", "action", "entity", "entity_id", "detail"),
}
#: Payload columns added after the chain: name → the value rows written before the column existed read.
#: A row's payload holds such a column only when its value differs from that value (a row without the
#: column, e.g. during revision 0004's back-fill, reads it too).
OPTIONAL_COLUMNS: dict[Chain, dict[str, Any]] = {
    "measurements": {"illumination_deg": ILLUMINATION_DEG, "texture": None},
    "audit_events": {},
}

HEADS: TableClause = table(
    "ledger_heads",
    column("chain", String),
    column("length", Integer),
    column("head_sha256", String),
    column("head_at", UTCDateTime),
    column("backfill_last_id", Integer),
)


def chain_table(chain: Chain, *, optional: bool = True) -> TableClause:
    """A lightweight table of *chain* with its id, payload columns and hashes (typed for round-trips).

    *optional*: with the :data:`OPTIONAL_COLUMNS` (``False`` for a migration that runs before they exist).
    """
    extra = tuple(OPTIONAL_COLUMNS[chain]) if optional else ()
    names = ("id", *PAYLOAD_COLUMNS[chain], *extra, "row_sha256", "chain_sha256")
    return table(chain, *(column(n, _TYPES[n]) for n in names))


def _floats(value: Any) -> Any:
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, Mapping):
        return {str(k): _floats(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_floats(v) for v in value]
    return value


def _scalar(value: Any) -> Any:
    if isinstance(value, dt.datetime):
        if value.tzinfo is None:
            value = value.replace(tzinfo=dt.UTC)
        return value.astimezone(dt.UTC).isoformat(timespec="microseconds")
    if isinstance(value, uuid.UUID):
        return str(value)
    if hasattr(value, "value") and not isinstance(value, (int, float, str)):  # an enum member
        return value.value
    return value


def _canonical(name: str, value: Any) -> Any:
    return _floats(value) if name in JSON_COLUMNS or name in FLOAT_COLUMNS else _scalar(value)


def payload_sha256(chain: Chain, row: Mapping[Any, Any]) -> str:
    """SHA-256 (hex) of the canonical payload of *row* (a mapping with every payload column).

    An optional column (:data:`OPTIONAL_COLUMNS`) enters the payload only when *row* holds it with a
    value other than its old-row value.
    """
    payload = {name: _canonical(name, row[name]) for name in PAYLOAD_COLUMNS[chain]}
    for name, old in OPTIONAL_COLUMNS[chain].items():
        value = _canonical(name, row.get(name, old))
        if value != _canonical(name, old):
            payload[name] = value
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def link_sha256(previous: str, row_sha256: str) -> str:
    """SHA-256 (hex) of the previous link followed by this row's payload hash (both hex)."""
    return hashlib.sha256((previous + row_sha256).encode("ascii")).hexdigest()


@dataclass(frozen=True)
class Head:
    """The end of one chain: how many rows, the last link and the last write time."""

    length: int
    sha256: str
    at: dt.datetime | None


def lock_head(session: Session | Connection, chain: Chain) -> Head:
    """Lock *chain*'s head row for this transaction (both heads, audit first, for a measurement)."""
    wanted = [c for c in CHAINS if c == chain or chain == "measurements"]
    rows = session.execute(
        select(HEADS.c.chain, HEADS.c.length, HEADS.c.head_sha256, HEADS.c.head_at)
        .where(HEADS.c.chain.in_(wanted))
        .order_by(HEADS.c.chain)
        .with_for_update()
    ).all()
    for row in rows:
        if row.chain == chain:
            return Head(int(row.length), str(row.head_sha256), row.head_at)
    raise LookupError(f"ledger_heads has no row for {chain}: is the database migrated?")


def chain_time(head: Head) -> dt.datetime:
    """The write time of the next row: now, or the head's time when the clock is behind it."""
    now = utcnow()
    return now if head.at is None or now >= head.at else head.at


def seal(chain: Chain, head: Head, row: Mapping[Any, Any]) -> tuple[str, str]:
    """``(row_sha256, chain_sha256)`` of *row* appended after *head*."""
    row_hash = payload_sha256(chain, row)
    return row_hash, link_sha256(head.sha256, row_hash)


def advance(session: Session | Connection, chain: Chain, head: Head, link: str, at: dt.datetime) -> Head:
    """Move *chain*'s head past one appended row (call after the row is inserted)."""
    new = Head(head.length + 1, link, at)
    session.execute(
        update(HEADS)
        .where(HEADS.c.chain == chain)
        .values(length=new.length, head_sha256=new.sha256, head_at=new.at)
    )
    return new


def append_audit(session: Session | Connection, values: Mapping[str, Any]) -> int:
    """Insert one audit event (``actor_id``, ``action``, ``entity``, ``entity_id``, ``detail``) on the chain; its id."""
    head = lock_head(session, "audit_events")
    row = dict(values)
    row["at"] = chain_time(head)
    row_hash, link = seal("audit_events", head, row)
    tbl = chain_table("audit_events")
    new_id = session.execute(
        tbl.insert().values(**row, row_sha256=row_hash, chain_sha256=link).returning(tbl.c.id)
    ).scalar_one()
    advance(session, "audit_events", head, link, row["at"])
    return int(new_id)


@dataclass(frozen=True)
class Verdict:
    """Result of :func:`verify` for one chain: rows checked and the first broken link (``None``: intact)."""

    chain: Chain
    rows: int
    broken: str | None = None
    head_sha256: str = GENESIS


def verify_chain(conn: Connection | Session, chain: Chain, *, batch: int = 1000) -> Verdict:
    """Recompute *chain* in id order and compare with the stored hashes and the head row."""
    tbl = chain_table(chain)
    time_col = TIME_COLUMN[chain]
    backfilled = conn.execute(select(HEADS.c.backfill_last_id).where(HEADS.c.chain == chain)).scalar()
    unordered_through = int(backfilled) if backfilled is not None else 0
    previous, previous_at, count, last_id = GENESIS, None, 0, None
    while True:
        query = select(tbl).order_by(tbl.c.id).limit(batch)
        if last_id is not None:
            query = query.where(tbl.c.id > last_id)
        rows = conn.execute(query).mappings().all()
        if not rows:
            break
        for row in rows:
            rid = row["id"]
            if row["row_sha256"] is None or row["chain_sha256"] is None:
                return Verdict(chain, count, f"{chain} id {rid}: no hash (written around the chain)")
            if payload_sha256(chain, row) != row["row_sha256"]:
                return Verdict(chain, count, f"{chain} id {rid}: payload hash differs (row changed)")
            if link_sha256(previous, row["row_sha256"]) != row["chain_sha256"]:
                return Verdict(
                    chain,
                    count,
                    f"{chain} id {rid}: link to the previous row differs (row removed or inserted)",
                )
            at = row[time_col]
            late = rid > unordered_through  # rows back-filled by the migration kept their old times
            if late and previous_at is not None and at is not None and at < previous_at:
                return Verdict(
                    chain,
                    count,
                    f"{chain} id {rid}: {time_col} {at.isoformat()} earlier than its predecessor",
                )
            previous, previous_at, count, last_id = row["chain_sha256"], at, count + 1, rid
    head = conn.execute(select(HEADS.c.length, HEADS.c.head_sha256).where(HEADS.c.chain == chain)).first()
    if head is None:
        return Verdict(chain, count, f"{chain}: head row missing from ledger_heads")
    if int(head.length) == count and head.head_sha256 != previous:
        return Verdict(chain, count, f"{chain}: the last row is not the one the head records (rows replaced)")
    if int(head.length) != count or head.head_sha256 != previous:
        return Verdict(
            chain,
            count,
            f"{chain}: head records {head.length} rows, table holds {count} (rows removed after id {last_id})",
        )
    return Verdict(chain, count, head_sha256=previous)


def verify(conn: Connection | Session) -> list[Verdict]:
    """Verify every chain (measurements, then audit events)."""
    return [verify_chain(conn, "measurements"), verify_chain(conn, "audit_events")]
