"""Panels (physical samples) and their immutable measurements.

A measurement row is never updated or deleted. A correction is a new row whose ``supersedes_id``
points at the row it replaces, with who corrected it and why; a row can be superseded at most once,
so corrections form a chain.
"""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

from sqlalchemy import Enum, ForeignKey, String, Text, event, text
from sqlalchemy.orm import Mapped, mapped_column

from db.base import Base, JSONType, utcnow
from db.errors import ImmutableRowError
from station.model.domain import ILLUMINATION_DEG

PARTS: tuple[str, ...] = (
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


class Panel(Base):
    """A painted sample: the job it belongs to, the car part, the substrate and free notes."""

    __tablename__ = "panels"

    id: Mapped[int] = mapped_column(primary_key=True)
    job: Mapped[str] = mapped_column(String(64), index=True)
    part: Mapped[str] = mapped_column(
        Enum(*PARTS, name="part", native_enum=False, create_constraint=True, length=16)
    )
    substrate: Mapped[str] = mapped_column(String(64), default="")
    notes: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"))


class Measurement(Base):
    """One immutable reading: Lab (and spectra) per aspecular geometry, gloss, provenance, hash.

    ``geometries_deg`` are aspecular angles in degrees under ``illumination_deg`` (45° unless the row holds
    another illumination block of a multi-illumination instrument, e.g. an MA-T12's 15°); ``lab`` is one [L*, a*, b*] per geometry
    (D65 / CIE 1964 10° unless ``illuminant``/``observer`` say otherwise); ``spectra`` is one
    reflectance curve (0–1) per geometry sampled at ``wavelengths_nm``; ``gloss_gu`` in gloss units
    at ``gloss_geometry_deg`` (60° by default). ``texture`` holds the instrument's vendor texture values
    (sparkle, graininess) as ``[{"vendor", "name", "geometry", "value"}, …]`` (``geometry`` a name such as
    ``45as15``, or ``""`` for a per-sample value), or ``None``: device-dependent values, never compared
    across vendors. ``payload_sha256`` is the SHA-256 of the raw payload
    as received, so a re-sent reading can be told from a different one under the same client id.
    ``row_sha256`` and ``chain_sha256`` link the row into the measurement hash chain (``db.chain``).
    """

    __tablename__ = "measurements"

    id: Mapped[int] = mapped_column(primary_key=True)
    client_id: Mapped[uuid.UUID] = mapped_column(unique=True)
    panel_id: Mapped[int | None] = mapped_column(ForeignKey("panels.id"), index=True)
    instrument_id: Mapped[int] = mapped_column(ForeignKey("instruments.id"), index=True)
    calibration_id: Mapped[int | None] = mapped_column(ForeignKey("calibration_records.id"))
    operator: Mapped[str] = mapped_column(String(64))
    measured_at: Mapped[dt.datetime] = mapped_column(index=True)
    received_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    illuminant: Mapped[str] = mapped_column(String(16), default="D65")
    observer: Mapped[str] = mapped_column(String(64), default="CIE 1964 10 Degree Standard Observer")
    geometries_deg: Mapped[list[float]] = mapped_column(JSONType)
    lab: Mapped[list[list[float]]] = mapped_column(JSONType)
    wavelengths_nm: Mapped[list[float] | None] = mapped_column(JSONType)
    spectra: Mapped[list[list[float]] | None] = mapped_column(JSONType)
    gloss_gu: Mapped[float | None]
    gloss_geometry_deg: Mapped[float | None]
    illumination_deg: Mapped[float] = mapped_column(
        default=ILLUMINATION_DEG, server_default=text(f"{ILLUMINATION_DEG:g}"), index=True
    )
    texture: Mapped[list[dict[str, Any]] | None] = mapped_column(JSONType)
    payload_sha256: Mapped[str] = mapped_column(String(64))
    supersedes_id: Mapped[int | None] = mapped_column(ForeignKey("measurements.id"), unique=True)
    correction_reason: Mapped[str | None] = mapped_column(Text)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"))
    row_sha256: Mapped[str | None] = mapped_column(String(64))
    chain_sha256: Mapped[str | None] = mapped_column(String(64))


@event.listens_for(Measurement, "before_update")
def _refuse_update(_mapper: Any, _conn: Any, target: Measurement) -> None:
    raise ImmutableRowError(f"measurement {target.id} is immutable; post a correction instead")


@event.listens_for(Measurement, "before_delete")
def _refuse_delete(_mapper: Any, _conn: Any, target: Measurement) -> None:
    raise ImmutableRowError(f"measurement {target.id} is immutable; it cannot be deleted")
