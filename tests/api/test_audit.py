"""Every write through the API leaves one audit event naming who did it and when."""

from __future__ import annotations

import datetime as dt

from tests.api.conftest import Api
from tests.ingest._readings import make_reading

V1 = "/api/v1"
DESIGN = {"face": [62.0, -4.0, -38.0], "flop": [24.0, 1.0, -20.0], "travel_deg": 70.0, "gloss_gu": 88.0}


def test_every_write_is_audited_with_actor_and_time(sqlite_api: Api) -> None:
    c = sqlite_api.client
    ids = {
        role: c.get(f"{V1}/me", headers=sqlite_api.auth(role)).json()["id"]
        for role in ("admin", "technician", "qa", "stylist")
    }
    reading = make_reading(31, 0).model_dump(mode="json")
    writes: list[tuple[str, str, str, dict | None, str]] = [
        ("technician", "POST", f"{V1}/panels", {"job": "J-1", "part": "hood"}, "panel.create"),
        ("technician", "POST", f"{V1}/measurements", reading, "measurement.create"),
        (
            "qa",
            "POST",
            f"{V1}/measurements/1/corrections",
            {"reason": "re-measured", "reading": make_reading(31, 1).model_dump(mode="json")},
            "measurement.correct",
        ),
        ("stylist", "POST", f"{V1}/designs", {"name": "d", "design": DESIGN}, "design.create"),
        ("stylist", "PUT", f"{V1}/designs/1", {"design": DESIGN | {"travel_deg": 50.0}}, "design.version"),
        ("stylist", "DELETE", f"{V1}/designs/1", None, "design.archive"),
        ("admin", "POST", f"{V1}/users", {"name": "eve", "role": "chemist"}, "user.create"),
        ("admin", "POST", f"{V1}/users/6/tokens", {"label": "laptop"}, "token.issue"),
        ("admin", "DELETE", f"{V1}/users/6", None, "user.deactivate"),
    ]
    for role, method, url, body, action in writes:
        before = dt.datetime.now(dt.UTC)
        r = c.request(method, url, json=body, headers=sqlite_api.auth(role))
        assert r.status_code in (200, 201), (url, r.text)
        latest = c.get(f"{V1}/audit", params={"limit": 1}, headers=sqlite_api.auth("admin")).json()["data"][0]
        assert latest["action"] == action
        assert latest["actor_id"] == ids[role]
        at = dt.datetime.fromisoformat(latest["at"])
        assert before - dt.timedelta(seconds=1) <= at <= dt.datetime.now(dt.UTC) + dt.timedelta(seconds=1)
    total = c.get(f"{V1}/audit", headers=sqlite_api.auth("admin")).json()["count"]
    # 4 users created by the fixture outside the API + the bootstrap admin, then one per write above
    assert total == 5 + len(writes)
    # a re-sent reading is not a write: no audit event
    assert (
        c.post(f"{V1}/measurements", json=reading, headers=sqlite_api.auth("technician")).status_code == 200
    )
    assert c.get(f"{V1}/audit", headers=sqlite_api.auth("admin")).json()["count"] == total
    # reads leave nothing either; and the audit log itself is not writable through the API
    assert c.post(f"{V1}/audit", json={}, headers=sqlite_api.auth("admin")).status_code == 405
