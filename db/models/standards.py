"""QC standards: the reference each sample of a job and part is judged against.

A standard is either a reference measurement (a panel measured as the master) or a design (its Lab
at the sample's aspecular angles comes from the design model); exactly one of the two is set. There is
one standard per job and part; replacing it is an explicit act (``station.qc.jobs.set_standard`` with
``replace=True``) that records who did it and when.
"""

from __future__ import annotations

import datetime as dt

from sqlalchemy import CheckConstraint, Enum, ForeignKey, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from db.base import Base, utcnow
from db.models.measurements import PARTS


class Standard(Base):
    """The standard of one job and part: a reference measurement id or a design id (never both)."""

    __tablename__ = "standards"
    __table_args__ = (
        UniqueConstraint("job", "part"),
        CheckConstraint("(measurement_id IS NULL) != (design_id IS NULL)", name="one_reference"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    job: Mapped[str] = mapped_column(String(64), index=True)
    part: Mapped[str] = mapped_column(
        Enum(*PARTS, name="part", native_enum=False, create_constraint=True, length=16)
    )
    measurement_id: Mapped[int | None] = mapped_column(ForeignKey("measurements.id"))
    design_id: Mapped[int | None] = mapped_column(ForeignKey("designs.id"))
    notes: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"))
