"""The service's watch folder (``Settings.watch_dir``): a file dropped while the service runs is stored
through the service's ingestor on the configured job and part, a bad one is moved to ``rejected/``."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError
from sqlalchemy import select

from db.models import Measurement, Panel
from station.api import Settings, create_app
from tests.waiting import wait_until


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
        wait_until(
            lambda: (drop / "done" / "a.csv").exists() and (drop / "rejected" / "b.csv").exists(),
            20,
            what="a.csv done and b.csv rejected",
        )
        with app.state.sessions() as session:
            rows = session.execute(select(Measurement.geometries_deg, Measurement.lab, Panel.job, Panel.part, Panel.notes).join(Panel)).all()  # fmt: skip
    assert (drop / "done" / "a.csv").is_file()
    assert (
        "CsvImportError: geometry: expected each geometry once per sample (b.csv, line 3)"
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


def test_service_watch_folder_refuses_a_linked_rejected_folder(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """``rejected/`` made beforehand as a symbolic link: the service's watcher refuses the folder with
    one error line and stops; the dropped files stay where they were, nothing goes through the link."""
    drop = tmp_path / "drop"
    drop.mkdir()
    outside = tmp_path / "cron.d"
    outside.mkdir()
    (drop / "rejected").symlink_to(outside)
    (drop / "evil").write_text("* * * * * root sh -c 'id > /tmp/owned'\n")
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'station.sqlite3'}",
        data_dir=tmp_path,
        simulators=(),
        load_demo_library=False,
        watch_dir=drop,
        watch_interval_s=0.05,
    )
    app = create_app(settings)
    with caplog.at_level(logging.INFO, logger="station.api.app"), TestClient(app):
        wait_until(
            lambda: any("refused" in r.message for r in caplog.records), 20, what="the watch folder refused"
        )
        refusals = [r for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(refusals) == 1 and "rejected: expected a folder the watcher makes" in refusals[0].getMessage()
    assert "a symbolic link" in refusals[0].getMessage() and refusals[0].exc_info is None
    assert list(outside.iterdir()) == [] and (drop / "evil").is_file()
