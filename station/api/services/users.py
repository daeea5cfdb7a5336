"""Users and tokens: create, issue, revoke, bootstrap the first admin."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from db.base import utcnow
from db.chain import record_change
from db.models import ApiToken, Role, User
from station.api.errors import ConflictError, NotFoundError
from station.api.security import DEFAULT_TOKEN_TTL, hash_token, new_token
from station.api.services import audit


def _issue(session: Session, user: User, label: str, ttl: dt.timedelta) -> tuple[ApiToken, str]:
    if ttl <= dt.timedelta(0):
        raise ValueError(f"token lifetime must be positive, got {ttl}")
    secret = new_token()
    now = utcnow()
    token = ApiToken(
        user_id=user.id, token_hash=hash_token(secret), label=label, created_at=now, expires_at=now + ttl
    )
    session.add(token)
    session.flush()
    return token, secret


def create_user(
    *,
    session: Session,
    actor: User | None,
    name: str,
    role: Role,
    label: str = "",
    ttl: dt.timedelta = DEFAULT_TOKEN_TTL,
) -> tuple[User, ApiToken, str]:
    """Create a user with a first token valid for *ttl*; returns the secret (shown once)."""
    if session.scalar(select(User.id).where(User.name == name)) is not None:
        raise ConflictError(f"user {name!r} exists")
    user = User(name=name, role=role)
    session.add(user)
    session.flush()
    token, secret = _issue(session, user, label, ttl)
    audit.record(
        session=session,
        actor=actor,
        action="user.create",
        entity="user",
        entity_id=user.id,
        name=name,
        role=role.value,
    )
    session.commit()
    return user, token, secret


def get_user(*, session: Session, user_id: int) -> User:
    """The user *user_id* or :class:`NotFoundError`."""
    user = session.get(User, user_id)
    if user is None:
        raise NotFoundError(f"user {user_id} not found")
    return user


def find_user(*, session: Session, name: str) -> User:
    """The user called *name* or :class:`NotFoundError`."""
    user = session.scalar(select(User).where(User.name == name))
    if user is None:
        raise NotFoundError(f"user {name!r} not found")
    return user


def issue_token(
    *,
    session: Session,
    actor: User | None,
    user: User,
    label: str = "",
    ttl: dt.timedelta = DEFAULT_TOKEN_TTL,
) -> tuple[ApiToken, str]:
    """A new token for *user*, valid for *ttl* (an inactive user gets none)."""
    if not user.active:
        raise ConflictError(f"user {user.name!r} is deactivated")
    token, secret = _issue(session, user, label, ttl)
    audit.record(
        session=session,
        actor=actor,
        action="token.issue",
        entity="user",
        entity_id=user.id,
        token_id=token.id,
        label=label,
    )
    session.commit()
    return token, secret


def deactivate(*, session: Session, actor: User | None, user: User) -> User:
    """Deactivate *user* and revoke every token it holds."""
    if actor is not None and actor.id == user.id:
        raise ConflictError("an admin cannot deactivate themself")
    user.active = False
    revoked = session.execute(
        update(ApiToken)
        .where(ApiToken.user_id == user.id, ApiToken.revoked_at.is_(None))
        .values(revoked_at=utcnow())
        .returning(ApiToken.id)
    ).scalars()
    for token_id in sorted(revoked):  # a Core UPDATE: sealed here, not by the flush hook
        record_change(session, "api_tokens", token_id, "update")
    audit.record(session=session, actor=actor, action="user.deactivate", entity="user", entity_id=user.id)
    session.commit()
    return user


def get_token(*, session: Session, token_id: int) -> ApiToken:
    """The token *token_id* or :class:`NotFoundError`."""
    token = session.get(ApiToken, token_id)
    if token is None:
        raise NotFoundError(f"token {token_id} not found")
    return token


def list_tokens(*, session: Session, user: User) -> list[ApiToken]:
    """Every token of *user*, oldest first (revoked and expired ones included)."""
    return list(session.scalars(select(ApiToken).where(ApiToken.user_id == user.id).order_by(ApiToken.id)))


def revoke_token(*, session: Session, actor: User | None, token: ApiToken) -> ApiToken:
    """Revoke one token now (a token already revoked keeps its first revocation time)."""
    if token.revoked_at is None:
        token.revoked_at = utcnow()
        audit.record(
            session=session,
            actor=actor,
            action="token.revoke",
            entity="user",
            entity_id=token.user_id,
            token_id=token.id,
        )
    session.commit()
    return token


def list_users(*, session: Session) -> list[User]:
    """Every user, oldest first."""
    return list(session.scalars(select(User).order_by(User.id)))


def bootstrap_admin(
    *, session: Session, name: str = "admin", ttl: dt.timedelta = DEFAULT_TOKEN_TTL
) -> str | None:
    """On an empty user table: create the first admin and return its token (valid for *ttl*); else ``None``."""
    if (session.scalar(select(func.count()).select_from(User)) or 0) > 0:
        return None
    _user, _token, secret = create_user(
        session=session, actor=None, name=name, role=Role.ADMIN, label="bootstrap", ttl=ttl
    )
    return secret
