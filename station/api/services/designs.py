"""Designs: create (version 1), new versions, archive; bodies validated through station.model.design_io."""

from __future__ import annotations

from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import Design, DesignVersion, User
from station.api.errors import ConflictError, NotFoundError
from station.api.schemas.designs import DesignBody, DesignPublic, DesignVersionPublic
from station.api.services import audit
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_from_dict, design_to_dict


def canonical_body(body: DesignBody) -> dict[str, Any]:
    """Validate *body* through the model (``design_from_dict``) and return its canonical dict."""
    data = body.model_dump(by_alias=True)
    try:
        return design_to_dict(design_from_dict(data))
    except InputError as exc:  # name the field as the request does: design.<field>
        raise InputError(f"design.{exc.field}", exc.accepted, exc.got) from exc


def to_design(body: DesignBody, field: str = "design") -> FaceFlopTravelGloss:
    """The appearance-model design of *body*; a refusal names the request field (``<field>.<name>``)."""
    data = body.model_dump(by_alias=True)
    try:
        return design_from_dict(data)
    except InputError as exc:
        raise InputError(f"{field}.{exc.field}", exc.accepted, exc.got) from exc


def design_version(*, session: Session, design_id: int, version: int | None) -> DesignVersion:
    """Version *version* (default: the latest) of design *design_id*, or :class:`NotFoundError`."""
    design = _design(session, design_id)
    return _version(session, design_id, version or design.latest_version)


def _public(design: Design, body: dict[str, Any]) -> DesignPublic:
    return DesignPublic(
        id=design.id,
        name=design.name,
        latest_version=design.latest_version,
        archived=design.archived,
        created_at=design.created_at,
        created_by_id=design.created_by_id,
        design=body,
    )


def _version(session: Session, design_id: int, version: int) -> DesignVersion:
    row = session.scalar(
        select(DesignVersion).where(DesignVersion.design_id == design_id, DesignVersion.version == version)
    )
    if row is None:
        raise NotFoundError(f"design {design_id} has no version {version}")
    return row


def _design(session: Session, design_id: int) -> Design:
    design = session.get(Design, design_id)
    if design is None:
        raise NotFoundError(f"design {design_id} not found")
    return design


def create_design(*, session: Session, actor: User, name: str, body: DesignBody, note: str) -> DesignPublic:
    """A new design at version 1."""
    canonical = canonical_body(body)
    design = Design(name=name, latest_version=1, created_by_id=actor.id)
    session.add(design)
    session.flush()
    session.add(
        DesignVersion(design_id=design.id, version=1, body=canonical, note=note, created_by_id=actor.id)
    )
    audit.record(
        session=session, actor=actor, action="design.create", entity="design", entity_id=design.id, version=1
    )
    session.commit()
    return _public(design, canonical)


def add_version(
    *, session: Session, actor: User, design_id: int, body: DesignBody, note: str
) -> DesignPublic:
    """Save *body* as the next version of *design_id* (earlier versions stay)."""
    design = _design(session, design_id)
    if design.archived:
        raise ConflictError(f"design {design_id} is archived")
    canonical = canonical_body(body)
    design.latest_version += 1
    session.add(
        DesignVersion(
            design_id=design.id,
            version=design.latest_version,
            body=canonical,
            note=note,
            created_by_id=actor.id,
        )
    )
    audit.record(
        session=session,
        actor=actor,
        action="design.version",
        entity="design",
        entity_id=design.id,
        version=design.latest_version,
    )
    session.commit()
    return _public(design, canonical)


def archive(*, session: Session, actor: User, design_id: int) -> DesignPublic:
    """Archive a design (hidden from lists, versions kept)."""
    design = _design(session, design_id)
    design.archived = True
    audit.record(session=session, actor=actor, action="design.archive", entity="design", entity_id=design.id)
    session.commit()
    return _public(design, _version(session, design.id, design.latest_version).body)


def get_design(*, session: Session, design_id: int) -> DesignPublic:
    """Design *design_id* with its latest body."""
    design = _design(session, design_id)
    return _public(design, _version(session, design.id, design.latest_version).body)


def get_version(*, session: Session, design_id: int, version: int) -> DesignVersionPublic:
    """Version *version* of *design_id*."""
    _design(session, design_id)
    row = _version(session, design_id, version)
    return DesignVersionPublic.model_validate(row)


def list_versions(*, session: Session, design_id: int) -> list[DesignVersionPublic]:
    """Every version of *design_id*, oldest first."""
    _design(session, design_id)
    rows = session.scalars(
        select(DesignVersion).where(DesignVersion.design_id == design_id).order_by(DesignVersion.version)
    )
    return [DesignVersionPublic.model_validate(r) for r in rows]


def list_designs(
    *, session: Session, name: str | None, include_archived: bool, limit: int, offset: int
) -> tuple[list[DesignPublic], int]:
    """Designs (name substring filter), newest first, with their latest bodies."""
    query = select(Design, DesignVersion.body).join(
        DesignVersion,
        (DesignVersion.design_id == Design.id) & (DesignVersion.version == Design.latest_version),
    )
    if name:
        query = query.where(Design.name.contains(name, autoescape=True))
    if not include_archived:
        query = query.where(Design.archived.is_(False))
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.execute(query.order_by(Design.id.desc()).limit(limit).offset(offset)).all()
    return [_public(d, body) for d, body in rows], total
