"""Records sealed on their own chain, canonical numbers, and a chain head only a linked row can move.

* ``record_events`` (append-only, hash-chained like audit events): one event per insert, update and
  delete the product makes to users, API tokens, instruments, calibration records, panels, standards
  and gloss readings (``db.chain.RECORD_TABLES``), holding the hash of the row as the change left it.
  The rows already stored get one ``insert`` event each, sealed as they are now.
* ``ledger_heads.legacy_last_id``: the last id of each chain hashed before canonical numbers (form 1,
  which kept the sign of −0.0); ``db.chain`` verifies those rows with form 1 as well.
* The head rule: an UPDATE of ``ledger_heads`` must end the head on the chain table's last row (and, on
  PostgreSQL, with SHA-256(old head ‖ that row's hash) as its link and that row's time as its time), so
  a role that may write rows cannot move a head past rows that do not link.

Revision ID: 0009_chain_records
Revises: 0008_measurement_texture
Create Date: 2026-12-05 02:40:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

from db.chain import GENESIS, HEADS, READING_CHAINS, RECORD_TABLES, TIME_COLUMN, Chain, record_change

revision: str = "0009_chain_records"
down_revision: str | Sequence[str] | None = "0008_measurement_texture"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

TABLE = "record_events"
CHAIN_TABLES: tuple[Chain, ...] = ("measurements", "audit_events", "record_events")
_HEAD_RULE = "ledger_heads only moves forward one row at a time"


def _pg_head_function(with_rows: bool) -> str:
    """``cacad_head_forward()``: revision 0004's rule, and with *with_rows* the rule of this revision."""
    legacy = " OR NEW.legacy_last_id IS DISTINCT FROM OLD.legacy_last_id" if with_rows else ""
    rows = ""
    if with_rows:
        branches = " ".join(
            f"{'IF' if i == 0 else 'ELSIF'} NEW.chain = '{t}' THEN SELECT row_sha256, chain_sha256, {TIME_COLUMN[t]} "
            f"INTO last_row, last_link, last_at FROM {t} ORDER BY id DESC LIMIT 1;"
            for i, t in enumerate(CHAIN_TABLES)
        )
        rows = (
            f"{branches} END IF; "
            "IF last_link IS NULL OR NEW.head_sha256 IS DISTINCT FROM last_link "
            "OR last_link IS DISTINCT FROM encode(sha256(convert_to(OLD.head_sha256 || last_row, 'UTF8')), 'hex') "
            "OR NEW.head_at IS DISTINCT FROM last_at THEN "
            f"RAISE EXCEPTION '{_HEAD_RULE}, onto the last row of its chain' USING ERRCODE = 'restrict_violation'; "
            "END IF; "
        )
    declare = "DECLARE last_row text; last_link text; last_at timestamptz; " if with_rows else ""
    return (
        "CREATE OR REPLACE FUNCTION cacad_head_forward() RETURNS trigger LANGUAGE plpgsql AS $$ "
        f"{declare}BEGIN "
        "IF TG_OP = 'DELETE' OR NEW.chain <> OLD.chain OR NEW.length <> OLD.length + 1 "
        f"OR NEW.backfill_last_id IS DISTINCT FROM OLD.backfill_last_id{legacy} THEN RAISE EXCEPTION '{_HEAD_RULE}' "
        "USING ERRCODE = 'restrict_violation'; END IF; "
        f"{rows}"
        "IF TG_OP = 'DELETE' THEN RETURN OLD; END IF; RETURN NEW; END $$"
    )


def _sqlite_head_trigger(with_rows: bool) -> str:
    when = "NEW.chain <> OLD.chain OR NEW.length <> OLD.length + 1 OR NEW.backfill_last_id IS NOT OLD.backfill_last_id"
    if with_rows:
        last = " ".join(
            f"WHEN '{t}' THEN (SELECT chain_sha256 FROM {t} ORDER BY id DESC LIMIT 1)" for t in CHAIN_TABLES
        )
        when += f" OR NEW.legacy_last_id IS NOT OLD.legacy_last_id OR NEW.head_sha256 IS NOT (CASE NEW.chain {last} END)"
    return (
        f"CREATE TRIGGER tr_ledger_heads_forward BEFORE UPDATE ON ledger_heads WHEN {when} "
        f"BEGIN SELECT RAISE(ABORT, '{_HEAD_RULE}'); END"
    )


def _append_only(pg: bool) -> None:
    if pg:
        op.execute(
            f"CREATE TRIGGER tr_{TABLE}_append_only BEFORE UPDATE OR DELETE ON {TABLE} "
            "FOR EACH ROW EXECUTE FUNCTION cacad_refuse_change()"
        )
        return
    for action in ("UPDATE", "DELETE"):
        op.execute(
            f"CREATE TRIGGER tr_{TABLE}_no_{action.lower()} BEFORE {action} ON {TABLE} "
            f"BEGIN SELECT RAISE(ABORT, '{TABLE} is append-only: {action} refused'); END"
        )


def upgrade() -> None:
    conn = op.get_bind()
    pg = conn.dialect.name == "postgresql"
    op.create_table(
        TABLE,
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("entity", sa.String(length=32), nullable=False),
        sa.Column("entity_id", sa.String(length=64), nullable=False),
        sa.Column("op", sa.String(length=8), nullable=False),
        sa.Column("state_sha256", sa.String(length=64), nullable=True),
        sa.Column("row_sha256", sa.String(length=64), nullable=True),
        sa.Column("chain_sha256", sa.String(length=64), nullable=True),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_record_events")),
    )
    _append_only(pg)
    op.add_column("ledger_heads", sa.Column("legacy_last_id", sa.Integer(), nullable=True))
    if pg:
        op.execute("ALTER TABLE ledger_heads DISABLE TRIGGER tr_ledger_heads_forward")
    else:
        op.execute("DROP TRIGGER IF EXISTS tr_ledger_heads_forward")
    for chain in READING_CHAINS:
        last = conn.execute(sa.text(f"SELECT max(id) FROM {chain}")).scalar()
        conn.execute(sa.update(HEADS).where(HEADS.c.chain == chain).values(legacy_last_id=last))
    conn.execute(HEADS.insert().values(chain=TABLE, length=0, head_sha256=GENESIS, head_at=None))
    present = set(sa.inspect(conn).get_table_names())
    for name in RECORD_TABLES:  # the records stored so far, sealed as they are now
        if name not in present:
            continue
        columns = {c["name"] for c in sa.inspect(conn).get_columns(name)}
        for (row_id,) in conn.execute(sa.text(f"SELECT id FROM {name} ORDER BY id")).all():
            record_change(conn, name, int(row_id), "insert", columns=columns)
    if pg:
        op.execute("ALTER TABLE ledger_heads ENABLE TRIGGER tr_ledger_heads_forward")
        op.execute(_pg_head_function(with_rows=True))
    else:
        op.execute(_sqlite_head_trigger(with_rows=True))


def downgrade() -> None:
    conn = op.get_bind()
    pg = conn.dialect.name == "postgresql"
    if pg:
        op.execute("ALTER TABLE ledger_heads DISABLE TRIGGER tr_ledger_heads_forward")
    else:
        op.execute("DROP TRIGGER IF EXISTS tr_ledger_heads_forward")
        op.execute("DROP TRIGGER IF EXISTS tr_ledger_heads_no_delete")
    conn.execute(sa.delete(HEADS).where(HEADS.c.chain == TABLE))
    if pg:
        op.execute(_pg_head_function(with_rows=False))
    op.drop_column("ledger_heads", "legacy_last_id")
    if pg:
        op.execute("ALTER TABLE ledger_heads ENABLE TRIGGER tr_ledger_heads_forward")
        op.execute(f"DROP TRIGGER IF EXISTS tr_{TABLE}_append_only ON {TABLE}")
    else:
        op.execute(_sqlite_head_trigger(with_rows=False))
        op.execute(
            "CREATE TRIGGER tr_ledger_heads_no_delete BEFORE DELETE ON ledger_heads "
            f"BEGIN SELECT RAISE(ABORT, '{_HEAD_RULE}'); END"
        )
        for action in ("update", "delete"):
            op.execute(f"DROP TRIGGER IF EXISTS tr_{TABLE}_no_{action}")
    op.drop_table(TABLE)
