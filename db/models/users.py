"""Users, their roles, their hashed API tokens and the audit log."""

from __future__ import annotations

import datetime as dt
import enum
from typing import Any

from sqlalchemy import Enum, ForeignKey, String
from sqlalchemy.orm import Mapped, mapped_column, relationship

from db.base import Base, utcnow


class Role(enum.StrEnum):
    """What a user is allowed to do (least privilege; see ``station.api.security.ROLE_SCOPES``)."""

    TECHNICIAN = "technician"
    QA = "qa"
    STYLIST = "stylist"
    CHEMIST = "chemist"
    ADMIN = "admin"


class User(Base):
    """A person (or a station account) that holds tokens and signs audit events."""

    __tablename__ = "users"

    id: Mapped[int] = mapped_column(primary_key=True)
    name: Mapped[str] = mapped_column(String(64), unique=True)
    role: Mapped[Role] = mapped_column(
        Enum(
            Role,
            name="role",
            native_enum=False,
            create_constraint=True,
            length=16,
            values_callable=lambda e: [m.value for m in e],
        )
    )
    active: Mapped[bool] = mapped_column(default=True)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)

    tokens: Mapped[list[ApiToken]] = relationship(back_populates="user")


class ApiToken(Base):
    """A bearer token, stored only as the SHA-256 of the secret (the secret is shown once)."""

    __tablename__ = "api_tokens"

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id"), index=True)
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    label: Mapped[str] = mapped_column(String(64), default="")
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    expires_at: Mapped[dt.datetime | None]
    revoked_at: Mapped[dt.datetime | None]

    user: Mapped[User] = relationship(back_populates="tokens")


class AuditEvent(Base):
    """One write: who did what to which entity, and when (append-only, hash-chained: ``db.chain``)."""

    __tablename__ = "audit_events"

    id: Mapped[int] = mapped_column(primary_key=True)
    at: Mapped[dt.datetime] = mapped_column(default=utcnow, index=True)
    actor_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), index=True)
    action: Mapped[str] = mapped_column(String(64))
    entity: Mapped[str] = mapped_column(String(32))
    entity_id: Mapped[str] = mapped_column(String(64))
    detail: Mapped[dict[str, Any]] = mapped_column(default=dict)
    row_sha256: Mapped[str | None] = mapped_column(String(64))
    chain_sha256: Mapped[str | None] = mapped_column(String(64))


class RecordEvent(Base):
    """One change the product made to a sealed record table (append-only, hash-chained: ``db.chain``).

    ``entity`` is the table (``db.chain.RECORD_TABLES``), ``entity_id`` the row id, ``op`` ``insert``,
    ``update`` or ``delete`` and ``state_sha256`` the hash of the row as the change left it (null for
    a delete); ``at`` is the write time (UTC).
    """

    __tablename__ = "record_events"

    id: Mapped[int] = mapped_column(primary_key=True)
    at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    entity: Mapped[str] = mapped_column(String(32))
    entity_id: Mapped[str] = mapped_column(String(64))
    op: Mapped[str] = mapped_column(String(8))
    state_sha256: Mapped[str | None] = mapped_column(String(64))
    row_sha256: Mapped[str | None] = mapped_column(String(64))
    chain_sha256: Mapped[str | None] = mapped_column(String(64))


class LedgerHead(Base):
    """The head of one hash chain (``measurements``, ``audit_events``, ``record_events``) and the lock its writers take.

    ``length`` rows, the last ``head_sha256`` link, the last write time ``head_at`` (UTC), the last
    row back-filled when the chain was introduced (``backfill_last_id``) and the last row hashed with
    the canonical form before revision 0009 (``legacy_last_id``); see ``db.chain``.
    """

    __tablename__ = "ledger_heads"

    chain: Mapped[str] = mapped_column(String(32), primary_key=True)
    length: Mapped[int]
    head_sha256: Mapped[str] = mapped_column(String(64))
    head_at: Mapped[dt.datetime | None]
    backfill_last_id: Mapped[int | None]
    legacy_last_id: Mapped[int | None]
