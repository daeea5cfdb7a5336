"""Gloss readings: one immutable row per reading of a 20/60/85° gloss meter, gloss-only or paired.

A gloss meter and a multi-angle spectrophotometer are separate instruments; a panel measured on both
gives one colour row (``measurements``) and one gloss row (``gloss_readings``). The gloss row names the
colour measurement it belongs to (``measurement_id``) when the two were taken together; otherwise it
stands alone (gloss-only) and pairs with a colour measurement of the same panel by time
(``station.ingest.gloss.pair_gloss``). Like a measurement, a gloss row is never updated or deleted.

Units: gloss in gloss units (GU, ISO 2813) at 20°, 60° and 85° (any may be absent, at least one is
given); haze in haze units (ASTM E430), log haze in log haze units (0–2000), DOI 0–100, Rspec in GU.
"""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

from sqlalchemy import CheckConstraint, ForeignKey, String, event
from sqlalchemy.orm import Mapped, mapped_column

from db.base import Base, utcnow
from db.errors import ImmutableRowError


class GlossReading(Base):
    """One gloss meter reading: gloss per geometry (GU), haze, log haze, DOI, Rspec and provenance."""

    __tablename__ = "gloss_readings"
    __table_args__ = (
        CheckConstraint(
            "gloss_20_gu IS NOT NULL OR gloss_60_gu IS NOT NULL OR gloss_85_gu IS NOT NULL",
            name="some_gloss",
        ),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    client_id: Mapped[uuid.UUID] = mapped_column(unique=True)
    panel_id: Mapped[int | None] = mapped_column(ForeignKey("panels.id"), index=True)
    measurement_id: Mapped[int | None] = mapped_column(ForeignKey("measurements.id"), index=True)
    instrument_id: Mapped[int] = mapped_column(ForeignKey("instruments.id"), index=True)
    calibration_id: Mapped[int | None] = mapped_column(ForeignKey("calibration_records.id"))
    operator: Mapped[str] = mapped_column(String(64))
    measured_at: Mapped[dt.datetime] = mapped_column(index=True)
    received_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    gloss_20_gu: Mapped[float | None]
    gloss_60_gu: Mapped[float | None]
    gloss_85_gu: Mapped[float | None]
    haze_hu: Mapped[float | None]
    log_haze: Mapped[float | None]
    doi: Mapped[float | None]
    rspec_gu: Mapped[float | None]
    payload_sha256: Mapped[str] = mapped_column(String(64))
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"))


@event.listens_for(GlossReading, "before_update")
def _refuse_update(_mapper: Any, _conn: Any, target: GlossReading) -> None:
    raise ImmutableRowError(f"gloss reading {target.id} is immutable; store a new reading instead")


@event.listens_for(GlossReading, "before_delete")
def _refuse_delete(_mapper: Any, _conn: Any, target: GlossReading) -> None:
    raise ImmutableRowError(f"gloss reading {target.id} is immutable; it cannot be deleted")
