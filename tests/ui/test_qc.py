"""QC screen: real widgets driven by clicks over a real database and over the real service app."""

from __future__ import annotations

import csv
import datetime as dt
import math
import uuid
from pathlib import Path
from typing import Any

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFileDialog

from db.engine import make_engine, make_sessionmaker
from db.migrate import ensure_at_head
from db.models import Measurement
from station.ingest import GlossRecord, InstrumentRef, store_gloss
from station.qc.jobs import set_standard
from tests.qc.conftest import FENDER_OFFSETS, populate
from tests.ui.screens import item_at, screen_of
from ui.models.qc import LocalQc, QcModel, ServiceQc
from ui.widgets.qc_screen import COLUMNS, QcScreen

pytestmark = [pytest.mark.qt]


def _click(qtbot, button) -> None:
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)


def _column(screen: QcScreen, name: str) -> list[str]:
    j = COLUMNS.index(name)
    return [item_at(screen.table, i, j).text() for i in range(screen.table.rowCount())]


def _database(tmp_path: Path):
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    ensure_at_head(url)
    engine = make_engine(url)
    with make_sessionmaker(engine)() as session:
        job = populate(session)
        set_standard(session, "J-100", "fender", measurement_id=job.standard_id)
        meter = InstrumentRef(serial="GL-9", model="gloss meter", kind="gloss")
        first = session.get(Measurement, job.sample_ids[0])
        second = session.get(Measurement, job.sample_ids[1])
        assert first is not None and second is not None
        common: dict[str, Any] = dict(instrument=meter, operator="ana", gloss_20_gu=80.0, gloss_85_gu=95.0)
        # linked to the first sample; gloss-only on the second sample's panel 5 minutes after it
        store_gloss(
            session,
            GlossRecord(
                client_id=uuid.uuid4(),
                measurement_id=first.id,
                measured_at=first.measured_at,
                gloss_60_gu=91.25,
                **common,
            ),
        )
        store_gloss(
            session,
            GlossRecord(
                client_id=uuid.uuid4(),
                panel_id=second.panel_id,
                measured_at=second.measured_at + dt.timedelta(minutes=5),
                gloss_60_gu=88.5,
                **common,
            ),
        )
        session.commit()
    engine.dispose()
    return url, job


def test_judge_a_job_from_the_local_database_and_export(qtbot, tmp_path, monkeypatch):
    url, job = _database(tmp_path)
    screen = QcScreen(QcModel(LocalQc(url)))
    qtbot.addWidget(screen)
    screen.show()
    assert not screen.judge_btn.isEnabled()
    _click(qtbot, screen.load_btn)
    assert [screen.job.itemText(i) for i in range(screen.job.count())] == ["J-100", "J-200"]
    screen.job.setCurrentText("J-100")
    assert [screen.part.itemText(i) for i in range(screen.part.count())] == ["bumper", "fender"]
    screen.part.setCurrentText("fender")
    screen.formula.setCurrentText("cie76")
    _click(qtbot, screen.judge_btn)
    # 7 samples × 3 geometries; ΔE*ab of each sample = |its offset| at every geometry (hand), limit 1.0
    assert screen.table.rowCount() == len(FENDER_OFFSETS) * 3
    expected = [math.sqrt(sum(v * v for v in off)) for off in FENDER_OFFSETS for _ in range(3)]
    assert _column(screen, "ΔE") == [f"{d:.2f}" for d in expected]
    assert _column(screen, "verdict") == ["fail" if d > 1.0 else "pass" for d in expected]
    assert _column(screen, "sample")[15:18] == [str(job.sample_ids[5])] * 3
    assert all("ΔE 2.5 beyond 1" in r for r in _column(screen, "reason")[15:18])
    assert _column(screen, "ΔL*")[15] == "+2.50"
    # the gloss reading paired with each sample: linked (first), same panel within 30 min (second), none
    assert _column(screen, "60° GU")[:9] == ["91.2"] * 3 + ["88.5"] * 3 + [""] * 3
    assert f"measurement {job.standard_id}" in screen.standard.text()
    assert "pass 6 · warn 0 · fail 1" in screen.standard.text()
    fail_cell = screen.table.item(15, COLUMNS.index("verdict"))
    assert fail_cell is not None
    assert fail_cell.background().color().name() == "#f4a09a"
    screen.part.setCurrentText("bumper")
    assert "no standard set" in screen.standard.text() and screen.table.rowCount() == 0

    out = tmp_path / "report.csv"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: (str(out), "")))
    _click(qtbot, screen.csv_btn)
    qtbot.waitUntil(lambda: screen.last_report == out, timeout=30000)
    assert screen.task is not None
    screen.task.wait()
    rows = list(csv.DictReader(out.read_text(encoding="utf-8").splitlines()))
    assert len(rows) == len(FENDER_OFFSETS) * 3 and {r["part"] for r in rows} == {"fender"}
    pdf = tmp_path / "report.pdf"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: (str(pdf), "")))
    qtbot.waitUntil(screen.pdf_btn.isEnabled, timeout=10000)
    _click(qtbot, screen.pdf_btn)
    qtbot.waitUntil(lambda: screen.last_report == pdf, timeout=60000)
    screen.task.wait()
    assert pdf.read_bytes().startswith(b"%PDF") and "report written" in screen.status.text()
    screen.close()


def test_an_unreachable_database_is_said_not_raised(qtbot, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    screen = QcScreen(QcModel(LocalQc(f"sqlite:///{blocker / 'station.sqlite3'}")))
    qtbot.addWidget(screen)
    _click(qtbot, screen.load_btn)
    assert screen.status.text().startswith("error:") and "database" in screen.status.text()
    assert screen.job.count() == 0 and not screen.judge_btn.isEnabled()
    screen.close()


def test_judge_through_the_service(qtbot, tmp_path):
    from tests.api.conftest import make_api
    from ui.models.service import ServiceClient

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        with api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
            job = populate(session)
            session.commit()
        r = api.client.put(
            "/api/v1/qc/jobs/J-100/standards/bumper",
            json={"measurement_id": job.correction_id},
            headers=api.auth("qa"),
        )
        assert r.status_code == 200, r.text
        service = ServiceClient("http://testserver", api.tokens[next(iter(api.tokens))], client=api.http)
        screen = QcScreen(QcModel(ServiceQc(service)))
        qtbot.addWidget(screen)
        _click(qtbot, screen.load_btn)
        screen.job.setCurrentText("J-100")
        screen.part.setCurrentText("bumper")
        screen.formula.setCurrentText("cie76")
        _click(qtbot, screen.judge_btn)
        # the second bumper sample (50, 0.6, 0) against the corrected standard (50.3, 0, 0): √0.45 = 0.67
        assert _column(screen, "ΔE") == [f"{math.sqrt(0.45):.2f}"] * 3
        assert _column(screen, "verdict") == ["pass"] * 3
        assert _column(screen, "sample") == [str(job.bumper_ids[1])] * 3
        assert screen.model.source.where == "service http://testserver"
        # metamerism: a sample with the standard's very spectra has index 0 under A and F11
        from tests.ingest._readings import make_reading

        tech, qa = api.auth("technician"), api.auth("qa")
        ids = []
        for k in range(2):  # the standard panel and a sample panel (a standard's repeats are no samples)
            panel = api.client.post(
                "/api/v1/panels", json={"job": "J-MI", "part": "door"}, headers=tech
            ).json()
            body = make_reading(41, k, panel_id=panel["id"]).model_dump(mode="json")
            body["spectra"] = [[0.5] * 31, [0.3] * 31, [0.1] * 31]
            r = api.client.post("/api/v1/measurements", json=body, headers=tech)
            assert r.status_code == 201, r.text
            ids.append(r.json()["id"])
        api.client.put("/api/v1/qc/jobs/J-MI/standards/door", json={"measurement_id": ids[0]}, headers=qa)
        _click(qtbot, screen.load_btn)
        screen.job.setCurrentText("J-MI")
        screen.part.setCurrentText("door")
        _click(qtbot, screen.judge_btn)
        _click(qtbot, screen.mi_btn)
        assert screen.status.text() == "error: select a sample row first"
        cell = screen.table.visualItemRect(item_at(screen.table, 0, 0)).center()
        qtbot.mouseClick(screen.table.viewport(), Qt.MouseButton.LeftButton, pos=cell)
        _click(qtbot, screen.mi_btn)
        assert screen.status.text() == (
            f"metamerism of {ids[1]} against {ids[0]} (cie76): MI A 0.00 · MI F11 0.00 (max over geometries)"
        )
        screen.part.setCurrentText("door")
        screen.job.setCurrentText("J-100")
        screen.part.setCurrentText("bumper")
        _click(qtbot, screen.judge_btn)
        qtbot.mouseClick(screen.table.viewport(), Qt.MouseButton.LeftButton, pos=cell)
        _click(qtbot, screen.mi_btn)  # the populated job has no spectra: refused, the field named
        assert screen.status.text().startswith("error:") and "spectra" in screen.status.text()
        screen.close()
    finally:
        gen.close()


def test_the_qc_tab_reads_the_database_the_scans_go_to(qtbot, tmp_path):
    """The main window's QC tab judges the jobs of the window's own database (its sink), not the
    configured default: a job stored there is listed."""
    from ui.app import MainWindow
    from ui.models.measure_db import LocalSink

    url, _job = _database(tmp_path)
    win = MainWindow(sink=LocalSink(url, tmp_path / "outbox.sqlite3"), ask_on_close=False)
    qtbot.addWidget(win)
    win.show()
    win.tabs.setCurrentWidget(win.screens["QC"])
    screen = screen_of(win, "QC", QcScreen)
    assert isinstance(screen.model.source, LocalQc) and screen.model.source.url == url
    _click(qtbot, screen.load_btn)
    assert [screen.job.itemText(i) for i in range(screen.job.count())] == ["J-100", "J-200"]
    win.close()
