"""Gloss readings are stored on their own (``gloss_readings``), append-only like measurements.

A 20/60/85° gloss meter reading (with haze, log haze, DOI and Rspec) is one row, gloss-only or naming
the colour measurement of the same panel it was taken with (``measurement_id``). UPDATE and DELETE are
refused by triggers as revision 0002 does for measurements (PostgreSQL reuses its
``cacad_refuse_change()`` function).

Revision ID: 0007_gloss_readings
Revises: 0006_qc_standards
Create Date: 2026-12-01 20:40:00
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0007_gloss_readings"
down_revision: str | Sequence[str] | None = "0006_qc_standards"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

TABLE = "gloss_readings"


def upgrade() -> None:
    op.create_table(
        TABLE,
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("client_id", sa.Uuid(), nullable=False),
        sa.Column("panel_id", sa.Integer(), nullable=True),
        sa.Column("measurement_id", sa.Integer(), nullable=True),
        sa.Column("instrument_id", sa.Integer(), nullable=False),
        sa.Column("calibration_id", sa.Integer(), nullable=True),
        sa.Column("operator", sa.String(length=64), nullable=False),
        sa.Column("measured_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("received_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("gloss_20_gu", sa.Double(), nullable=True),
        sa.Column("gloss_60_gu", sa.Double(), nullable=True),
        sa.Column("gloss_85_gu", sa.Double(), nullable=True),
        sa.Column("haze_hu", sa.Double(), nullable=True),
        sa.Column("log_haze", sa.Double(), nullable=True),
        sa.Column("doi", sa.Double(), nullable=True),
        sa.Column("rspec_gu", sa.Double(), nullable=True),
        sa.Column("payload_sha256", sa.String(length=64), nullable=False),
        sa.Column("created_by_id", sa.Integer(), nullable=True),
        sa.CheckConstraint(
            "gloss_20_gu IS NOT NULL OR gloss_60_gu IS NOT NULL OR gloss_85_gu IS NOT NULL",
            name=op.f("ck_gloss_readings_some_gloss"),
        ),
        sa.ForeignKeyConstraint(
            ["calibration_id"],
            ["calibration_records.id"],
            name=op.f("fk_gloss_readings_calibration_id_calibration_records"),
        ),
        sa.ForeignKeyConstraint(
            ["created_by_id"], ["users.id"], name=op.f("fk_gloss_readings_created_by_id_users")
        ),
        sa.ForeignKeyConstraint(
            ["instrument_id"], ["instruments.id"], name=op.f("fk_gloss_readings_instrument_id_instruments")
        ),
        sa.ForeignKeyConstraint(
            ["measurement_id"],
            ["measurements.id"],
            name=op.f("fk_gloss_readings_measurement_id_measurements"),
        ),
        sa.ForeignKeyConstraint(["panel_id"], ["panels.id"], name=op.f("fk_gloss_readings_panel_id_panels")),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_gloss_readings")),
        sa.UniqueConstraint("client_id", name=op.f("uq_gloss_readings_client_id")),
    )
    for column in ("panel_id", "measurement_id", "instrument_id", "measured_at"):
        op.create_index(op.f(f"ix_gloss_readings_{column}"), TABLE, [column], unique=False)
    if op.get_bind().dialect.name == "postgresql":
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


def downgrade() -> None:
    if op.get_bind().dialect.name == "postgresql":
        op.execute(f"DROP TRIGGER IF EXISTS tr_{TABLE}_append_only ON {TABLE}")
    else:
        for action in ("UPDATE", "DELETE"):
            op.execute(f"DROP TRIGGER IF EXISTS tr_{TABLE}_no_{action.lower()}")
    for column in ("panel_id", "measurement_id", "instrument_id", "measured_at"):
        op.drop_index(op.f(f"ix_gloss_readings_{column}"), table_name=TABLE)
    op.drop_table(TABLE)
