"""Soak fixtures: the migrated databases of tests.db (one SQLite file, one PostgreSQL database)."""

from tests.db._fixtures import (  # noqa: F401
    _migrated_pg,
    _migrated_sqlite,
    database_url,
    pg_server,
    pg_url,
)
