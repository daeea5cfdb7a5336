"""Roles, scopes and bearer tokens.

Tokens are 256-bit random secrets; the database keeps only their SHA-256 (a fast hash is enough for
secrets of this entropy: there is nothing to brute-force, unlike a password). Each role holds the
fewest scopes its job needs (a technician measures; a chemist formulates; only admin manages users).

Tokens expire (``Settings.token_ttl_days``) and can be revoked one by one. A :class:`TokenCache`
(one per app) remembers the tokens the database verified: a token verified less than
``Settings.token_recheck_s`` seconds ago is not looked up again (the common case under load), and
while the database is away a technician keeps scanning for ``Settings.token_offline_s`` seconds after
the last verification. Once the database is back a token is checked against it again within
``token_recheck_s``, so a revocation made meanwhile takes effect then; one made through this service
drops the cached grant at once.
"""

from __future__ import annotations

import datetime as dt
import enum
import hashlib
import secrets
import threading
import time
from dataclasses import dataclass

from db.models import ApiToken, Role, User

TOKEN_PREFIX = "cst_"


class Scope(enum.StrEnum):
    """One permission; routes declare the scope they need."""

    INSTRUMENTS_READ = "instruments:read"
    INSTRUMENTS_OPERATE = "instruments:operate"
    MEASUREMENTS_READ = "measurements:read"
    MEASUREMENTS_WRITE = "measurements:write"
    MEASUREMENTS_CORRECT = "measurements:correct"
    DESIGNS_READ = "designs:read"
    DESIGNS_WRITE = "designs:write"
    STYLING_USE = "styling:use"
    LIBRARY_READ = "library:read"
    LIBRARY_WRITE = "library:write"
    FORMULATION_USE = "formulation:use"  # ColorSnap, formulate, export: computed, nothing stored
    RECIPES_WRITE = "recipes:write"
    ANALYSIS_WRITE = "analysis:write"
    AUDIT_READ = "audit:read"
    QC_STANDARDS_WRITE = "qc:standards"
    USERS_MANAGE = "users:manage"


S = Scope
ROLE_SCOPES: dict[Role, frozenset[Scope]] = {
    Role.TECHNICIAN: frozenset(
        {
            S.INSTRUMENTS_READ,
            S.INSTRUMENTS_OPERATE,
            S.MEASUREMENTS_READ,
            S.MEASUREMENTS_WRITE,
            S.MEASUREMENTS_CORRECT,
        }
    ),
    Role.QA: frozenset(
        {
            S.INSTRUMENTS_READ,
            S.MEASUREMENTS_READ,
            S.MEASUREMENTS_CORRECT,
            S.DESIGNS_READ,
            S.DESIGNS_WRITE,  # a corrected paint goes to the chemist as a stored design
            S.LIBRARY_READ,
            S.FORMULATION_USE,  # whether the corrected paint is formulable; storing a job stays the chemist's
            S.ANALYSIS_WRITE,
            S.AUDIT_READ,
            S.QC_STANDARDS_WRITE,
        }
    ),
    Role.STYLIST: frozenset(
        {S.MEASUREMENTS_READ, S.DESIGNS_READ, S.DESIGNS_WRITE, S.STYLING_USE, S.LIBRARY_READ}
    ),
    Role.CHEMIST: frozenset(
        {
            S.MEASUREMENTS_READ,
            S.DESIGNS_READ,
            S.DESIGNS_WRITE,  # a formulated or adjusted paint is kept as a design
            S.LIBRARY_READ,
            S.LIBRARY_WRITE,
            S.FORMULATION_USE,
            S.RECIPES_WRITE,
        }
    ),
    Role.ADMIN: frozenset(Scope),
}


def new_token() -> str:
    """A fresh bearer token (shown once, never stored)."""
    return TOKEN_PREFIX + secrets.token_urlsafe(32)


def hash_token(token: str) -> str:
    """The stored form of *token*: SHA-256, hex."""
    return hashlib.sha256(token.encode("utf-8")).hexdigest()


def allows(role: Role, scope: Scope) -> bool:
    """Whether *role* holds *scope*."""
    return scope in ROLE_SCOPES[role]


def scope_refusal(role: Role, scope: Scope) -> str:
    """The 403 message for *role* lacking *scope*: what is missing and which roles hold it."""
    holders = ", ".join(r.value for r in Role if allows(r, scope))
    return f"role {role.value} lacks scope {scope.value} (held by: {holders})"


DEFAULT_TOKEN_TTL = dt.timedelta(days=90)
MAX_CACHED_TOKENS = 4096


@dataclass(frozen=True)
class TokenGrant:
    """What the database said about one token and its user, when it was last asked."""

    token_id: int
    user_id: int
    name: str
    role: Role
    active: bool
    user_created_at: dt.datetime
    expires_at: dt.datetime | None
    revoked_at: dt.datetime | None

    @classmethod
    def of(cls, token: ApiToken) -> TokenGrant:
        """The grant of a token row (its user loaded)."""
        user = token.user
        return cls(
            token_id=token.id,
            user_id=user.id,
            name=user.name,
            role=user.role,
            active=user.active,
            user_created_at=user.created_at,
            expires_at=token.expires_at,
            revoked_at=token.revoked_at,
        )

    def refusal(self, now: dt.datetime) -> str | None:
        """Why this token is refused at *now* (``None``: it is valid)."""
        if self.revoked_at is not None:
            return f"token {self.token_id} was revoked at {self.revoked_at.isoformat()}"
        if not self.active:
            return f"user {self.name!r} is deactivated"
        if self.expires_at is not None and now >= self.expires_at:
            return (
                f"token {self.token_id} expired at {self.expires_at.isoformat()}; ask an admin for a new one"
            )
        return None

    def user(self) -> User:
        """A detached :class:`User` standing for the caller (never added to a session)."""
        return User(
            id=self.user_id,
            name=self.name,
            role=self.role,
            active=self.active,
            created_at=self.user_created_at,
        )


class TokenCache:
    """Grants the database verified, usable for *offline_s* seconds after that while it is away.

    Thread-safe; one per app (``app.state.tokens``). Only valid grants are kept, at most
    ``MAX_CACHED_TOKENS`` (the oldest verification leaves first). Time is ``time.monotonic`` seconds.
    """

    def __init__(self, offline_s: float) -> None:
        self.offline_s = offline_s
        self._lock = threading.Lock()
        self._grants: dict[str, tuple[float, TokenGrant]] = {}

    def put(self, token_hash: str, grant: TokenGrant) -> None:
        """Remember that the database verified *grant* now."""
        with self._lock:
            self._grants.pop(token_hash, None)
            self._grants[token_hash] = (time.monotonic(), grant)
            while len(self._grants) > MAX_CACHED_TOKENS:
                self._grants.pop(next(iter(self._grants)))

    def get(self, token_hash: str, within_s: float | None = None) -> TokenGrant | None:
        """The grant verified within the last *within_s* seconds (default *offline_s*), or ``None``."""
        limit = self.offline_s if within_s is None else within_s
        with self._lock:
            found = self._grants.get(token_hash)
        if found is None or time.monotonic() - found[0] > limit:
            return None
        return found[1]

    def drop(self, token_hash: str | None = None, *, user_id: int | None = None) -> None:
        """Forget one token (by hash) or every token of *user_id* (a revocation or deactivation)."""
        with self._lock:
            if token_hash is not None:
                self._grants.pop(token_hash, None)
            if user_id is not None:
                for key in [k for k, (_, g) in self._grants.items() if g.user_id == user_id]:
                    del self._grants[key]

    def __len__(self) -> int:
        with self._lock:
            return len(self._grants)
