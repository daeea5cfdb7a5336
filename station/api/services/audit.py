"""The audit log: one row per write, in the same transaction as the write, hash-chained (``db.chain``)."""

from __future__ import annotations

from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.chain import append_audit
from db.models import AuditEvent, User


def record(
    *, session: Session, actor: User | None, action: str, entity: str, entity_id: object, **detail: Any
) -> int:
    """Append an audit event to the chain (committed with the caller's transaction); its id."""
    return append_audit(
        session,
        {
            "actor_id": actor.id if actor else None,
            "action": action,
            "entity": entity,
            "entity_id": str(entity_id),
            "detail": detail,
        },
    )


def list_events(
    *, session: Session, entity: str | None, actor_id: int | None, limit: int, offset: int
) -> tuple[list[AuditEvent], int]:
    """Audit events, newest first."""
    query = select(AuditEvent)
    if entity:
        query = query.where(AuditEvent.entity == entity)
    if actor_id is not None:
        query = query.where(AuditEvent.actor_id == actor_id)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.scalars(query.order_by(AuditEvent.id.desc()).limit(limit).offset(offset)).all()
    return list(rows), total
