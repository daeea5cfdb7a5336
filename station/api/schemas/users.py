"""Users, tokens and the audit log."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field

from db.models import Role
from station.schema_config import strict_config

UserName = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.@-]+$", examples=["ana"])]


class UserCreate(BaseModel):
    """Properties to receive on creation."""

    model_config = strict_config(examples=[{"name": "ana", "role": "technician"}])

    name: UserName
    role: Role


class TokenCreate(BaseModel):
    """A label for a new token (which device or script holds it)."""

    model_config = strict_config(examples=[{"label": "booth-2 station"}])

    label: Annotated[str, Field(max_length=64, examples=["booth-2 station"])] = ""


class UserPublic(BaseModel):
    """A user (tokens are never shown after issue)."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    name: str
    role: Role
    active: bool
    created_at: dt.datetime


class TokenIssued(BaseModel):
    """A freshly issued token: the only time the secret is shown."""

    user: UserPublic
    token_id: int
    token: Annotated[str, Field(description="bearer secret; store it now, it is kept only hashed")]
    expires_at: Annotated[dt.datetime | None, Field(description="when the token stops working (UTC)")] = None


class TokenPublic(BaseModel):
    """One token of a user (never its secret)."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    user_id: int
    label: str
    created_at: dt.datetime
    expires_at: dt.datetime | None
    revoked_at: dt.datetime | None


class AuditEventPublic(BaseModel):
    """One audit entry."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    at: dt.datetime
    actor_id: int | None
    action: str
    entity: str
    entity_id: str
    detail: dict[str, Any]
