"""Service fixtures: an app per test database, a user and token per role."""

from __future__ import annotations

from collections.abc import Generator, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import httpx
import pytest
from fastapi.testclient import TestClient

from db.models import Role
from station.api import Settings, create_app
from station.api.services import users
from tests.db._fixtures import (  # noqa: F401
    _migrated_pg,
    _migrated_sqlite,
    database_url,
    empty_database_url,
    pg_server,
    pg_url,
)


@dataclass
class Api:
    """A running app (TestClient, lifespan entered) and one bearer token per role."""

    client: TestClient
    tokens: dict[Role, str]

    def auth(self, role: Role | str) -> dict[str, str]:
        return {"Authorization": f"Bearer {self.tokens[Role(role)]}"}

    @property
    def http(self) -> httpx.Client:
        """The test client as the ``httpx.Client`` the viewer's ServiceClient takes: Starlette's TestClient
        is built on httpx2, whose Client has the same interface under another package name."""
        return cast(httpx.Client, self.client)


def make_api(url: str, tmp_path: Path, **settings: Any) -> Generator[Api]:
    opts: dict[str, Any] = dict(database_url=url, data_dir=tmp_path, simulators=(), load_demo_library=False)
    opts.update(settings)
    app = create_app(Settings(**opts))
    with TestClient(app) as client:
        tokens: dict[Role, str] = {}
        with app.state.sessions() as session:
            tokens[Role.ADMIN] = users.bootstrap_admin(session=session) or ""
            for role in Role:
                if role is not Role.ADMIN:
                    _u, _t, secret = users.create_user(
                        session=session, actor=None, name=f"{role.value}-1", role=role
                    )
                    tokens[role] = secret
        yield Api(client, tokens)


@pytest.fixture
def api(database_url: str, tmp_path: Path) -> Iterator[Api]:  # noqa: F811
    """The service on SQLite and on PostgreSQL."""
    yield from make_api(database_url, tmp_path)


@pytest.fixture
def sqlite_api(tmp_path: Path) -> Iterator[Api]:
    """The service on a fresh SQLite file only (for the broad table and fuzz tests)."""
    yield from make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
