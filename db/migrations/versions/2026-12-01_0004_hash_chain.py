"""Measurements and audit events are hash-chained; ``ledger_heads`` holds each chain's head and lock.

Adds ``row_sha256`` and ``chain_sha256`` to both append-only tables and back-fills the rows already
stored, in id order (the append-only triggers are lifted for the back-fill only, inside this
migration's transaction). ``ledger_heads`` gets one row per chain: its length, last link, last write
time and the last back-filled id (rows up to it keep their old, possibly unordered, times). Its rows
cannot be deleted and move forward one row at a time only (triggers on both backends). See
``db.chain``.

Revision ID: 0004_hash_chain
Revises: 0003
Create Date: 2026-12-01 18:00:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

from db.chain import GENESIS, HEADS, READING_CHAINS, TIME_COLUMN, chain_table, link_sha256, payload_sha256

revision: str = "0004_hash_chain"
down_revision: str | Sequence[str] | None = "0003"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

_HEAD_RULE = "ledger_heads only moves forward one row at a time"


def _lift_triggers(pg: bool) -> None:
    for table in READING_CHAINS:
        if pg:
            op.execute(f"ALTER TABLE {table} DISABLE TRIGGER tr_{table}_append_only")
        else:
            op.execute(f"DROP TRIGGER IF EXISTS tr_{table}_no_update")


def _restore_triggers(pg: bool) -> None:
    for table in READING_CHAINS:
        if pg:
            op.execute(f"ALTER TABLE {table} ENABLE TRIGGER tr_{table}_append_only")
        else:
            op.execute(
                f"CREATE TRIGGER tr_{table}_no_update BEFORE UPDATE ON {table} "
                f"BEGIN SELECT RAISE(ABORT, '{table} is append-only: UPDATE refused'); END"
            )


def _backfill(conn: sa.Connection) -> None:
    for chain in READING_CHAINS:
        tbl = chain_table(chain, optional=False)  # the columns of revision 0008 do not exist yet
        previous, count, last_at, last_id = GENESIS, 0, None, None
        for row in conn.execute(sa.select(tbl).order_by(tbl.c.id)).mappings().all():
            row_hash = payload_sha256(chain, row)
            previous = link_sha256(previous, row_hash)
            conn.execute(
                tbl.update().where(tbl.c.id == row["id"]).values(row_sha256=row_hash, chain_sha256=previous)
            )
            at = row[TIME_COLUMN[chain]]
            last_at = at if last_at is None or (at is not None and at > last_at) else last_at
            count, last_id = count + 1, row["id"]
        conn.execute(
            HEADS.insert().values(
                chain=chain, length=count, head_sha256=previous, head_at=last_at, backfill_last_id=last_id
            )
        )


def upgrade() -> None:
    conn = op.get_bind()
    pg = conn.dialect.name == "postgresql"
    for table in READING_CHAINS:
        op.add_column(table, sa.Column("row_sha256", sa.String(length=64), nullable=True))
        op.add_column(table, sa.Column("chain_sha256", sa.String(length=64), nullable=True))
    op.create_table(
        "ledger_heads",
        sa.Column("chain", sa.String(length=32), nullable=False),
        sa.Column("length", sa.Integer(), nullable=False),
        sa.Column("head_sha256", sa.String(length=64), nullable=False),
        sa.Column("head_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("backfill_last_id", sa.Integer(), nullable=True),
        sa.PrimaryKeyConstraint("chain", name=op.f("pk_ledger_heads")),
    )
    _lift_triggers(pg)
    _backfill(conn)
    _restore_triggers(pg)
    if pg:
        op.execute(
            "CREATE FUNCTION cacad_head_forward() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN "
            "IF TG_OP = 'DELETE' OR NEW.chain <> OLD.chain OR NEW.length <> OLD.length + 1 "
            f"OR NEW.backfill_last_id IS DISTINCT FROM OLD.backfill_last_id THEN RAISE EXCEPTION '{_HEAD_RULE}' "
            "USING ERRCODE = 'restrict_violation'; END IF; "
            "IF TG_OP = 'DELETE' THEN RETURN OLD; END IF; RETURN NEW; END $$"
        )
        op.execute(
            "CREATE TRIGGER tr_ledger_heads_forward BEFORE UPDATE OR DELETE ON ledger_heads "
            "FOR EACH ROW EXECUTE FUNCTION cacad_head_forward()"
        )
        return
    op.execute(
        "CREATE TRIGGER tr_ledger_heads_forward BEFORE UPDATE ON ledger_heads "
        "WHEN NEW.chain <> OLD.chain OR NEW.length <> OLD.length + 1 "
        "OR NEW.backfill_last_id IS NOT OLD.backfill_last_id "
        f"BEGIN SELECT RAISE(ABORT, '{_HEAD_RULE}'); END"
    )
    op.execute(
        "CREATE TRIGGER tr_ledger_heads_no_delete BEFORE DELETE ON ledger_heads "
        f"BEGIN SELECT RAISE(ABORT, '{_HEAD_RULE}'); END"
    )


def downgrade() -> None:
    if op.get_bind().dialect.name == "postgresql":
        op.execute("DROP TRIGGER IF EXISTS tr_ledger_heads_forward ON ledger_heads")
        op.execute("DROP FUNCTION IF EXISTS cacad_head_forward()")
    else:
        op.execute("DROP TRIGGER IF EXISTS tr_ledger_heads_forward")
        op.execute("DROP TRIGGER IF EXISTS tr_ledger_heads_no_delete")
    op.drop_table("ledger_heads")
    for table in READING_CHAINS:
        op.drop_column(table, "chain_sha256")
        op.drop_column(table, "row_sha256")
