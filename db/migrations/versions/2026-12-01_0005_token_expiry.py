"""Bearer tokens expire: ``api_tokens.expires_at`` (UTC; tokens issued before this revision get 90 days from now).

Backfilling from the upgrade moment rather than from ``created_at`` keeps every working token (the
bootstrap admin's included) working for the default lifetime, instead of expiring old ones at once.
Revoking one token sets ``revoked_at``, which the first schema already has.

Revision ID: 0005_token_expiry
Revises: 0004_hash_chain
Create Date: 2026-12-01 18:00:00
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0005_token_expiry"
down_revision: str | Sequence[str] | None = "0004_hash_chain"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

BACKFILL = dt.timedelta(days=90)


def upgrade() -> None:
    with op.batch_alter_table("api_tokens") as batch:
        batch.add_column(sa.Column("expires_at", sa.DateTime(timezone=True), nullable=True))
    expires = dt.datetime.now(dt.UTC) + BACKFILL
    if op.get_bind().dialect.name == "sqlite":  # stored as naive UTC, as db.base.UTCDateTime does
        expires = expires.replace(tzinfo=None)
    op.get_bind().execute(
        sa.text("UPDATE api_tokens SET expires_at = :at WHERE expires_at IS NULL"), {"at": expires}
    )


def downgrade() -> None:
    with op.batch_alter_table("api_tokens") as batch:
        batch.drop_column("expires_at")
