"""The service role of ``scripts/pg-roles.sh`` cannot move a chain head, nor append a row that does not link.

Runs the script against the test server (fixture ``roles`` of ``test_pg_roles``); the service role then
stores readings (its job) and tries, with plain SQL, what a writer of the database would do to hide a
change: move a head forward over nothing, onto a row whose link is forged, or erase a record event.
"""

from __future__ import annotations

import pytest
from sqlalchemy import text
from sqlalchemy.exc import DBAPIError
from sqlalchemy.pool import NullPool

from db.engine import make_engine
from station.ingest import DatabaseDestination
from tests.db.test_pg_roles import roles  # noqa: F401  (the fixture)
from tests.ingest._readings import make_reading

pytestmark = pytest.mark.postgres

REFUSED = (
    "UPDATE ledger_heads SET length = length + 1, head_sha256 = repeat('f', 64) WHERE chain = 'measurements'",
    "UPDATE ledger_heads SET length = length + 1, head_sha256 = (SELECT chain_sha256 FROM measurements "
    "ORDER BY id LIMIT 1) WHERE chain = 'measurements'",
    "UPDATE record_events SET op = 'delete'",
    "DELETE FROM record_events",
)


def test_service_role_cannot_move_a_head_or_forge_a_link(roles: tuple[str, str]) -> None:  # noqa: F811
    _owner_url, service_url = roles
    destination = DatabaseDestination(service_url)
    try:
        assert [destination.store(make_reading(21, i)).status for i in range(3)] == ["stored"] * 3
    finally:
        destination.close()
    engine = make_engine(service_url, poolclass=NullPool)
    try:
        for statement in REFUSED:
            with pytest.raises(DBAPIError) as caught, engine.begin() as conn:
                conn.execute(text(statement))
            message = str(caught.value.orig)
            assert "only moves forward" in message or "permission denied" in message, (statement, message)
        with pytest.raises(DBAPIError, match="only moves forward"), engine.begin() as conn:
            # a copy of the last row under a new client id, its link forged, then the head moved onto it
            conn.execute(
                text(
                    "INSERT INTO measurements (client_id, instrument_id, operator, measured_at, received_at, "
                    "illuminant, observer, geometries_deg, lab, payload_sha256, row_sha256, chain_sha256) "
                    "SELECT gen_random_uuid(), instrument_id, operator, measured_at, received_at, illuminant, "
                    "observer, geometries_deg, lab, payload_sha256, row_sha256, repeat('e', 64) "
                    "FROM measurements ORDER BY id DESC LIMIT 1"
                )
            )
            conn.execute(
                text(
                    "UPDATE ledger_heads SET length = length + 1, head_sha256 = repeat('e', 64), "
                    "head_at = (SELECT max(received_at) FROM measurements) WHERE chain = 'measurements'"
                )
            )
        with engine.connect() as conn:
            head = conn.execute(text("SELECT length FROM ledger_heads WHERE chain = 'measurements'")).scalar()
            assert head == 3
    finally:
        engine.dispose()
