"""``station db …`` and ``station users …`` in-process, and the service outbox replay."""

from __future__ import annotations

import json
from pathlib import Path

from station.cli import main
from station.ingest import Outbox
from tests.api.conftest import Api
from tests.ingest._readings import make_reading
from tests.waiting import wait_until


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def test_db_and_users_commands(tmp_path: Path, capsys) -> None:
    d = ["--data-dir", str(tmp_path)]
    assert main(["db", "upgrade", *d, "--json"]) == 0
    out = _json(capsys)
    from db.migrate import head_revision

    assert out["revision"] == out["head"] == head_revision()
    assert main(["db", "downgrade", "0001", *d, "--json"]) == 0
    assert _json(capsys)["revision"] == "0001"
    assert main(["db", "upgrade", *d, "--json"]) == 0
    capsys.readouterr()
    assert main(["users", "add", "ana", "--role", "qa", *d, "--json"]) == 0
    added = _json(capsys)
    assert added["role"] == "qa" and added["token"].startswith("cst_")
    assert main(["users", "add", "ana", *d]) == 1  # name taken
    assert "exists" in capsys.readouterr().err
    assert main(["users", "token", *d]) == 2  # name missing
    assert "name" in capsys.readouterr().err
    assert main(["users", "token", "ana", *d, "--json"]) == 0
    assert _json(capsys)["token"] != added["token"]
    assert main(["users", "deactivate", "ana", *d, "--json"]) == 0
    assert _json(capsys)["active"] is False
    assert main(["users", "list", *d, "--json"]) == 0
    assert [u["name"] for u in _json(capsys)["users"]] == ["ana"]


def test_service_drains_its_outbox_in_the_background(tmp_path: Path) -> None:
    from tests.api.conftest import make_api

    reading = make_reading(22, 0)
    with Outbox(tmp_path / "outbox.sqlite3") as box:
        box.put(str(reading.client_id), reading.canonical_json())
    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, outbox_replay_s=0.2)
    api = next(gen)
    try:
        count = wait_until(
            lambda: api.client.get("/api/v1/measurements", headers=api.auth("qa")).json()["count"],
            60,
            interval=0.2,
            what="the outbox reading to be stored",
        )
        assert count == 1
    finally:
        gen.close()


def test_service_outbox_is_replayed_in_order_and_audited(sqlite_api: Api) -> None:
    app = sqlite_api.client.app
    hub = app.state.instruments  # type: ignore[attr-defined]
    readings = [make_reading(21, i) for i in range(4)]
    with Outbox(hub.settings.outbox_path) as box:  # what measure() leaves behind while the database is away
        for r in readings:
            box.put(str(r.client_id), r.canonical_json())
    assert hub.replay_outbox() == 4
    assert len(hub.outbox()) == 0
    data = sqlite_api.client.get(
        "/api/v1/measurements", params={"limit": 10}, headers=sqlite_api.auth("qa")
    ).json()["data"]
    assert sorted((m["id"], m["client_id"]) for m in data) == [
        (i + 1, str(r.client_id)) for i, r in enumerate(readings)
    ]
    events = sqlite_api.client.get(
        "/api/v1/audit", params={"entity": "measurement"}, headers=sqlite_api.auth("admin")
    ).json()
    assert events["count"] == 4 and {e["action"] for e in events["data"]} == {"measurement.replay"}
