"""Dependencies shared by the routers: the session, the settings, the caller and its scopes.

``SessionDep`` yields a session from the app's own session factory (built in ``create_app``);
tests swap it with ``app.dependency_overrides[get_session]``. ``authorize`` resolves the bearer
token to a user (401 otherwise) and checks the route's scopes against the role (403 otherwise):
``user: Annotated[User, Security(authorize, scopes=[Scope.DESIGNS_WRITE])]``.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated

from fastapi import Depends, HTTPException, Request, Security, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer, SecurityScopes
from sqlalchemy import select
from sqlalchemy.orm import Session

from db.models import ApiToken, User
from station.api.security import Scope, allows, hash_token
from station.api.settings import Settings

bearer = HTTPBearer(auto_error=False, description="token printed by `station serve` or `station users add`")


def get_session(request: Request) -> Iterator[Session]:
    """One session per request from the app's session factory."""
    with request.app.state.sessions() as session:
        yield session


def get_settings(request: Request) -> Settings:
    """The settings the app was created with."""
    return request.app.state.settings


SessionDep = Annotated[Session, Depends(get_session)]
SettingsDep = Annotated[Settings, Depends(get_settings)]


def _unauthorised(detail: str) -> HTTPException:
    return HTTPException(status.HTTP_401_UNAUTHORIZED, detail, headers={"WWW-Authenticate": "Bearer"})


def authorize(
    security_scopes: SecurityScopes,
    session: SessionDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(bearer)],
) -> User:
    """The active user behind the bearer token, holding every scope the route declares."""
    if credentials is None or credentials.scheme.lower() != "bearer" or not credentials.credentials:
        raise _unauthorised("missing bearer token")
    token = session.scalars(
        select(ApiToken).where(ApiToken.token_hash == hash_token(credentials.credentials))
    ).first()
    if token is None or token.revoked_at is not None or not token.user.active:
        raise _unauthorised("unknown or revoked token")
    user = token.user
    session.commit()  # end the read transaction: SQLite holds its write lock per transaction (BEGIN IMMEDIATE)
    missing = [s for s in security_scopes.scopes if not allows(user.role, Scope(s))]
    if missing:
        raise HTTPException(status.HTTP_403_FORBIDDEN, f"role {user.role.value} lacks scope {missing[0]}")
    return user


def scoped(scope: Scope | None) -> object:
    """``Security(authorize, scopes=[scope])``: the annotation metadata for a route's caller."""
    return Security(authorize, scopes=[scope.value] if scope else [])


AnyUser = Annotated[User, scoped(None)]
