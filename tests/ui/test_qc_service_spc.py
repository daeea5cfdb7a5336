"""The QC tab in service mode judges as in local mode: panels averaged with the dirty reading left out (and
kept on request), texture limits, a tolerance file, and the SPC chart with its drift, each through the service's routes,
compared with the same tab reading the same database directly.

Independent expectations: the dirty reading's id (the one stored 4 ΔL* off), and ΔE00 of the
hand-averaged panel means by colour-science, charted by the closed form of the individuals chart."""

from __future__ import annotations

import datetime as dt
import json
import uuid
from pathlib import Path
from typing import Any

import colour
import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from station.api.security import Role
from tests.api.conftest import make_api
from tests.ui.screens import item_at
from ui.models.qc import LocalQc, QcModel, ServiceQc
from ui.models.service import ServiceClient
from ui.widgets.qc_panels import SPC_COLUMNS
from ui.widgets.qc_screen import COLUMNS, QcScreen

pytestmark = [pytest.mark.qt]

JOB, PART = "J-SPC-VIEW", "hood"
ANGLES = [15.0, 45.0, 110.0]
STD = np.array([[55.0, -1.0, 2.0], [50.0, -0.5, 1.0], [45.0, 0.0, 0.5]])
#: ΔL* of each sample panel, oldest first: steady, then a rise that ends in a fail; each read twice.
DLS = (0.10, 0.13, 0.09, 0.12, 0.11, 0.25, 0.40, 0.60, 0.85, 1.30)
DIRTY_PANEL, BASELINE = 2, 5
TEXTURE = [{"vendor": "BYK", "name": "graininess", "geometry": "", "value": 3.0}]


def _store(http: Any, auth: dict[str, str]) -> int:
    """The job through the service; the id of the dirty reading."""

    def post(lab: np.ndarray, notes: str, minute: int, grain: float) -> int:
        body = {
            "client_id": str(uuid.uuid4()),
            "instrument": {"serial": "SIM-SPC-2", "model": "MA6", "kind": "multiangle"},
            "panel": {"job": JOB, "part": PART, "notes": notes},
            "operator": "ana",
            "measured_at": (
                dt.datetime(2026, 11, 4, 8, tzinfo=dt.UTC) + dt.timedelta(minutes=minute)
            ).isoformat(),
            "geometries_deg": ANGLES,
            "lab": lab.tolist(),
            "texture": [{**TEXTURE[0], "value": grain}],
        }
        r = http.post("/api/v1/measurements", json=body, headers=auth)
        assert r.status_code == 201, r.text
        return int(r.json()["id"])

    std = post(STD, "standard panel", 0, 3.0)
    dirty = 0
    for i, dl in enumerate(DLS):
        for k, d in enumerate([dl, dl + 0.02] + ([dl + 4.0] if i == DIRTY_PANEL else [])):
            mid = post(STD + [d, 0.0, 0.0], f"panel {i + 1}", 10 * (i + 1) + k, 3.0 + 0.05 * i)
            dirty = mid if k == 2 else dirty
    r = http.put(f"/api/v1/qc/jobs/{JOB}/standards/{PART}", json={"measurement_id": std}, headers=auth)
    assert r.status_code == 200, r.text
    return dirty


def _screen(qtbot: Any, model: QcModel) -> QcScreen:
    screen = QcScreen(model)
    qtbot.addWidget(screen)
    screen.show()
    screen.load_jobs()
    screen.job.setCurrentIndex(screen.job.findText(JOB))
    screen.formula.setCurrentIndex(screen.formula.findText("cie2000"))
    screen.texture_limits.setText("dg=0.5")
    QTest.mouseClick(screen.average, Qt.MouseButton.LeftButton)
    QTest.mouseClick(screen.judge_btn, Qt.MouseButton.LeftButton)
    screen.part.setCurrentIndex(screen.part.findText(PART))
    screen.spc.baseline.setValue(BASELINE)
    QTest.mouseClick(screen.spc.draw_btn, Qt.MouseButton.LeftButton)
    return screen


def _shown(screen: QcScreen) -> dict[str, Any]:
    table = [
        [item_at(screen.table, i, j).text() for j in range(len(COLUMNS))]
        for i in range(screen.table.rowCount())
    ]
    spc = [
        [item_at(screen.spc.table, i, j).text() for j in range(len(SPC_COLUMNS))]
        for i in range(screen.spc.table.rowCount())
    ]
    return {
        "table": table,
        "outliers": screen.outliers.text(),
        "texture": screen.texture_table.rowCount(),
        "spc": spc,
        "spc_text": screen.spc.text.toPlainText(),
        "status": screen.status.text(),
    }


def test_service_mode_judges_and_charts_as_local_mode(qtbot: Any, tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    gen = make_api(url, tmp_path)
    api = next(gen)
    try:
        dirty = _store(api.http, {"Authorization": f"Bearer {api.tokens[Role.ADMIN]}"})
        client = ServiceClient("http://testserver", api.tokens[Role.ADMIN], client=api.http)
        service = _screen(qtbot, QcModel(ServiceQc(client)))
        local = _screen(qtbot, QcModel(LocalQc(url)))
        got, want = _shown(service), _shown(local)
        assert service.model.source.where.startswith("service")
        assert "error" not in got["status"] and "error" not in got["spc_text"], (
            got["status"],
            got["spc_text"],
        )
        # the dirty reading is named as left out, in both modes
        assert f"measurement {dirty} left out" in got["outliers"] and "mean of 2 of 3" in got["outliers"]
        # the panel means' ΔE00 at 45° (colour-science) charted: centre of the first five, drift at the 7th
        de = np.array([colour.delta_E(STD[1], STD[1] + [dl + 0.01, 0, 0], method="CIE 2000") for dl in DLS])
        row = got["spc"][[r[0] for r in got["spc"]].index("45as45")]
        assert float(row[SPC_COLUMNS.index("centre")]) == pytest.approx(de[:BASELINE].mean(), abs=5e-4)
        assert "DRIFT 45as45: drift from sample #7" in got["spc_text"]
        assert "before the first fail" in got["spc_text"]
        assert got["texture"] > 0  # the texture limits went through: the graininess table is shown
        assert got == {**want, "status": got["status"]}  # the same numbers as local mode
        assert got["status"].split(":", 1)[1] == want["status"].split(":", 1)[1]
        # keep outliers: averaged in, through the service, as locally
        for s in (service, local):
            QTest.mouseClick(s.keep_outliers, Qt.MouseButton.LeftButton)
        got, want = _shown(service), _shown(local)
        assert f"measurement {dirty} kept although flagged" in got["outliers"]
        assert got == {**want, "status": got["status"]}
        # a tolerance file: sent as a tolerance set in the body (POST), judged as locally
        tol = tmp_path / "tol.json"
        geoms = [{"aspecular_deg": a, "de": 0.5} for a in ANGLES]
        tol.write_text(json.dumps({"formula": "cie2000", "geometries": geoms}))
        for s in (service, local):
            s.tolerance.setText(str(tol))
            QTest.mouseClick(s.judge_btn, Qt.MouseButton.LeftButton)
        got, want = _shown(service), _shown(local)
        assert "error" not in got["status"] and "error" not in got["spc_text"], (
            got["status"],
            got["spc_text"],
        )
        assert any("beyond 0.5" in row[COLUMNS.index("reason")] for row in got["table"])
        assert got == {**want, "status": got["status"]}
        client.close()
    finally:
        gen.close()
