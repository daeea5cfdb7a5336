"""Two corrections of one measurement racing on PostgreSQL: one stores, the other is a 409.

Both requests are held after their "already superseded?" check until both have made it, so the race
is the one a lab meets when two QA engineers correct the same reading at once: the database's unique
``supersedes_id`` refuses the second insert, and the service must say *conflict*, not *not found*.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from station.api.services import measurements as service
from tests.api.conftest import Api, make_api
from tests.db._fixtures import PgServer
from tests.ingest._readings import make_reading

V1 = "/api/v1"
pytestmark = pytest.mark.postgres


@pytest.fixture
def pg_api(pg_server: PgServer, _migrated_pg: str, tmp_path: Path) -> Iterator[Api]:
    url = pg_server.create(template=_migrated_pg)
    try:
        yield from make_api(url, tmp_path)
    finally:
        pg_server.drop(url)


def _reading(i: int) -> dict[str, Any]:
    return make_reading(13, i).model_dump(mode="json")


def test_concurrent_corrections_one_wins_the_other_is_409(
    pg_api: Api, monkeypatch: pytest.MonkeyPatch
) -> None:
    api = pg_api
    original = api.client.post(f"{V1}/measurements", json=_reading(0), headers=api.auth("technician"))
    assert original.status_code == 201, original.text
    mid = original.json()["id"]
    both_checked = threading.Barrier(2, timeout=20)
    store = service.store_reading

    def store_after_both_checked(*args: Any, **kwargs: Any) -> Any:
        both_checked.wait()
        return store(*args, **kwargs)

    monkeypatch.setattr(service, "store_reading", store_after_both_checked)

    def correct(i: int) -> Any:
        body = {"reason": f"fix {i}", "reading": _reading(i)}
        return api.client.post(f"{V1}/measurements/{mid}/corrections", json=body, headers=api.auth("qa"))

    with ThreadPoolExecutor(2) as pool:
        answers = list(pool.map(correct, (1, 2)))
    codes = sorted(r.status_code for r in answers)
    assert codes == [201, 409], [r.text for r in answers]
    loser = next(r for r in answers if r.status_code == 409)
    winner = next(r for r in answers if r.status_code == 201).json()
    assert f"measurement {mid} is already superseded by {winner['id']}" in loser.json()["detail"]
    monkeypatch.undo()
    everything = api.client.get(
        f"{V1}/measurements", params={"include_superseded": True}, headers=api.auth("qa")
    ).json()
    assert everything["count"] == 2
    events = api.client.get(f"{V1}/audit", params={"entity": "measurement"}, headers=api.auth("admin"))
    assert [e["action"] for e in events.json()["data"]].count("measurement.correct") == 1
