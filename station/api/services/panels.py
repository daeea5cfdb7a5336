"""Panels: create, fetch, list."""

from __future__ import annotations

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import Panel, User
from station.api.errors import NotFoundError
from station.api.schemas.panels import PanelCreate
from station.api.services import audit


def create_panel(*, session: Session, actor: User, panel_in: PanelCreate) -> Panel:
    """Store a new panel."""
    panel = Panel(**panel_in.model_dump(), created_by_id=actor.id)
    session.add(panel)
    session.flush()
    audit.record(
        session=session,
        actor=actor,
        action="panel.create",
        entity="panel",
        entity_id=panel.id,
        job=panel.job,
        part=panel.part,
    )
    session.commit()
    return panel


def get_panel(*, session: Session, panel_id: int) -> Panel:
    """Panel *panel_id* or :class:`NotFoundError`."""
    panel = session.get(Panel, panel_id)
    if panel is None:
        raise NotFoundError(f"panel {panel_id} not found")
    return panel


def list_panels(
    *, session: Session, job: str | None, part: str | None, limit: int, offset: int
) -> tuple[list[Panel], int]:
    """Panels matching *job* / *part*, newest first."""
    query = select(Panel)
    if job:
        query = query.where(Panel.job == job)
    if part:
        query = query.where(Panel.part == part)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.scalars(query.order_by(Panel.id.desc()).limit(limit).offset(offset)).all()
    return list(rows), total
