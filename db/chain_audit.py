"""Checkpoints of the hash chains and :func:`audit_database`: every chain, record seal and checkpoint checked.

**Checkpoints** (:func:`write_checkpoint`) are lines appended to a file in the data folder outside the
database, HMAC-SHA256-signed with a key kept next to it (mode 0600): each records every chain's length
and head. :func:`audit_database` names a chain that holds fewer rows than a checkpoint recorded or a
different link at a checkpointed length (a tail removed and the head rewound), and a line whose
signature does not recompute.

**Records** (``db.chain.RECORD_TABLES``): every row of those tables is compared with its last
``record_events`` event: a row changed, inserted or deleted outside the product is named.

**Time**: a row dated beyond the verifier's clock plus ``db.chain.MAX_CLOCK_SKEW`` is named, and a row
earlier than its last plausible predecessor.

:func:`audit_database` reports every finding (:class:`Finding`), not only the first.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import hmac
import json
import os
import secrets
from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

from sqlalchemy import Connection, select
from sqlalchemy.engine import RowMapping
from sqlalchemy.orm import Session
from sqlalchemy.sql.expression import TableClause

from db.base import utcnow
from db.chain import (
    CHAINS,
    GENESIS,
    HEADS,
    MAX_CLOCK_SKEW,
    READING_CHAINS,
    RECORD_TABLES,
    TIME_COLUMN,
    Chain,
    _record_table,
    chain_table,
    state_sha256,
)
from db.chain_hash import legacy_hashes, link_sha256, payload_sha256

#: Files of the data folder: the signed checkpoints (one JSON object a line) and the key (0600).
CHECKPOINT_FILE = "chain-checkpoints.jsonl"
CHECKPOINT_KEY_FILE = "chain-checkpoint.key"


# --- checkpoints --------------------------------------------------------------------------------------


def _create_private(path: Path, data: bytes) -> None:
    """Create *path* with *data*, mode 0600, failing if anything (a link included) is already there.

    The bytes are written to a private file beside it first and then linked into place, so a reader
    never finds *path* before it holds the whole of *data*.
    """
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(8)}")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    try:
        try:
            os.write(fd, data)
            os.fsync(fd)
        finally:
            os.close(fd)
        os.link(tmp, path)  # atomic; FileExistsError when someone else's is already there
    finally:
        tmp.unlink(missing_ok=True)


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
    """The checkpoint key of the data *folder* (32 random bytes, hex in a 0600 file); made when *create*.

    ``None`` when there is none (and not *create*); ``ValueError`` naming the file when it does not hold
    a whole key (64 hex digits), which is never used to sign or check a checkpoint.
    """
    path = folder / CHECKPOINT_KEY_FILE
    data = _read_regular(path)
    if data is None and create:
        try:
            _create_private(path, secrets.token_hex(32).encode("ascii") + b"\n")
        except FileExistsError:
            pass  # another process made it first
        data = _read_regular(path)
    if data is None:
        return None
    text = data.decode("ascii", "replace").strip()
    try:
        key = bytes.fromhex(text)
    except ValueError:
        key = b""
    if len(key) != 32:
        raise ValueError(
            f"checkpoint key {path.name}: not a whole key (64 hex digits), {len(text)} characters"
        )
    return key


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


@dataclass
class _Walk:
    """Where a walk along one chain stands: the last link and time, rows seen, the last id."""

    previous: str = GENESIS
    previous_at: dt.datetime | None = None
    count: int = 0
    last_id: int | None = None


def _read_head(conn: Connection | Session, chain: Chain) -> tuple[RowMapping | None, int, int]:
    """*chain*'s head row, the last id back-filled out of time order and the last id hashed with form 1."""
    head_cols = [HEADS.c.length, HEADS.c.head_sha256, HEADS.c.backfill_last_id]
    has_legacy = "legacy_last_id" in _head_columns(conn)
    if has_legacy:
        head_cols.append(HEADS.c.legacy_last_id)
    head = (
        conn.execute(select(*head_cols).select_from(HEADS).where(HEADS.c.chain == chain)).mappings().first()
    )
    unordered_through = int(head["backfill_last_id"] or 0) if head is not None else 0
    legacy_through = int(head["legacy_last_id"] or 0) if head is not None and has_legacy else 1 << 62
    return head, unordered_through, legacy_through


def _check_row_hashes(
    chain: Chain, row: RowMapping, previous: str, legacy: bool, found: list[Finding]
) -> bool:
    """Name a changed payload or a broken link of *row*; whether its payload hash matches."""
    rid = int(row["id"])
    try:
        same = _row_matches(chain, row, legacy)
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
    return same


def _check_row_time(
    chain: Chain, row: RowMapping, walk: _Walk, future_limit: dt.datetime, ordered: bool, found: list[Finding]
) -> None:
    """Name a row dated in the future, or (when *ordered*) earlier than its predecessor; move the walk's time."""
    rid, time_col = int(row["id"]), TIME_COLUMN[chain]
    at = row[time_col]
    if at is None:
        return
    if at > future_limit:
        found.append(
            Finding(chain, "future", rid, f"{chain} id {rid}: {time_col} {at.isoformat()} is in the future")
        )
        return
    if ordered and walk.previous_at is not None and at < walk.previous_at:
        found.append(
            Finding(
                chain,
                "backdated",
                rid,
                f"{chain} id {rid}: {time_col} {at.isoformat()} earlier than its predecessor",
            )
        )
    walk.previous_at = at if walk.previous_at is None or at > walk.previous_at else walk.previous_at


def _check_tail(
    chain: Chain,
    head: RowMapping | None,
    marks: Mapping[int, list[Checkpoint]],
    walk: _Walk,
    found: list[Finding],
) -> None:
    """Name a chain shorter than a checkpoint recorded, and a head that does not end on its last row."""
    count, last_id = walk.count, walk.last_id
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
    elif int(head["length"]) == count and head["head_sha256"] != walk.previous:
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


def _verify_chain(
    conn: Connection | Session,
    chain: Chain,
    report: Report,
    checkpoints: list[Checkpoint],
    now: dt.datetime,
    batch: int,
    records: dict[tuple[str, str], tuple[str, str | None]] | None = None,
) -> None:
    """Walk *chain* in id order, adding every finding to *report* (and each sealed record's last event
    to *records*, for ``record_events``)."""
    found = report.findings
    head, unordered_through, legacy_through = _read_head(conn, chain)
    marks: dict[int, list[Checkpoint]] = {}
    for cp in checkpoints:
        if chain in cp.chains:
            marks.setdefault(cp.chains[chain][0], []).append(cp)
    for cp in marks.get(0, []):
        if cp.chains[chain][1] != GENESIS:
            found.append(_mismatch(chain, cp, None))
    walk = _Walk()
    future_limit = now + MAX_CLOCK_SKEW
    for row in _rows_by_id(conn, chain_table(chain), batch):
        rid = int(row["id"])
        walk.count += 1
        walk.last_id = rid
        if row["row_sha256"] is None or row["chain_sha256"] is None:
            found.append(
                Finding(chain, "unhashed", rid, f"{chain} id {rid}: no hash (written around the chain)")
            )
            continue
        same = _check_row_hashes(chain, row, walk.previous, rid <= legacy_through, found)
        for cp in marks.get(walk.count, []):
            if cp.chains[chain][1] != row["chain_sha256"]:
                found.append(_mismatch(chain, cp, rid))
        # rows back-filled by the migration kept their old times
        _check_row_time(chain, row, walk, future_limit, rid > unordered_through, found)
        if records is not None and same:
            records[(str(row["entity"]), str(row["entity_id"]))] = (str(row["op"]), row["state_sha256"])
        walk.previous = row["chain_sha256"]
    report.rows[chain] = walk.count
    report.heads[chain] = walk.previous
    _check_tail(chain, head, marks, walk, found)


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
