"""``scripts/pg-roles.sh``: migrations run as the owner; the service role cannot erase history.

The script runs against the test server with throwaway role and database names; the service role then
stores a reading (it can do its job) and every way of erasing history without a trace is refused:
TRUNCATE, DISABLE TRIGGER, DROP TRIGGER, UPDATE and DELETE of measurements and audit events, and
moving a chain head back.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import text
from sqlalchemy.engine import make_url
from sqlalchemy.exc import DBAPIError
from sqlalchemy.pool import NullPool

from db.engine import make_engine
from station.ingest import DatabaseDestination
from tests.db._fixtures import PG_ADMIN_URL
from tests.ingest._readings import make_reading
from tests.processes import run

pytestmark = pytest.mark.postgres
REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def roles(pg_server: object) -> Iterator[tuple[str, str]]:
    """Run the script with fresh names; the owner's and the service's URLs."""
    import psycopg

    tag = secrets.token_hex(4)
    names = {
        "CACAD_PG_DB": f"cacad_roles_{tag}",
        "CACAD_PG_OWNER": f"own_{tag}",
        "CACAD_PG_SERVICE": f"svc_{tag}",
    }
    admin = make_url(PG_ADMIN_URL)
    env = dict(
        os.environ,
        **names,
        CACAD_PG_HOST=admin.host or "127.0.0.1",
        CACAD_PG_PORT=str(admin.port or 5432),
        CACAD_PG_SUPERUSER=admin.username or "postgres",
        PYTHON=os.environ.get("PYTHON", "python"),
    )
    done = run(["bash", str(REPO / "scripts" / "pg-roles.sh")], env=env, timeout=120)
    assert done.returncode == 0, done.stderr + done.stdout
    base = f"postgresql://{{}}@{admin.host}:{admin.port or 5432}/{names['CACAD_PG_DB']}"
    try:
        yield base.format(names["CACAD_PG_OWNER"]), base.format(names["CACAD_PG_SERVICE"])
    finally:
        with psycopg.connect(PG_ADMIN_URL, autocommit=True) as conn:
            conn.execute(f'DROP DATABASE IF EXISTS "{names["CACAD_PG_DB"]}" WITH (FORCE)')
            conn.execute(f'DROP ROLE IF EXISTS "{names["CACAD_PG_SERVICE"]}"')
            conn.execute(f'DROP ROLE IF EXISTS "{names["CACAD_PG_OWNER"]}"')


REFUSED = (
    "TRUNCATE measurements",
    "TRUNCATE audit_events",
    "ALTER TABLE measurements DISABLE TRIGGER tr_measurements_append_only",
    "ALTER TABLE audit_events DISABLE TRIGGER ALL",
    "DROP TRIGGER tr_measurements_append_only ON measurements",
    "UPDATE measurements SET operator = 'x'",
    "DELETE FROM audit_events",
    "DELETE FROM ledger_heads",
    "UPDATE ledger_heads SET length = 0",
    "ALTER TABLE measurements DROP COLUMN chain_sha256",
    "CREATE TABLE scratch (x int)",
)


def test_service_role_stores_but_cannot_erase_history(roles: tuple[str, str]) -> None:
    owner_url, service_url = roles
    destination = DatabaseDestination(service_url)
    try:
        assert destination.store(make_reading(3, 0)).status == "stored"
        assert destination.store(make_reading(3, 1)).status == "stored"
    finally:
        destination.close()
    engine = make_engine(service_url, poolclass=NullPool)
    try:
        for statement in REFUSED:
            with pytest.raises(DBAPIError) as caught, engine.begin() as conn:
                conn.execute(text(statement))
            message = str(caught.value.orig)
            assert (
                "permission denied" in message
                or "must be owner" in message
                or "only moves forward" in message
            ), (
                statement,
                message,
            )
        with engine.connect() as conn:
            assert conn.execute(text("SELECT count(*) FROM measurements")).scalar() == 2
    finally:
        engine.dispose()
    owner = make_engine(owner_url, poolclass=NullPool)
    with owner.connect() as conn:  # the owner can lift a trigger (migrations need it); the service cannot
        assert conn.execute(
            text("SELECT tableowner FROM pg_tables WHERE tablename = 'measurements'")
        ).scalar() == (make_url(owner_url).username)
    owner.dispose()
