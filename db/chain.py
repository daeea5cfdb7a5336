"""Hash chains over the append-only tables: heads, appends and record seals.

Three chains: ``measurements``, ``audit_events`` and ``record_events``. Each row carries ``row_sha256``,
the SHA-256 of its canonical payload, and ``chain_sha256`` = SHA-256(previous row's ``chain_sha256`` ‖
``row_sha256``), hex strings, the first row chaining from :data:`GENESIS` (the canonical form and the
hashes: ``db.chain_hash``). The chain runs in id order. ``ledger_heads`` holds one row per chain with its
length, last link and last write time; it is the lock every writer takes before appending (all heads at
once, in one ``SELECT … FOR UPDATE``, so two writers never wait on each other crosswise), so concurrent
writers form one chain. The database refuses a head that does not end on the table's last row (and, on
PostgreSQL, one whose link is not SHA-256(old head ‖ that row's hash)): revision 0009.

**Records** that are not readings but matter (users and their roles, API tokens, instruments,
calibration records, panels, standards, gloss readings: :data:`RECORD_TABLES`) are sealed through the
``record_events`` chain: every insert, update and delete the product makes appends one event
``(entity, entity_id, op, state_sha256)`` where ``state_sha256`` is the hash of the row's whole content
as stored (:func:`state_sha256`) and null for a delete. ORM writes are sealed by a flush hook; Core
writes call :func:`record_change`.

**Time** (``received_at``, ``at``) is written by the chain, never ahead of the clock: the next row takes
now, or the head's time when the clock is behind it by at most :data:`MAX_CLOCK_SKEW` (a small NTP step);
a head further ahead (a row dated in the future) is not carried forward.

Checkpoints and the audit of every chain, seal and checkpoint: ``db.chain_audit``.
"""

from __future__ import annotations

import datetime as dt
import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

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
from sqlalchemy.engine import Dialect
from sqlalchemy.orm import Session, UOWTransaction
from sqlalchemy.sql.expression import TableClause
from sqlalchemy.types import JSON, TypeEngine

import db.models  # noqa: F401  (registers every table the chain seals)
from db.base import Base, JSONType, UTCDateTime, utcnow
from db.chain_hash import (
    FLOAT_COLUMNS,
    JSON_COLUMNS,
    LEGACY_ZERO_SIGNS,
    OPTIONAL_COLUMNS,
    PAYLOAD_COLUMNS,
    Chain,
    _digest,
    _floats,
    _number,
    _scalar,
    legacy_hashes,
    link_sha256,
    payload_sha256,
)

__all__ = [
    "CHAINS",
    "FLOAT_COLUMNS",
    "GENESIS",
    "HEADS",
    "JSON_COLUMNS",
    "LEGACY_ZERO_SIGNS",
    "MAX_CLOCK_SKEW",
    "OPTIONAL_COLUMNS",
    "PAYLOAD_COLUMNS",
    "READING_CHAINS",
    "RECORD_OPS",
    "RECORD_TABLES",
    "TIME_COLUMN",
    "Chain",
    "Head",
    "advance",
    "append_audit",
    "append_many",
    "chain_table",
    "chain_time",
    "legacy_hashes",
    "link_sha256",
    "lock_head",
    "lock_head_with",
    "payload_sha256",
    "record_change",
    "seal",
    "state_sha256",
    "utcnow",
]

#: Every chain, in the order their head rows are locked (one statement, sorted by name).
CHAINS: tuple[Chain, ...] = ("audit_events", "measurements", "record_events")
#: The chains of revision 0004 (before ``record_events``).
READING_CHAINS: tuple[Chain, ...] = ("measurements", "audit_events")
GENESIS = "0" * 64
#: The column of each chain that the chain keeps monotonic (the write time).
TIME_COLUMN: dict[Chain, str] = {"measurements": "received_at", "audit_events": "at", "record_events": "at"}
#: How far (s) the chain's time may run ahead of the writer's clock and still be carried forward, and
#: how far ahead of the verifier's clock a row may be dated before it is named.
MAX_CLOCK_SKEW = dt.timedelta(seconds=300)
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
