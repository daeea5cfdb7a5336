"""Measurements keep their illumination block and the instrument's vendor texture values.

``measurements.illumination_deg`` (degrees, not null, 45 for every row written before: the only block
stored until now) lets both illumination blocks of an MA-T12-style reading be stored, one row each;
``measurements.texture`` (JSON, null before) holds the vendor-tagged sparkle and graininess values. Both
enter the row hash only when they differ from 45 and null (``db.chain.OPTIONAL_COLUMNS``), so the rows
already chained keep their hashes. Adding columns fires no row trigger, so the append-only triggers stay.

Revision ID: 0008_measurement_texture
Revises: 0007_gloss_readings
Create Date: 2026-12-01 21:50:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

from db.base import JSONType

revision: str = "0008_measurement_texture"
down_revision: str | Sequence[str] | None = "0007_gloss_readings"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

TABLE = "measurements"
INDEX = "ix_measurements_illumination_deg"


def upgrade() -> None:
    op.add_column(
        TABLE, sa.Column("illumination_deg", sa.Double(), nullable=False, server_default=sa.text("45"))
    )
    op.add_column(TABLE, sa.Column("texture", JSONType, nullable=True))
    op.create_index(INDEX, TABLE, ["illumination_deg"], unique=False)


def downgrade() -> None:
    op.drop_index(INDEX, table_name=TABLE)
    op.drop_column(TABLE, "texture")
    op.drop_column(TABLE, "illumination_deg")
