"""Dependencies shared by the routers: the session, the settings, the caller and its scopes.

``SessionDep`` yields a session from the app's own session factory (``app.state.sessions``, built in
``create_app``), whose transactions may write (SQLite: ``BEGIN IMMEDIATE``); ``ReadSessionDep`` yields
one from its read-only factory (``app.state.read_sessions``, on ``db.engine.reading``: SQLite deferred
reads that never take or wait for the write lock), for routes and checks that only read. Nothing swaps
them: the service's tests build the app with ``create_app`` on a real test database, SQLite or
PostgreSQL (tests/api/conftest.py).
``authorize`` resolves the bearer token to a user (401 otherwise) and checks the route's scopes against
the role (403 otherwise):
``user: Annotated[User, Security(authorize, scopes=[Scope.DESIGNS_WRITE])]``.

These dependencies run on the event loop (no worker-thread hop per dependency: a request to a sync
route pays one, for the route itself); whatever may block goes to a worker thread: closing a session
that still holds a connection (returning it to the pool may talk to the database) and the token's
database lookup.

The token is checked against the database on every request while it is reachable; while it is away
(``app.state.database``) a token the database verified in the last ``Settings.token_offline_s``
seconds (``app.state.tokens``) still authenticates, any other gets 503 (it cannot be checked). A token
verified less than ``Settings.token_recheck_s`` seconds ago is not looked up again.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Annotated

from fastapi import Depends, HTTPException, Request, Security, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer, SecurityScopes
from sqlalchemy import select
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

from db.base import utcnow
from db.models import ApiToken, User
from station.api.availability import DatabaseState
from station.api.security import Scope, TokenCache, TokenGrant, allows, hash_token, scope_refusal
from station.api.settings import Settings
from station.ingest import is_unreachable

bearer = HTTPBearer(auto_error=False, description="token printed by `station serve` or `station users add`")


async def _close(session: Session) -> None:
    """Close *session*: in a worker thread when it is in a transaction (its connection goes back to the
    pool, which may end the transaction on the database), at once when it never began one."""
    if session.in_transaction():
        await run_in_threadpool(session.close)
    else:
        session.close()


async def get_session(request: Request) -> AsyncIterator[Session]:
    """One session per request from the app's session factory (made without touching the database)."""
    session: Session = request.app.state.sessions()
    try:
        yield session
    finally:
        await _close(session)


async def get_read_session(request: Request) -> AsyncIterator[Session]:
    """One read-only session per request (a write through it fails: "attempt to write a readonly database")."""
    session: Session = request.app.state.read_sessions()
    try:
        yield session
    finally:
        await _close(session)


def get_settings(request: Request) -> Settings:
    """The settings the app was created with."""
    return request.app.state.settings


SessionDep = Annotated[Session, Depends(get_session)]
ReadSessionDep = Annotated[Session, Depends(get_read_session)]
SettingsDep = Annotated[Settings, Depends(get_settings)]


def _unauthorised(detail: str) -> HTTPException:
    return HTTPException(status.HTTP_401_UNAUTHORIZED, detail, headers={"WWW-Authenticate": "Bearer"})


def _verified(session: Session, token_hash: str) -> tuple[TokenGrant, User] | None:
    """The grant and user of *token_hash* from the database (``None``: no such token)."""
    token = session.scalars(select(ApiToken).where(ApiToken.token_hash == token_hash)).first()
    if token is None:
        return None
    grant, user = TokenGrant.of(token), token.user
    session.commit()  # end the read transaction (a read-only session: it never held the write lock)
    return grant, user


def _lookup(request: Request, token_hash: str) -> tuple[TokenGrant, User] | None:
    """:func:`_verified` on a read-only session of its own (closed, its transaction ended, on return)."""
    with request.app.state.read_sessions() as session:
        return _verified(session, token_hash)


def _unavailable() -> HTTPException:
    return HTTPException(
        status.HTTP_503_SERVICE_UNAVAILABLE,
        "database unavailable and this token was not verified recently; retry later",
        headers={"Retry-After": "5"},
    )


async def authorize(
    security_scopes: SecurityScopes,
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(bearer)],
) -> User:
    """The active user behind the bearer token, holding every scope the route declares.

    A token verified within ``token_recheck_s`` costs no session, no database round trip and no
    worker thread; otherwise the lookup runs in a worker thread, on a read-only session of the app's
    (``app.state.read_sessions``).
    """
    if credentials is None or credentials.scheme.lower() != "bearer" or not credentials.credentials:
        raise _unauthorised("missing bearer token")
    token_hash = hash_token(credentials.credentials)
    tokens: TokenCache = request.app.state.tokens
    database: DatabaseState = request.app.state.database
    grant: TokenGrant | None = None
    user: User | None = None
    recheck_s: float = request.app.state.settings.token_recheck_s
    recent = tokens.get(token_hash, within_s=recheck_s) if recheck_s > 0 else None
    if recent is not None:
        grant = recent  # verified moments ago: no database round trip
    elif database.should_try():
        try:
            found = await run_in_threadpool(_lookup, request, token_hash)
        except Exception as exc:
            if not is_unreachable(exc):
                raise
            database.mark_away(exc)
        else:
            database.mark_back()
            if found is None:
                tokens.drop(token_hash)
                raise _unauthorised("unknown or revoked token")
            grant, user = found
    verified_now = grant is not None and recent is None
    if grant is None:
        grant = tokens.get(token_hash)
        if grant is None:
            raise _unavailable()
    refusal = grant.refusal(utcnow())
    if refusal is not None:
        tokens.drop(token_hash)
        raise _unauthorised(refusal)
    if verified_now:
        tokens.put(token_hash, grant)  # only a database answer restarts the offline window
    if user is None:
        user = grant.user()
    missing = [s for s in security_scopes.scopes if not allows(grant.role, Scope(s))]
    if missing:
        raise HTTPException(status.HTTP_403_FORBIDDEN, scope_refusal(grant.role, Scope(missing[0])))
    return user


def scoped(scope: Scope | None) -> object:
    """``Security(authorize, scopes=[scope])``: the annotation metadata for a route's caller."""
    return Security(authorize, scopes=[scope.value] if scope else [])


AnyUser = Annotated[User, scoped(None)]
