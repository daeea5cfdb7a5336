"""Hash chains over the append-only tables, record seals, checkpoints and :func:`audit_database`.

Three chains: ``measurements``, ``audit_events`` and ``record_events``. Each row carries ``row_sha256``,
the SHA-256 of its canonical payload (the columns of :data:`PAYLOAD_COLUMNS` as sorted-key JSON, UTC ISO
timestamps with microseconds, numbers of float and JSON columns as floats), and ``chain_sha256`` =
SHA-256(previous row's ``chain_sha256`` ‖ ``row_sha256``), hex strings, the first row chaining from
:data:`GENESIS`. The chain runs in id order. ``ledger_heads`` holds one row per chain with its length,
last link and last write time; it is the lock every writer takes before appending (all heads at once, in
one ``SELECT … FOR UPDATE``, so two writers never wait on each other crosswise), so concurrent writers
form one chain. The database refuses a head that does not end on the table's last row (and, on
PostgreSQL, one whose link is not SHA-256(old head ‖ that row's hash)): revision 0009.

**Canonical numbers** (form 2, every row written from revision 0009 on): a number in a float or JSON
column is hashed as the shortest round-trip repr of the IEEE double (``json``'s), integers as floats,
and −0.0 as 0.0 (SQLite's REAL and PostgreSQL's JSONB both store −0.0 as 0). Rows written before
(``id <= ledger_heads.legacy_last_id``) were hashed with form 1, which kept the sign of zero: they
verify against form 2, form 1, or form 1 with the sign of some zeros restored (at most
:data:`LEGACY_ZERO_SIGNS` zeros, the signs the storage dropped).

**Records** that are not readings but matter (users and their roles, API tokens, instruments,
calibration records, panels, standards, gloss readings: :data:`RECORD_TABLES`) are sealed through the
``record_events`` chain: every insert, update and delete the product makes appends one event
``(entity, entity_id, op, state_sha256)`` where ``state_sha256`` is the hash of the row's whole content
as stored (:func:`state_sha256`) and null for a delete. ORM writes are sealed by a flush hook; Core
writes call :func:`record_change`. :func:`audit_database` compares every row of those tables with its
last event: a row changed, inserted or deleted outside the product is named.

**Time** (``received_at``, ``at``) is written by the chain, never ahead of the clock: the next row takes
now, or the head's time when the clock is behind it by at most :data:`MAX_CLOCK_SKEW` (a small NTP step);
a head further ahead (a row dated in the future) is not carried forward. :func:`audit_database` names a
row dated beyond its own clock plus the skew, and a row earlier than its last plausible predecessor.

**Checkpoints** (:func:`write_checkpoint`) are lines appended to a file in the data folder outside the
database, HMAC-SHA256-signed with a key kept next to it (mode 0600): each records every chain's length
and head. :func:`audit_database` names a chain that holds fewer rows than a checkpoint recorded or a
different link at a checkpointed length (a tail removed and the head rewound), and a line whose
signature does not recompute.

:func:`audit_database` reports every finding (:class:`Finding`), not only the first.
"""

from __future__ import annotations

import datetime as dt
import functools
import hashlib
import hmac
import itertools
import json
import os
import secrets
import uuid
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

from sqlalchemy import (
    Boolean,
    Connection,
    Float,
    Integer,
    String,
    Table,
    Text,
    Uuid,
    bindparam,
    column,
    event,
    select,
    table,
    update,
)
from sqlalchemy.engine import Dialect, RowMapping
from sqlalchemy.orm import Session, UOWTransaction
from sqlalchemy.sql.expression import TableClause
from sqlalchemy.types import JSON, TypeEngine

import db.models  # noqa: F401  (registers every table the chain seals)
from db.base import Base, JSONType, UTCDateTime, utcnow
from station.model.domain import ILLUMINATION_DEG

Chain = Literal["measurements", "audit_events", "record_events"]
#: Every chain, in the order their head rows are locked (one statement, sorted by name).
CHAINS: tuple[Chain, ...] = ("audit_events", "measurements", "record_events")
#: The chains of revision 0004 (before ``record_events``).
READING_CHAINS: tuple[Chain, ...] = ("measurements", "audit_events")
GENESIS = "0" * 64
#: The column of each chain that the chain keeps monotonic (the write time).
TIME_COLUMN: dict[Chain, str] = {"measurements": "received_at", "audit_events": "at", "record_events": "at"}
#: The JSON-typed payload columns; their numbers are hashed as floats (JSON number round-trips differ).
JSON_COLUMNS = frozenset({"geometries_deg", "lab", "wavelengths_nm", "spectra", "texture", "detail"})
#: Floating-point payload columns: hashed as floats whether the writer passed 60 or 60.0.
FLOAT_COLUMNS = frozenset({"gloss_gu", "gloss_geometry_deg", "illumination_deg"})
#: How far (s) the chain's time may run ahead of the writer's clock and still be carried forward, and
#: how far ahead of the verifier's clock a row may be dated before it is named.
MAX_CLOCK_SKEW = dt.timedelta(seconds=300)
#: The most zeros of a form-1 row whose signs :func:`audit_database` tries to restore (2**n hashes).
LEGACY_ZERO_SIGNS = 10
#: Tables sealed through ``record_events`` (mutable or not: any UPDATE or DELETE outside the product shows).
RECORD_TABLES: tuple[str, ...] = (
    "users",
    "api_tokens",
    "instruments",
    "calibration_records",
    "panels",
    "standards",
    "gloss_readings",
)
RECORD_OPS: tuple[str, ...] = ("insert", "update", "delete")
#: Files of the data folder: the signed checkpoints (one JSON object a line) and the key (0600).
CHECKPOINT_FILE = "chain-checkpoints.jsonl"
CHECKPOINT_KEY_FILE = "chain-checkpoint.key"

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
    "op": String,
    "state_sha256": String,
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
    "record_events": ("at", "entity", "entity_id", "op", "state_sha256"),
}
#: Payload columns added after the chain: name → the value rows written before the column existed read.
#: A row's payload holds such a column only when its value differs from that value (a row without the
#: column, e.g. during revision 0004's back-fill, reads it too).
OPTIONAL_COLUMNS: dict[Chain, dict[str, Any]] = {
    "measurements": {"illumination_deg": ILLUMINATION_DEG, "texture": None},
    "audit_events": {},
    "record_events": {},
}

HEADS: TableClause = table(
    "ledger_heads",
    column("chain", String),
    column("length", Integer),
    column("head_sha256", String),
    column("head_at", UTCDateTime),
    column("backfill_last_id", Integer),
    column("legacy_last_id", Integer),  # revision 0009: the last id hashed with canonical form 1
)


def chain_table(chain: Chain, *, optional: bool = True) -> TableClause:
    """A lightweight table of *chain* with its id, payload columns and hashes (typed for round-trips).

    *optional*: with the :data:`OPTIONAL_COLUMNS` (``False`` for a migration that runs before they exist).
    """
    extra = tuple(OPTIONAL_COLUMNS[chain]) if optional else ()
    names = ("id", *PAYLOAD_COLUMNS[chain], *extra, "row_sha256", "chain_sha256")
    return table(chain, *(column(n, _TYPES[n]) for n in names))


# --- canonical form -----------------------------------------------------------------------------------


def _number(value: float, form: int) -> float:
    """A number as hashed: a float; form 2 also folds −0.0 into 0.0."""
    number = float(value)
    return 0.0 if form >= 2 and number == 0.0 else number


def _floats(value: Any, form: int = 2) -> Any:
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        return _number(value, form)
    if isinstance(value, Mapping):
        return {str(k): _floats(v, form) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_floats(v, form) for v in value]
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


def _canonical(name: str, value: Any, form: int = 2) -> Any:
    return _floats(value, form) if name in JSON_COLUMNS or name in FLOAT_COLUMNS else _scalar(value)


def _digest(payload: Mapping[str, Any]) -> str:
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _payload(chain: Chain, row: Mapping[Any, Any], form: int) -> dict[str, Any]:
    payload = {name: _canonical(name, row[name], form) for name in PAYLOAD_COLUMNS[chain]}
    for name, old in OPTIONAL_COLUMNS[chain].items():
        value = _canonical(name, row.get(name, old), form)
        if value != _canonical(name, old, form):
            payload[name] = value
    return payload


def payload_sha256(chain: Chain, row: Mapping[Any, Any], *, form: int = 2) -> str:
    """SHA-256 (hex) of the canonical payload of *row* (a mapping with every payload column).

    An optional column (:data:`OPTIONAL_COLUMNS`) enters the payload only when *row* holds it with a
    value other than its old-row value. *form* 1 is the form of rows written before revision 0009.
    """
    return _digest(_payload(chain, row, form))


def _zero_paths(value: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    if isinstance(value, float) and value == 0.0:
        yield path
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _zero_paths(v, (*path, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _zero_paths(v, (*path, i))


def _negated(payload: Any, path: tuple[Any, ...]) -> Any:
    if not path:
        return -0.0
    head, rest = path[0], path[1:]
    if isinstance(payload, dict):
        return {k: (_negated(v, rest) if k == head else v) for k, v in payload.items()}
    return [(_negated(v, rest) if i == head else v) for i, v in enumerate(payload)]


def legacy_hashes(chain: Chain, row: Mapping[Any, Any]) -> Iterator[str]:
    """The form-1 hashes *row* may have been written with: as read, then with the sign of zeros restored.

    Form 1 hashed −0.0 as ``-0.0``; the storage returns 0.0, so the sign is tried back on every subset of
    the row's zeros (none when it holds more than :data:`LEGACY_ZERO_SIGNS`).
    """
    payload = _payload(chain, row, 1)
    yield _digest(payload)
    zeros = list(_zero_paths(payload))
    if len(zeros) > LEGACY_ZERO_SIGNS:
        return
    for size in range(1, len(zeros) + 1):
        for subset in itertools.combinations(zeros, size):
            signed: Any = payload
            for path in subset:
                signed = _negated(signed, path)
            yield _digest(signed)


def link_sha256(previous: str, row_sha256: str) -> str:
    """SHA-256 (hex) of the previous link followed by this row's payload hash (both hex)."""
    return hashlib.sha256((previous + row_sha256).encode("ascii")).hexdigest()


# --- appending ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Head:
    """The end of one chain: how many rows, the last link and the last write time."""

    length: int
    sha256: str
    at: dt.datetime | None


#: Where a transaction keeps the heads it locked (``Connection.info``; see :func:`lock_head`).
_HEADS_INFO = "db.chain.heads"

#: Every chain's head row, locked for the transaction (one statement, by name, built once).
_LOCK_HEADS = (
    select(HEADS.c.chain, HEADS.c.length, HEADS.c.head_sha256, HEADS.c.head_at)
    .where(HEADS.c.chain.in_(CHAINS))
    .order_by(HEADS.c.chain)
    .with_for_update()
)
#: Move one chain's head (parameters bound per call: ``c_chain``, ``length``, ``head_sha256``, ``head_at``).
_ADVANCE = (
    update(HEADS)
    .where(HEADS.c.chain == bindparam("c_chain"))
    .values(length=bindparam("length"), head_sha256=bindparam("head_sha256"), head_at=bindparam("head_at"))
)


def _transaction_key(conn: Connection) -> tuple[object, object]:
    """The database transaction *conn* is in now: its root transaction and innermost savepoint."""
    return (conn.get_transaction(), conn.get_nested_transaction())


def _connection(session: Session | Connection) -> Connection:
    return session.connection() if isinstance(session, Session) else session


def lock_head(session: Session | Connection, chain: Chain) -> Head:
    """Lock every chain's head row for this transaction (one statement, by name) and return *chain*'s.

    The heads are read once per database transaction (and savepoint): the rows stay locked until it
    ends, and :func:`advance` keeps the copy current, so a later call in the same transaction reads the
    copy instead of the database. A transaction that moves a head some other way must not call this
    afterwards (no product code does; the database refuses a head that does not follow its table).
    """
    conn = _connection(session)
    kept = conn.info.get(_HEADS_INFO)
    if kept is not None and kept[0] == _transaction_key(conn) and chain in kept[1]:
        head: Head = kept[1][chain]
        return head
    rows = conn.execute(_LOCK_HEADS).all()
    heads = {row.chain: Head(int(row.length), str(row.head_sha256), row.head_at) for row in rows}
    key = _transaction_key(conn)  # after the statement: it began the transaction when none was open
    conn.info[_HEADS_INFO] = (key, heads) if key[0] is not None else None
    if chain not in heads:
        raise LookupError(f"ledger_heads has no row for {chain}: is the database migrated?")
    return heads[chain]


def chain_time(head: Head, now: dt.datetime | None = None) -> dt.datetime:
    """The write time of the next row after *head* (UTC).

    *now* (default: the clock); the head's time instead when the clock is behind it by no more than
    :data:`MAX_CLOCK_SKEW`; a head further ahead (dated in the future) is not carried forward.
    """
    now = utcnow() if now is None else now
    if head.at is None or now >= head.at or head.at - now > MAX_CLOCK_SKEW:
        return now
    return head.at


def seal(chain: Chain, head: Head, row: Mapping[Any, Any]) -> tuple[str, str]:
    """``(row_sha256, chain_sha256)`` of *row* appended after *head*."""
    row_hash = payload_sha256(chain, row)
    return row_hash, link_sha256(head.sha256, row_hash)


def advance(session: Session | Connection, chain: Chain, head: Head, link: str, at: dt.datetime) -> Head:
    """Move *chain*'s head past one appended row (call after the row is inserted); the new head."""
    new = Head(head.length + 1, link, at)
    conn = _connection(session)
    conn.execute(
        _ADVANCE, {"c_chain": chain, "length": new.length, "head_sha256": new.sha256, "head_at": new.at}
    )
    kept = conn.info.get(_HEADS_INFO)
    if kept is not None and kept[0] == _transaction_key(conn):
        kept[1][chain] = new
    return new


@functools.cache
def _chain_insert(chain: Chain) -> Any:
    """``INSERT … RETURNING id`` into *chain* (every payload column, optional ones included, and the hashes)."""
    tbl = chain_table(chain)
    return tbl.insert().returning(tbl.c.id)


def _append(session: Session | Connection, chain: Chain, values: Mapping[str, Any]) -> int:
    head = lock_head(session, chain)
    row = dict(values)
    row[TIME_COLUMN[chain]] = chain_time(head)
    row_hash, link = seal(chain, head, row)
    row["row_sha256"], row["chain_sha256"] = row_hash, link
    new_id = session.execute(_chain_insert(chain), row).scalar_one()
    advance(session, chain, head, link, row[TIME_COLUMN[chain]])
    return int(new_id)


def append_audit(session: Session | Connection, values: Mapping[str, Any]) -> int:
    """Insert one audit event (``actor_id``, ``action``, ``entity``, ``entity_id``, ``detail``) on the chain; its id."""
    return _append(session, "audit_events", values)


def append_many(
    session: Session | Connection, batches: Mapping[Chain, Sequence[Mapping[str, Any]]]
) -> dict[Chain, list[tuple[int, dict[str, Any]]]]:
    """Append each chain's rows, in order (each row: its payload columns, the time column left to the
    chain, as :func:`append_audit` takes one; an ``id`` may be given, from the table's sequence);
    ``(id, row as inserted)`` of each, time and hashes included, by chain.

    The same rows, hashes, times and head moves as one append per row (each row inserted, then its
    chain's head moved onto it: the database's head rule), under the same lock (:func:`lock_head`).
    On PostgreSQL every insert and head move travels in one pipeline: one round trip for all of them
    instead of two per row. The rows of one chain must hold the same columns.
    """
    conn = _connection(session)
    sealed: dict[Chain, list[tuple[dict[str, Any], Head]]] = {}
    for chain, rows in batches.items():
        if not rows:
            continue
        head = lock_head(session, chain)
        sealed[chain] = []
        for values in rows:
            row = dict(values)
            at = chain_time(head)
            row[TIME_COLUMN[chain]] = at
            row_hash, link = seal(chain, head, row)
            row["row_sha256"], row["chain_sha256"] = row_hash, link
            head = Head(head.length + 1, link, at)
            sealed[chain].append((row, head))
    if conn.dialect.name == "postgresql":
        ids = _pipelined_append(conn, sealed)
        kept = conn.info.get(_HEADS_INFO)
        if kept is not None and kept[0] == _transaction_key(conn):
            for chain, rows_heads in sealed.items():
                kept[1][chain] = rows_heads[-1][1]
    else:
        ids = {}
        for chain, rows_heads in sealed.items():
            ids[chain] = []
            for row, new in rows_heads:
                ids[chain].append(int(session.execute(_chain_insert(chain), row).scalar_one()))
                advance(session, chain, lock_head(session, chain), new.sha256, row[TIME_COLUMN[chain]])
    return {
        chain: [(new_id, row) for new_id, (row, _) in zip(ids[chain], rows_heads, strict=True)]
        for chain, rows_heads in sealed.items()
    }


#: :data:`_LOCK_HEADS` as PostgreSQL text, for a pipeline.
_PG_LOCK_HEADS = (
    "SELECT chain, length, head_sha256, head_at FROM ledger_heads WHERE chain IN ("
    + ", ".join(f"'{c}'" for c in CHAINS)
    + ") ORDER BY chain FOR UPDATE"
)
#: :data:`_ADVANCE` as PostgreSQL text (psycopg's named placeholders), for a pipeline.
_PG_ADVANCE = (
    "UPDATE ledger_heads SET length = %(length)s, head_sha256 = %(head_sha256)s, head_at = %(head_at)s "
    "WHERE ledger_heads.chain = %(c_chain)s"
)


def lock_head_with(
    session: Session | Connection, chain: Chain, queries: Sequence[tuple[str, Mapping[str, Any]]]
) -> tuple[Head, list[list[tuple[Any, ...]]]]:
    """PostgreSQL only: :func:`lock_head`, then *queries* (driver text with psycopg's named placeholders,
    and their parameters) in the same transaction, all in one round trip (a pipeline); *chain*'s head
    and each query's rows. A query runs once the heads are locked: it sees every row a writer that
    held the lock before committed."""
    conn = _connection(session)
    if conn.dialect.name != "postgresql":
        raise NotImplementedError("lock_head_with pipelines PostgreSQL statements")
    kept = conn.info.get(_HEADS_INFO)
    locked = kept is not None and kept[0] == _transaction_key(conn) and chain in kept[1]
    statements: list[tuple[str, Mapping[str, Any]]] = [] if locked else [(_PG_LOCK_HEADS, {})]
    statements += queries
    results = _pipelined(conn, statements)
    if not locked:
        heads = {
            str(name): Head(int(length), str(sha), None if at is None else at.astimezone(dt.UTC))
            for name, length, sha, at in results.pop(0)
        }
        conn.info[_HEADS_INFO] = (_transaction_key(conn), heads)
        if chain not in heads:
            raise LookupError(f"ledger_heads has no row for {chain}: is the database migrated?")
    return lock_head(session, chain), results


def _pipelined(
    conn: Connection, statements: Sequence[tuple[str, Mapping[str, Any]]]
) -> list[list[tuple[Any, ...]]]:
    """Run *statements* in one psycopg pipeline on *conn*'s transaction; each one's rows (``[]`` for
    one that returns none). A driver error is raised as SQLAlchemy's wrapped error
    (``OperationalError`` for a lost server, ``IntegrityError`` for a refused row), as
    :meth:`Connection.execute` raises it."""
    from sqlalchemy.exc import DBAPIError

    driver: Any = conn.connection.driver_connection
    dbapi_error = conn.dialect.loaded_dbapi.Error
    cursors = []
    try:
        with driver.pipeline():
            for sql, params in statements:
                cursors.append(driver.execute(sql, params))
        return [cursor.fetchall() if cursor.description is not None else [] for cursor in cursors]
    except dbapi_error as exc:
        raise DBAPIError.instance(statements[0][0], None, exc, dbapi_error) from exc
    finally:
        for cursor in cursors:
            cursor.close()


@functools.cache
def _pg_insert(chain: Chain, names: tuple[str, ...]) -> str:
    """``INSERT INTO chain (names) VALUES (…) RETURNING id`` as PostgreSQL text (psycopg's named placeholders)."""
    columns = ", ".join(names)
    values = ", ".join(f"%({n})s" for n in names)
    return f"INSERT INTO {chain} ({columns}) VALUES ({values}) RETURNING id"


@functools.lru_cache(maxsize=64)
def _bind_processors(dialect: Dialect, chain: Chain, names: tuple[str, ...]) -> tuple[tuple[str, Any], ...]:
    """``(column, processor or None)`` per column: SQLAlchemy's own conversion of each value for the driver."""
    tbl = chain_table(chain)
    return tuple((n, tbl.c[n].type.dialect_impl(dialect).bind_processor(dialect)) for n in names)


def _pipelined_append(
    conn: Connection, sealed: Mapping[Chain, Sequence[tuple[dict[str, Any], Head]]]
) -> dict[Chain, list[int]]:
    """Insert each sealed row and move its chain's head onto it, all in one pipeline; the new ids."""
    statements: list[tuple[str, Mapping[str, Any]]] = []
    for chain, rows_heads in sealed.items():
        names = tuple(rows_heads[0][0])
        sql = _pg_insert(chain, names)
        processors = _bind_processors(conn.dialect, chain, names)
        for row, head in rows_heads:
            statements.append((sql, {n: row[n] if p is None else p(row[n]) for n, p in processors}))
            statements.append(
                (
                    _PG_ADVANCE,
                    {"c_chain": chain, "length": head.length, "head_sha256": head.sha256, "head_at": head.at},
                )
            )
    results = iter(_pipelined(conn, statements)[::2])  # each insert's RETURNING row
    return {chain: [int(next(results)[0][0]) for _ in rows_heads] for chain, rows_heads in sealed.items()}


# --- records ------------------------------------------------------------------------------------------


def _record_table(name: str) -> Table:
    return Base.metadata.tables[name]


def _state_value(kind: TypeEngine[Any], value: Any) -> Any:
    if isinstance(kind, (JSON,)) or isinstance(getattr(kind, "impl", None), JSON):
        return _floats(value)
    if isinstance(value, bool) or isinstance(kind, Boolean):
        return bool(value)
    if isinstance(value, float) or isinstance(kind, Float):
        return _number(value, 2)
    return _scalar(value)


def state_sha256(name: str, row: Mapping[Any, Any]) -> str:
    """SHA-256 (hex) of one row of the record table *name* as stored: every column but null ones.

    A null column is left out, so a nullable column added later keeps the hashes of rows sealed before.
    """
    tbl = _record_table(name)
    payload = {
        c.name: _state_value(c.type, row[c.name])
        for c in tbl.columns
        if c.name in row and row[c.name] is not None
    }
    return _digest({"table": name, "row": payload})


def record_change(
    session: Session | Connection, name: str, row_id: int, op: str, *, columns: set[str] | None = None
) -> int:
    """Seal one change the product made to a row of *name* (:data:`RECORD_TABLES`): append its event.

    *op* is ``insert``, ``update`` (the row as it now is, read in this transaction) or ``delete``;
    *columns*: only these columns exist yet (a migration that runs before later ones). Returns the event id.
    """
    if name not in RECORD_TABLES or op not in RECORD_OPS:
        raise ValueError(f"record_change: {name!r} {op!r} is not a sealed table and operation")
    state = None
    if op != "delete":
        tbl = _record_table(name)
        cols = [c for c in tbl.columns if columns is None or c.name in columns]
        row = session.execute(select(*cols).where(tbl.c.id == row_id)).mappings().one()
        state = state_sha256(name, row)
    return _append(
        session, "record_events", {"entity": name, "entity_id": str(row_id), "op": op, "state_sha256": state}
    )


@event.listens_for(Session, "after_flush")
def _seal_flushed(session: Session, _context: UOWTransaction) -> None:
    """Seal the record rows the ORM just inserted, updated or deleted (ids are known after the flush)."""
    changes: list[tuple[str, int, str]] = []
    for objects, op in ((session.new, "insert"), (session.dirty, "update"), (session.deleted, "delete")):
        for obj in objects:
            name = getattr(getattr(obj, "__table__", None), "name", None)
            if name not in RECORD_TABLES:
                continue
            if op == "update" and not session.is_modified(obj, include_collections=False):
                continue
            changes.append((str(name), int(obj.id), op))
    if changes:
        conn = session.connection()
        for name, row_id, op in sorted(changes, key=lambda c: (RECORD_OPS.index(c[2]), c[0], c[1])):
            record_change(conn, name, row_id, op)


# --- checkpoints --------------------------------------------------------------------------------------


def _create_private(path: Path, data: bytes) -> None:
    """Create *path* with *data*, mode 0600, failing if anything (a link included) is already there."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    try:
        os.write(fd, data)
        os.fsync(fd)
    finally:
        os.close(fd)


def _read_regular(path: Path) -> bytes | None:
    """The bytes of *path* when it is a regular file (not a link); ``None`` when absent."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    except FileNotFoundError:
        return None
    try:
        with os.fdopen(fd, "rb", closefd=False) as f:
            return f.read()
    finally:
        os.close(fd)


def checkpoint_key(folder: Path, *, create: bool) -> bytes | None:
    """The checkpoint key of the data *folder* (32 random bytes, hex in a 0600 file); made when *create*."""
    path = folder / CHECKPOINT_KEY_FILE
    data = _read_regular(path)
    if data is None and create:
        try:
            _create_private(path, secrets.token_hex(32).encode("ascii") + b"\n")
        except FileExistsError:
            pass  # another process made it first
        data = _read_regular(path)
    return None if data is None else bytes.fromhex(data.decode("ascii").strip())


def database_identity(url: str) -> str:
    """The name checkpoints give a database: the SQLite file's absolute path, or host:port/name."""
    from sqlalchemy.engine import make_url

    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        return f"sqlite:{Path(parsed.database or '').resolve()}"
    return f"{parsed.get_backend_name()}:{parsed.host}:{parsed.port or 5432}/{parsed.database}"


def _signature(key: bytes, body: Mapping[str, Any]) -> str:
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hmac.new(key, text.encode("ascii"), hashlib.sha256).hexdigest()


def write_checkpoint(source: Connection | Session | Report, folder: Path, database: str) -> dict[str, Any]:
    """Append one signed checkpoint of every chain's length and head to *folder*'s checkpoint file.

    *source*: a :class:`Report` (the heads it verified) or a connection (the committed heads, read now).
    *database* is :func:`database_identity` of the database. The key is made on first use. Returns the
    line written (without its signature).
    """
    key = checkpoint_key(folder, create=True)
    if key is None:  # made just now, then removed by someone else
        raise FileNotFoundError(folder / CHECKPOINT_KEY_FILE)
    if isinstance(source, Report):
        chains = {c: {"length": source.rows[c], "head_sha256": source.heads[c]} for c in sorted(source.rows)}
    else:
        heads = source.execute(
            select(HEADS.c.chain, HEADS.c.length, HEADS.c.head_sha256).where(HEADS.c.chain.in_(CHAINS))
        ).all()
        chains = {str(h.chain): {"length": int(h.length), "head_sha256": str(h.head_sha256)} for h in heads}
    body: dict[str, Any] = {
        "database": database,
        "at": utcnow().isoformat(timespec="microseconds"),
        "chains": chains,
    }
    line = json.dumps({**body, "hmac": _signature(key, body)}, sort_keys=True, separators=(",", ":"))
    fd = os.open(folder / CHECKPOINT_FILE, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o600)
    try:
        os.write(fd, (line + "\n").encode("ascii"))
        os.fsync(fd)
    finally:
        os.close(fd)
    return body


@dataclass(frozen=True)
class Checkpoint:
    """One signed checkpoint line: when, and each chain's length and head link then."""

    line: int
    at: str
    chains: dict[str, tuple[int, str]]


# --- verification -------------------------------------------------------------------------------------

FindingKind = Literal[
    "unhashed",
    "row_changed",
    "link_broken",
    "backdated",
    "future",
    "head_mismatch",
    "rewound",
    "checkpoint_mismatch",
    "checkpoint_invalid",
    "record_changed",
    "record_unsealed",
    "record_missing",
]


@dataclass(frozen=True)
class Finding:
    """One break: the chain or table, its kind, the row id (``None``: the chain as a whole), in words."""

    chain: str
    kind: FindingKind
    id: int | None
    message: str

    def as_dict(self) -> dict[str, Any]:
        """The finding as a JSON object (``chain``, ``kind``, ``id``, ``message``)."""
        return asdict(self)


@dataclass(frozen=True)
class Verdict:
    """Result of :func:`verify` for one chain: rows checked and the first finding (``None``: intact)."""

    chain: Chain
    rows: int
    broken: str | None = None
    head_sha256: str = GENESIS


@dataclass
class Report:
    """Result of :func:`audit_database`: rows and head of each chain, checkpoints read, every finding."""

    rows: dict[str, int] = field(default_factory=dict)
    heads: dict[str, str] = field(default_factory=dict)
    checkpoints: int = 0
    findings: list[Finding] = field(default_factory=list)

    @property
    def intact(self) -> bool:
        """No finding at all."""
        return not self.findings


def read_checkpoints(folder: Path | None, database: str) -> tuple[list[Checkpoint], list[Finding]]:
    """The checkpoints of *database* in *folder*'s file, and a finding for each line that is not genuine."""
    if folder is None:
        return [], []
    try:
        data = _read_regular(folder / CHECKPOINT_FILE)
        key = checkpoint_key(folder, create=False) if data is not None else None
    except (OSError, ValueError) as exc:  # a link, a folder, an unreadable or mangled key
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        return [], [
            Finding("checkpoints", "checkpoint_invalid", None, f"{CHECKPOINT_FILE}: cannot be read ({why})")
        ]
    if data is None:
        return [], []
    found: list[Checkpoint] = []
    bad: list[Finding] = []
    for number, raw in enumerate(data.decode("utf-8", "replace").splitlines(), start=1):
        if not raw.strip():
            continue
        try:
            obj = json.loads(raw)
            body = {k: obj[k] for k in ("database", "at", "chains")}
            genuine = key is not None and hmac.compare_digest(str(obj["hmac"]), _signature(key, body))
            chains = {str(c): (int(v["length"]), str(v["head_sha256"])) for c, v in body["chains"].items()}
        except (ValueError, KeyError, TypeError, AttributeError):
            genuine, chains, body = False, {}, {"database": database, "at": ""}
        if not genuine:
            why = "no key to check it with" if key is None else "its signature does not recompute"
            bad.append(
                Finding("checkpoints", "checkpoint_invalid", None, f"{CHECKPOINT_FILE} line {number}: {why}")
            )
        elif body["database"] == database:
            found.append(Checkpoint(number, str(body["at"]), chains))
    return found, bad


def _row_matches(chain: Chain, row: Mapping[Any, Any], legacy: bool) -> bool:
    stored = row["row_sha256"]
    if payload_sha256(chain, row) == stored:
        return True
    return legacy and any(h == stored for h in legacy_hashes(chain, row))


def _rows_by_id(conn: Connection | Session, tbl: TableClause, batch: int) -> Iterator[RowMapping]:
    """Every row of *tbl* in id order, read *batch* rows at a time (keyset pages: no OFFSET scans)."""
    last_id: int | None = None
    while True:
        query = select(tbl).order_by(tbl.c.id).limit(batch)
        if last_id is not None:
            query = query.where(tbl.c.id > last_id)
        rows = conn.execute(query).mappings().all()
        if not rows:
            return
        yield from rows
        last_id = int(rows[-1]["id"])


def _verify_chain(
    conn: Connection | Session,
    chain: Chain,
    report: Report,
    checkpoints: list[Checkpoint],
    now: dt.datetime,
    batch: int,
    records: dict[tuple[str, str], tuple[str, str | None]] | None = None,
) -> None:
    tbl = chain_table(chain)
    time_col = TIME_COLUMN[chain]
    found = report.findings
    head_cols = [HEADS.c.length, HEADS.c.head_sha256, HEADS.c.backfill_last_id]
    has_legacy = "legacy_last_id" in _head_columns(conn)
    if has_legacy:
        head_cols.append(HEADS.c.legacy_last_id)
    head = (
        conn.execute(select(*head_cols).select_from(HEADS).where(HEADS.c.chain == chain)).mappings().first()
    )
    unordered_through = int(head["backfill_last_id"] or 0) if head is not None else 0
    legacy_through = int(head["legacy_last_id"] or 0) if head is not None and has_legacy else 1 << 62
    marks: dict[int, list[Checkpoint]] = {}
    for cp in checkpoints:
        if chain in cp.chains:
            marks.setdefault(cp.chains[chain][0], []).append(cp)
    for cp in marks.get(0, []):
        if cp.chains[chain][1] != GENESIS:
            found.append(_mismatch(chain, cp, None))
    previous, previous_at, count, last_id = GENESIS, None, 0, None
    future_limit = now + MAX_CLOCK_SKEW
    for row in _rows_by_id(conn, tbl, batch):
        rid = int(row["id"])
        count += 1
        last_id = rid
        if row["row_sha256"] is None or row["chain_sha256"] is None:
            found.append(
                Finding(chain, "unhashed", rid, f"{chain} id {rid}: no hash (written around the chain)")
            )
            continue
        try:
            same = _row_matches(chain, row, rid <= legacy_through)
        except (ValueError, TypeError):  # a value no writer of the product stores (NaN …)
            same = False
        if not same:
            found.append(
                Finding(chain, "row_changed", rid, f"{chain} id {rid}: payload hash differs (row changed)")
            )
        if link_sha256(previous, row["row_sha256"]) != row["chain_sha256"]:
            found.append(
                Finding(
                    chain,
                    "link_broken",
                    rid,
                    f"{chain} id {rid}: link to the previous row differs (row removed or inserted)",
                )
            )
        for cp in marks.get(count, []):
            if cp.chains[chain][1] != row["chain_sha256"]:
                found.append(_mismatch(chain, cp, rid))
        at = row[time_col]
        if at is not None and at > future_limit:
            found.append(
                Finding(
                    chain,
                    "future",
                    rid,
                    f"{chain} id {rid}: {time_col} {at.isoformat()} is in the future",
                )
            )
        elif at is not None:
            late = rid > unordered_through  # rows back-filled by the migration kept their old times
            if late and previous_at is not None and at < previous_at:
                found.append(
                    Finding(
                        chain,
                        "backdated",
                        rid,
                        f"{chain} id {rid}: {time_col} {at.isoformat()} earlier than its predecessor",
                    )
                )
            previous_at = at if previous_at is None or at > previous_at else previous_at
        if records is not None and same:
            records[(str(row["entity"]), str(row["entity_id"]))] = (str(row["op"]), row["state_sha256"])
        previous = row["chain_sha256"]
    report.rows[chain] = count
    report.heads[chain] = previous
    for length, cps in sorted(marks.items()):
        if length > count:
            cp = cps[-1]
            found.append(
                Finding(
                    chain,
                    "rewound",
                    None,
                    f"{chain}: checkpoint of {cp.at} (line {cp.line}) recorded {length} rows, "
                    f"the table holds {count} (rows removed after id {last_id})",
                )
            )
    if head is None:
        found.append(Finding(chain, "head_mismatch", None, f"{chain}: head row missing from ledger_heads"))
    elif int(head["length"]) == count and head["head_sha256"] != previous:
        found.append(
            Finding(
                chain,
                "head_mismatch",
                None,
                f"{chain}: the last row is not the one the head records (rows replaced)",
            )
        )
    elif int(head["length"]) != count:
        found.append(
            Finding(
                chain,
                "head_mismatch",
                None,
                f"{chain}: head records {head['length']} rows, table holds {count} "
                + (
                    f"(rows removed after id {last_id})"
                    if int(head["length"]) > count
                    else "(rows appended without moving the head)"
                ),
            )
        )


def _mismatch(chain: Chain, cp: Checkpoint, rid: int | None) -> Finding:
    length = cp.chains[chain][0]
    return Finding(
        chain,
        "checkpoint_mismatch",
        rid,
        f"{chain}: row {length} is not the one the checkpoint of {cp.at} (line {cp.line}) recorded "
        "(rows replaced since)",
    )


def _head_columns(conn: Connection | Session) -> set[str]:
    from sqlalchemy import inspect

    bind = conn.connection() if isinstance(conn, Session) else conn
    return {c["name"] for c in inspect(bind).get_columns("ledger_heads")}


def _verify_records(
    conn: Connection | Session,
    report: Report,
    records: dict[tuple[str, str], tuple[str, str | None]],
    batch: int,
) -> None:
    from sqlalchemy import inspect

    bind = conn.connection() if isinstance(conn, Session) else conn
    present = set(inspect(bind).get_table_names())
    seen: set[tuple[str, str]] = set()
    for name in RECORD_TABLES:
        if name not in present:
            continue
        tbl = _record_table(name)
        for row in _rows_by_id(conn, tbl, batch):
            row_id = int(row["id"])
            key = (name, str(row_id))
            seen.add(key)
            sealed = records.get(key)
            if sealed is None or sealed[0] == "delete":
                report.findings.append(
                    Finding(
                        name,
                        "record_unsealed",
                        row_id,
                        f"{name} id {row_id}: no record event (written around the product)",
                    )
                )
            elif sealed[1] != state_sha256(name, row):
                report.findings.append(
                    Finding(
                        name,
                        "record_changed",
                        row_id,
                        f"{name} id {row_id}: differs from its last record event (changed outside the product)",
                    )
                )
    for (name, rid), (op, _state) in sorted(records.items()):
        if op != "delete" and (name, rid) not in seen and name in present:
            report.findings.append(
                Finding(
                    name,
                    "record_missing",
                    int(rid),
                    f"{name} id {rid}: sealed but gone (deleted outside the product)",
                )
            )


def audit_database(
    conn: Connection | Session,
    *,
    checkpoint_folder: Path | None = None,
    database: str | None = None,
    now: dt.datetime | None = None,
    batch: int = 1000,
) -> Report:
    """Verify every chain, every sealed record table and the checkpoints of *checkpoint_folder*.

    *database*: :func:`database_identity` of the database (the checkpoints of other databases in the
    folder are skipped); *now*: the verifier's clock (rows dated beyond it plus the skew are named).
    Reads in batches of *batch* rows; returns a :class:`Report` holding every finding.
    """
    from sqlalchemy import inspect

    report = Report()
    checkpoints, bad = read_checkpoints(checkpoint_folder, database or "")
    report.checkpoints = len(checkpoints)
    report.findings.extend(bad)
    now = utcnow() if now is None else now
    bind = conn.connection() if isinstance(conn, Session) else conn
    present = set(inspect(bind).get_table_names())
    records: dict[tuple[str, str], tuple[str, str | None]] = {}
    for chain in (*READING_CHAINS, "record_events"):
        if chain in present:
            _verify_chain(
                conn, chain, report, checkpoints, now, batch, records if chain == "record_events" else None
            )
    if "record_events" in present:
        _verify_records(conn, report, records, batch)
    return report


def verify_chain(conn: Connection | Session, chain: Chain, *, batch: int = 1000) -> Verdict:
    """Recompute *chain* in id order and compare with the stored hashes and the head row (first finding)."""
    report = Report()
    _verify_chain(conn, chain, report, [], utcnow(), batch)
    first = next((f.message for f in report.findings), None)
    return Verdict(chain, report.rows.get(chain, 0), first, report.heads.get(chain, GENESIS))


def verify(conn: Connection | Session) -> list[Verdict]:
    """Verify the reading chains (measurements, then audit events); see :func:`audit_database` for all."""
    return [verify_chain(conn, chain) for chain in READING_CHAINS]
