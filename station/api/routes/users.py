"""Users, tokens and the audit log: ``/api/v1/users``, ``/api/v1/me``, ``/api/v1/tokens``, ``/api/v1/audit``.

Users are managed by admins; a token can be revoked by an admin or by the user who holds it.
"""

from __future__ import annotations

import datetime as dt
from typing import Annotated

from fastapi import APIRouter, Query, Request, status

from db.models import User
from station.api.deps import AnyUser, ReadSessionDep, SessionDep, SettingsDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND, NotFoundError
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.schemas.users import (
    AuditEventPublic,
    TokenCreate,
    TokenIssued,
    TokenPublic,
    UserCreate,
    UserPublic,
)
from station.api.security import Scope, TokenCache, allows
from station.api.services import audit
from station.api.services import users as service

router = APIRouter(tags=["users"], responses=ERROR_RESPONSES)
#: The audit log has a section of its own in the API docs.
audit_router = APIRouter(tags=["audit"], responses=ERROR_RESPONSES)
Admin = Annotated[User, scoped(Scope.USERS_MANAGE)]
Auditor = Annotated[User, scoped(Scope.AUDIT_READ)]


def _ttl(days: float) -> dt.timedelta:
    return dt.timedelta(days=days)


@router.get("/me", response_model=UserPublic)
def me(user: AnyUser) -> UserPublic:
    """The caller."""
    return UserPublic.model_validate(user)


@router.get("/users", response_model=list[UserPublic])
def list_users(session: ReadSessionDep, _user: Admin) -> list[UserPublic]:
    """Every user."""
    return [UserPublic.model_validate(u) for u in service.list_users(session=session)]


@router.post("/users", status_code=status.HTTP_201_CREATED, response_model=TokenIssued, responses=CONFLICT)
def create_user(session: SessionDep, settings: SettingsDep, admin: Admin, user_in: UserCreate) -> TokenIssued:
    """Create a user and its first token (the secret is shown only in this response)."""
    user, token, secret = service.create_user(
        session=session, actor=admin, name=user_in.name, role=user_in.role, ttl=_ttl(settings.token_ttl_days)
    )
    return TokenIssued(
        user=UserPublic.model_validate(user), token_id=token.id, token=secret, expires_at=token.expires_at
    )


@router.post(
    "/users/{user_id}/tokens",
    status_code=status.HTTP_201_CREATED,
    response_model=TokenIssued,
    responses={**NOT_FOUND, **CONFLICT},
)
def issue_token(
    session: SessionDep, settings: SettingsDep, admin: Admin, user_id: Id, token_in: TokenCreate
) -> TokenIssued:
    """Issue another token for a user (valid for ``token_ttl_days``)."""
    user = service.get_user(session=session, user_id=user_id)
    token, secret = service.issue_token(
        session=session, actor=admin, user=user, label=token_in.label, ttl=_ttl(settings.token_ttl_days)
    )
    return TokenIssued(
        user=UserPublic.model_validate(user), token_id=token.id, token=secret, expires_at=token.expires_at
    )


@router.get("/users/{user_id}/tokens", response_model=list[TokenPublic], responses=NOT_FOUND)
def list_tokens(session: ReadSessionDep, _admin: Admin, user_id: Id) -> list[TokenPublic]:
    """A user's tokens (ids, labels, expiry, revocation; never the secrets)."""
    user = service.get_user(session=session, user_id=user_id)
    return [TokenPublic.model_validate(t) for t in service.list_tokens(session=session, user=user)]


@router.delete("/tokens/{token_id}", response_model=TokenPublic, responses=NOT_FOUND)
def revoke_token(request: Request, session: SessionDep, caller: AnyUser, token_id: Id) -> TokenPublic:
    """Revoke one token now (admin: any token; any user: their own). Another user's token is a 404."""
    token = service.get_token(session=session, token_id=token_id)
    if token.user_id != caller.id and not allows(caller.role, Scope.USERS_MANAGE):
        raise NotFoundError(f"token {token_id} not found")
    revoked = service.revoke_token(session=session, actor=caller, token=token)
    cache: TokenCache = request.app.state.tokens
    cache.drop(revoked.token_hash)
    return TokenPublic.model_validate(revoked)


@router.delete("/users/{user_id}", response_model=UserPublic, responses={**NOT_FOUND, **CONFLICT})
def deactivate_user(request: Request, session: SessionDep, admin: Admin, user_id: Id) -> UserPublic:
    """Deactivate a user and revoke its tokens (the row and its audit trail stay)."""
    user = service.get_user(session=session, user_id=user_id)
    deactivated = service.deactivate(session=session, actor=admin, user=user)
    cache: TokenCache = request.app.state.tokens
    cache.drop(user_id=deactivated.id)
    return UserPublic.model_validate(deactivated)


@audit_router.get("/audit", response_model=Page[AuditEventPublic])
def list_audit(
    session: ReadSessionDep,
    _user: Auditor,
    entity: Annotated[str | None, Query(max_length=32)] = None,
    actor_id: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[AuditEventPublic]:
    """Audit events, newest first."""
    rows, total = audit.list_events(
        session=session, entity=entity, actor_id=actor_id, limit=limit, offset=offset
    )
    return Page[AuditEventPublic](data=[AuditEventPublic.model_validate(r) for r in rows], count=total)
