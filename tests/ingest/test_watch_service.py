"""The service's watch folder (``Settings.watch_dir``): a file dropped while the service runs is stored
through the service's ingestor on the configured job and part, a bad one is moved to ``rejected/``."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError
from sqlalchemy import select

from db.models import Measurement, Panel
from station.api import Settings, create_app


def test_service_watch_folder(tmp_path: Path) -> None:
    drop = tmp_path / "drop"
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'station.sqlite3'}",
        data_dir=tmp_path,
        simulators=(),
        load_demo_library=False,
        watch_dir=drop,
        watch_interval_s=0.05,
        watch_job="J-9",
        watch_part="hood",
    )
    app = create_app(settings)
    with TestClient(app):
        assert drop.is_dir()  # created on start
        (drop / "a.csv.part").write_text("sample,geometry,L,a,b\np1,45as15,50,1,2\np1,45as45,40,1.5,2.5\n")
        (drop / "a.csv.part").rename(drop / "a.csv")
        (drop / "b.csv").write_text("sample,geometry,L,a,b\np2,45as15,50,1,2\np2,45as15,40,1.5,2.5\n")
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and not ((drop / "done" / "a.csv").exists() and (drop / "rejected" / "b.csv").exists()):  # fmt: skip
            time.sleep(0.05)
        with app.state.sessions() as session:
            rows = session.execute(select(Measurement.geometries_deg, Measurement.lab, Panel.job, Panel.part, Panel.notes).join(Panel)).all()  # fmt: skip
    assert (drop / "done" / "a.csv").is_file()
    assert (
        "geometry: expected each geometry once per sample (p2)"
        in (drop / "rejected" / "b.csv.reason").read_text()
    )
    assert [tuple(r) for r in rows] == [
        ([15.0, 45.0], [[50.0, 1.0, 2.0], [40.0, 1.5, 2.5]], "J-9", "hood", "sample: p1")
    ]


def test_watch_settings_refuse_half_a_panel(tmp_path: Path) -> None:
    with pytest.raises(ValidationError, match="watch_job and watch_part"):
        Settings(data_dir=tmp_path, watch_dir=tmp_path, watch_job="J")
    with pytest.raises(ValidationError, match="watch_part: expected one of bumper"):
        Settings(data_dir=tmp_path, watch_dir=tmp_path, watch_job="J", watch_part="wing")
