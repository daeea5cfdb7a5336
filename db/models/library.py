"""The paint library, formulation jobs (recipes) and stored analysis results."""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import Enum, ForeignKey, String
from sqlalchemy.orm import Mapped, mapped_column

from db.base import Base, JSONType, utcnow

JOB_STATES: tuple[str, ...] = ("pending", "done", "failed")


class LibraryPaint(Base):
    """A library paint: Lab at its aspecular angles (degrees), gloss (GU), place in the hierarchy."""

    __tablename__ = "library_paints"

    id: Mapped[int] = mapped_column(primary_key=True)
    code: Mapped[str] = mapped_column(String(64), unique=True)
    name: Mapped[str] = mapped_column(String(128), default="")
    category: Mapped[str] = mapped_column(String(32), default="", index=True)
    family: Mapped[str] = mapped_column(String(64), default="")
    angles_deg: Mapped[list[float]] = mapped_column(JSONType)
    lab: Mapped[list[list[float]]] = mapped_column(JSONType)
    gloss_gu: Mapped[float | None]
    extra: Mapped[dict[str, Any]] = mapped_column(default=dict)


class FormulationJob(Base):
    """A recipe request: the target (design version or Lab), its state and the recipe found."""

    __tablename__ = "formulation_jobs"

    id: Mapped[int] = mapped_column(primary_key=True)
    design_version_id: Mapped[int | None] = mapped_column(ForeignKey("design_versions.id"))
    library_paint_id: Mapped[int | None] = mapped_column(ForeignKey("library_paints.id"))
    state: Mapped[str] = mapped_column(
        Enum(*JOB_STATES, name="job_state", native_enum=False, create_constraint=True, length=16),
        default="pending",
    )
    target: Mapped[dict[str, Any]] = mapped_column(default=dict)
    recipe: Mapped[dict[str, Any] | None]
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"))


class AnalysisResult(Base):
    """A stored analysis (misalignment index, inverse trompe l'oeil …) with its inputs."""

    __tablename__ = "analysis_results"

    id: Mapped[int] = mapped_column(primary_key=True)
    kind: Mapped[str] = mapped_column(String(32), index=True)
    inputs: Mapped[dict[str, Any]] = mapped_column(default=dict)
    result: Mapped[dict[str, Any]] = mapped_column(default=dict)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"))
