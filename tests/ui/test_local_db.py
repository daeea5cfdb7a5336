"""The one local-database plumbing of the viewer's QC and booth sources (``ui.models.local_db``)."""

from __future__ import annotations

import pytest
from sqlalchemy import text

from ui.models.booth import BoothSourceError, LocalBoothSource
from ui.models.local_db import LocalDatabase
from ui.models.qc import LocalQc, QcSourceError


@pytest.mark.parametrize(
    ("source", "error"), [(LocalQc, QcSourceError), (LocalBoothSource, BoothSourceError)]
)
def test_each_source_opens_the_database_once_and_names_it_when_it_cannot(tmp_path, source, error):
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    db = source(url)
    assert isinstance(db, LocalDatabase) and db.url == url and db.where == f"database {url}"
    with db._session() as first:  # migrated on first use: the measurement tables are there
        assert first.execute(text("SELECT count(*) FROM measurements")).scalar_one() == 0
    factory = db._sessions
    with db._session():
        assert db._sessions is factory  # one session factory for the source's life
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    bad = source(f"sqlite:///{blocker / 'station.sqlite3'}")
    with pytest.raises(error) as info:
        bad._session()
    assert str(info.value).startswith(f"database sqlite:///{blocker / 'station.sqlite3'}: ")


def test_the_default_is_the_station_serve_database(tmp_path, monkeypatch):
    url = f"sqlite:///{tmp_path / 'configured.sqlite3'}"
    monkeypatch.setenv("CACAD_DATABASE_URL", url)
    assert LocalQc().url == url and LocalBoothSource().url == url
