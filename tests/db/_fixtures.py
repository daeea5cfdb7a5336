"""Database fixtures shared by tests/db, tests/ingest and tests/api.

``database_url`` runs a test on the embedded SQLite file and on PostgreSQL (127.0.0.1:5432, trust
auth). Every PostgreSQL test gets a throwaway database ``cacad_test_<session>_<n>``, created through
the ``postgres`` maintenance database and dropped afterwards. When the server cannot be reached the
PostgreSQL cases skip with the reason, except under ``CI=true``, where they fail.
"""

from __future__ import annotations

import itertools
import os
import secrets
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

PG_ADMIN_URL = os.environ.get("CACAD_TEST_PG_ADMIN", "postgresql://postgres@127.0.0.1:5432/postgres")
_SESSION_TAG = secrets.token_hex(4)
_counter = itertools.count()


def _pg_url(dbname: str) -> str:
    return PG_ADMIN_URL.rsplit("/", 1)[0] + "/" + dbname


class PgServer:
    """Creates and drops throwaway databases on the test server."""

    def __init__(self) -> None:
        import psycopg

        self._conn = psycopg.connect(PG_ADMIN_URL, autocommit=True, connect_timeout=3)
        self.created: list[str] = []

    def create(self, template: str | None = None) -> str:
        """Create a database (empty, or a copy of *template*'s URL) and return its SQLAlchemy URL."""
        name = f"cacad_test_{_SESSION_TAG}_{next(_counter)}"
        clause = f' TEMPLATE "{template.rsplit("/", 1)[1]}"' if template else ""
        self._conn.execute(f'CREATE DATABASE "{name}"{clause}')
        self.created.append(name)
        return _pg_url(name)

    def drop(self, url: str) -> None:
        """Drop the database behind *url* (disconnecting leftover sessions)."""
        name = url.rsplit("/", 1)[1]
        self._conn.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
        if name in self.created:
            self.created.remove(name)

    def close(self) -> None:
        for name in list(self.created):
            self._conn.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
        self._conn.close()


@pytest.fixture(scope="session")
def pg_server() -> Iterator[PgServer]:
    """The PostgreSQL test server, or a skip (a failure under ``CI=true``) when it is unreachable."""
    try:
        server = PgServer()
    except Exception as exc:
        reason = f"PostgreSQL not reachable at {PG_ADMIN_URL}: {exc}"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(reason)
        pytest.skip(reason)
    yield server
    server.close()


@pytest.fixture
def pg_url(pg_server: PgServer) -> Iterator[str]:
    """A fresh, empty PostgreSQL database for one test."""
    url = pg_server.create()
    yield url
    pg_server.drop(url)


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def empty_database_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A fresh, empty database (no tables): an SQLite file, then a PostgreSQL database."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'station.sqlite3'}"
    return request.getfixturevalue("pg_url")


@pytest.fixture(scope="session")
def _migrated_sqlite(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from db.migrate import upgrade

    path = tmp_path_factory.mktemp("template") / "station.sqlite3"
    upgrade(f"sqlite:///{path}")
    return path


@pytest.fixture(scope="session")
def _migrated_pg(pg_server: PgServer) -> str:
    from sqlalchemy.pool import NullPool

    from db.engine import make_engine
    from db.migrate import upgrade

    url = pg_server.create()
    upgrade(url)
    make_engine(url, poolclass=NullPool).dispose()
    return url


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """A fresh database migrated to head, on both backends (a copy of a once-migrated template)."""
    if request.param == "sqlite":
        target = tmp_path / "station.sqlite3"
        shutil.copyfile(request.getfixturevalue("_migrated_sqlite"), target)
        yield f"sqlite:///{target}"
        return
    server: PgServer = request.getfixturevalue("pg_server")
    url = server.create(template=request.getfixturevalue("_migrated_pg"))
    yield url
    server.drop(url)
