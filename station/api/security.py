"""Roles, scopes and bearer tokens.

Tokens are 256-bit random secrets; the database keeps only their SHA-256 (a fast hash is enough for
secrets of this entropy: there is nothing to brute-force, unlike a password). Each role holds the
fewest scopes its job needs (a technician measures; a chemist formulates; only admin manages users).
"""

from __future__ import annotations

import enum
import hashlib
import secrets

from db.models import Role

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
    LIBRARY_READ = "library:read"
    LIBRARY_WRITE = "library:write"
    RECIPES_WRITE = "recipes:write"
    ANALYSIS_WRITE = "analysis:write"
    AUDIT_READ = "audit:read"
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
            S.LIBRARY_READ,
            S.ANALYSIS_WRITE,
            S.AUDIT_READ,
        }
    ),
    Role.STYLIST: frozenset({S.MEASUREMENTS_READ, S.DESIGNS_READ, S.DESIGNS_WRITE, S.LIBRARY_READ}),
    Role.CHEMIST: frozenset(
        {S.MEASUREMENTS_READ, S.DESIGNS_READ, S.LIBRARY_READ, S.LIBRARY_WRITE, S.RECIPES_WRITE}
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
