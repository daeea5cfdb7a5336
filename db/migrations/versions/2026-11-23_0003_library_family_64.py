"""Library paint family holds the full hierarchy path (e.g. ``metallics+pearls/chromatic/yellow``): 64 chars.

A batch operation: on SQLite the table is rebuilt (copy, drop, rename) with the named constraints of the
naming convention kept; on PostgreSQL it is a plain ``ALTER COLUMN … TYPE``. Downgrading truncates
nothing silently: it refuses when a longer value is stored.

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-23 06:15:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0003"
down_revision: str | Sequence[str] | None = "0002"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("library_paints") as batch:
        batch.alter_column(
            "family", existing_type=sa.String(32), type_=sa.String(64), existing_nullable=False
        )


def downgrade() -> None:
    longest = op.get_bind().execute(sa.text("SELECT max(length(family)) FROM library_paints")).scalar()
    if longest is not None and longest > 32:
        raise RuntimeError(f"cannot downgrade: a library family is {longest} characters long (limit 32)")
    with op.batch_alter_table("library_paints") as batch:
        batch.alter_column(
            "family", existing_type=sa.String(64), type_=sa.String(32), existing_nullable=False
        )
