"""The measure route answers a new reading from the values it inserted (no read-back): that answer must be
exactly what the stored row reads, on SQLite and PostgreSQL, for a reading with every optional part
(a non-UTC time, calibration, panel metadata, gloss, texture, another illumination block)."""

from __future__ import annotations

import datetime as dt
import uuid

from station.ingest import CalibrationRef, PanelRef, TextureValue
from tests.api.conftest import Api
from tests.ingest._readings import make_reading

V1 = "/api/v1"


def test_created_answer_is_the_stored_row(api: Api) -> None:
    plus2 = dt.timezone(dt.timedelta(hours=2))
    reading = make_reading(77, 0).model_copy(
        update={
            "measured_at": dt.datetime(2026, 12, 1, 9, 30, 15, 123456, tzinfo=plus2),
            "calibration": CalibrationRef(client_id=uuid.uuid4(), performed_at=dt.datetime.now(plus2)),
            "panel": PanelRef(job="J-77", part="hood"),
            "illumination_deg": 15.0,
            "gloss_gu": 61,
            "texture": [TextureValue(vendor="acme", name="sparkle", geometry="", value=3)],
        }
    )
    body = reading.model_dump(mode="json", exclude_none=True)
    posted = api.client.post(f"{V1}/measurements", json=body, headers=api.auth("technician"))
    assert posted.status_code == 201, posted.text
    created = posted.json()
    stored = api.client.get(f"{V1}/measurements/{created['id']}", headers=api.auth("technician"))
    assert stored.status_code == 200
    assert created == stored.json()
    assert created["measured_at"].startswith("2026-12-01T07:30:15.123456")  # told in UTC
    again = api.client.post(f"{V1}/measurements", json=body, headers=api.auth("technician"))
    assert again.status_code == 200 and again.json() == created
