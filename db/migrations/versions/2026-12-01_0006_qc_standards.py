"""QC standards: ``standards`` holds the reference of each job and part (a measurement or a design).

One row per (job, part); exactly one of ``measurement_id`` and ``design_id`` is set (check
``ck_standards_one_reference``). Panels already carry job and part, so jobs need no table of their own.

Revision ID: 0006_qc_standards
Revises: 0005_token_expiry
Create Date: 2026-12-01 20:30:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0006_qc_standards"
down_revision: str | Sequence[str] | None = "0005_token_expiry"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

# Frozen here: later changes to db.models.measurements.PARTS must not alter this revision.
_PARTS = (
    "bumper",
    "fender",
    "door",
    "hood",
    "trunk",
    "mirror",
    "roof",
    "quarter_panel",
    "test_panel",
    "other",
)


def upgrade() -> None:
    op.create_table(
        "standards",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("job", sa.String(length=64), nullable=False),
        sa.Column(
            "part",
            sa.Enum(*_PARTS, name="part", native_enum=False, create_constraint=True, length=16),
            nullable=False,
        ),
        sa.Column("measurement_id", sa.Integer(), nullable=True),
        sa.Column("design_id", sa.Integer(), nullable=True),
        sa.Column("notes", sa.Text(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("created_by_id", sa.Integer(), nullable=True),
        sa.CheckConstraint(
            "(measurement_id IS NULL) != (design_id IS NULL)", name=op.f("ck_standards_one_reference")
        ),
        sa.ForeignKeyConstraint(
            ["measurement_id"], ["measurements.id"], name=op.f("fk_standards_measurement_id_measurements")
        ),
        sa.ForeignKeyConstraint(["design_id"], ["designs.id"], name=op.f("fk_standards_design_id_designs")),
        sa.ForeignKeyConstraint(
            ["created_by_id"], ["users.id"], name=op.f("fk_standards_created_by_id_users")
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_standards")),
        sa.UniqueConstraint("job", "part", name=op.f("uq_standards_job_part")),
    )
    op.create_index(op.f("ix_standards_job"), "standards", ["job"], unique=False)


def downgrade() -> None:
    op.drop_index(op.f("ix_standards_job"), table_name="standards")
    op.drop_table("standards")
