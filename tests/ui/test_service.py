"""Service mode against the real FastAPI app on a fresh SQLite database (TestClient transport, no network):
designs in and out of the palette, the library browser's library, a simulator scan stored through
``POST /api/v1/measurements`` with its panel, and stored measurements offered as QA panels."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.design_io import design_to_dict
from tests.api.conftest import make_api
from tests.ui.screens import screen_of
from ui.app import MainWindow
from ui.models.document import DEFAULT_DESIGN
from ui.models.instruments import InstrumentSession, MeasurementStore
from ui.models.measure_db import PanelInfo, ServiceSink
from ui.models.service import ServiceClient, ServiceError
from ui.widgets.library_screen import LibraryScreen
from ui.widgets.qa_screen import QAScreen

pytestmark = [pytest.mark.qt]

LIBRARY_CSV = (
    "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\n"
    "R-1,solid,90,40,50,30,39,49,29,38,48,28\n"
    "M-1,metallic,85,95,-2,-20,60,-1,-14,30,0,-8\n"
)


@pytest.fixture
def api(tmp_path):
    yield from make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)


def _token(api, *roles: str) -> str:
    return api.tokens[next(r for r in api.tokens if r.value in roles)]


def _window(api, token: str, tmp_path) -> MainWindow:
    service = ServiceClient("http://testserver", token, client=api.http)
    return MainWindow(
        service=service, sink=ServiceSink(service, tmp_path / "outbox.sqlite3"), ask_on_close=False
    )


def test_viewer_loads_and_saves_designs(qtbot, api, tmp_path):
    token = _token(api, "designer", "admin")
    other = DEFAULT_DESIGN.replace(face=(60.0, 30.0, 10.0), name="service red")
    r = api.client.post(
        "/api/v1/designs",
        json={"name": "service red", "design": design_to_dict(other)},
        headers={"Authorization": f"Bearer {token}"},
    )
    assert r.status_code == 201, r.text
    win = _window(api, token, tmp_path)
    qtbot.addWidget(win)
    assert win.load_from_service() == 1
    name, design = win.designer.palette[-1]
    assert name == "service red" and design.face == other.face and design.flop == other.flop
    new_id = win.save_to_service()
    assert new_id is not None
    assert win.service is not None
    names = [n for _i, n, _d in win.service.list_designs()]
    assert names.count("untitled") == 1
    win.close()


def test_library_browser_shows_the_service_library(qtbot, api, tmp_path):
    r = api.client.post(
        "/api/v1/library/import",
        content=LIBRARY_CSV.encode(),
        params={"name": "shop"},
        headers={**api.auth("admin"), "Content-Type": "text/csv"},
    )
    assert r.status_code == 201, r.text
    win = _window(api, _token(api, "admin"), tmp_path)
    qtbot.addWidget(win)
    lib = screen_of(win, "Library", LibraryScreen).model.library
    assert sorted(lib.codes.tolist()) == ["M-1", "R-1"] and not lib.synthetic
    i = lib.codes.tolist().index("R-1")
    np.testing.assert_allclose(lib.lab[i], [[40, 50, 30], [39, 49, 29], [38, 48, 28]])
    assert lib.angles_deg == (15.0, 45.0, 110.0) and lib.gloss_gu[i] == 90.0
    assert "service http://testserver" in screen_of(win, "Library", LibraryScreen).title.text()
    win.close()


@pytest.mark.slow
def test_scan_is_stored_on_the_service_and_offered_to_qa(qtbot, api, tmp_path):
    token = _token(api, "technician", "operator", "admin")
    win = _window(api, token, tmp_path)
    qtbot.addWidget(win)
    session = InstrumentSession()
    try:
        session.connect("sim:ma6")
        panel = PanelInfo("J-7", "fender", "steel", "left front")
        m = session.scan(panel, store=win.store)
    finally:
        session.close()
    assert m.receipt is not None
    assert m.receipt.status == "stored", m.receipt
    # read back over HTTP: one measurement on a panel with the metadata
    page = api.client.get("/api/v1/measurements", headers=api.auth("admin")).json()
    assert page["count"] == 1 and page["data"][0]["id"] == m.receipt.measurement_id
    stored = page["data"][0]
    assert m.reading is not None
    assert stored["client_id"] == str(m.reading.client_id)
    np.testing.assert_allclose(stored["lab"], m.lab, atol=1e-3)
    p = api.client.get(f"/api/v1/panels/{stored['panel_id']}", headers=api.auth("admin")).json()
    assert (p["job"], p["part"], p["substrate"], p["notes"]) == ("J-7", "fender", "steel", "left front")
    # a retry is stored once; the same panel metadata reuses the panel
    again = win.store.persist(m).receipt
    assert again is not None and again.status == "duplicate"
    assert api.client.get("/api/v1/measurements", headers=api.auth("admin")).json()["count"] == 1
    qa = screen_of(win, "QA", QAScreen)
    assert qa.load_stored() == 1
    label = next(lbl for lbl, _d in qa.sources() if lbl.startswith(f"stored #{stored['id']}: J-7 fender"))
    qa.panel_b.setCurrentText(label)
    got = qa.picked()[1]  # the fit of the same 45° Lab (stored to 4 decimals)
    for f in ("face", "flop", "travel_deg", "gloss_gu"):
        assert getattr(got, f) == pytest.approx(getattr(m.design, f), abs=1e-3)
    win.close()


def test_clicking_load_stored_in_service_mode_offers_the_stored_scans(qtbot, api, tmp_path):
    """The QA button over HTTP: a click sends a valid page size (no 422) and lists every stored scan."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    from tests.ui.test_instruments import _spectral
    from ui.models.instruments import measurement_from_reading

    win = _window(api, _token(api, "technician", "operator", "admin"), tmp_path)
    qtbot.addWidget(win)
    panels = [PanelInfo("J-8", "bumper", "PP/EPDM"), PanelInfo("J-8", "fender", "steel")]
    for i, panel in enumerate(panels):
        m = win.store.persist(measurement_from_reading(_spectral(f"SIM-S-{i}"), panel, "test"))
        assert m.receipt is not None
        assert m.receipt.status == "stored", m.receipt
    page = api.client.get("/api/v1/measurements", headers=api.auth("admin")).json()
    assert page["count"] == len(panels)
    qa = screen_of(win, "QA", QAScreen)
    win.show()
    win.tabs.setCurrentWidget(win.screens["QA"])
    QTest.mouseClick(qa.load_btn, Qt.MouseButton.LeftButton)
    assert qa.verdict.text() != "error", qa.details.text()
    assert "422" not in qa.details.text()
    items = [qa.panel_a.itemText(i) for i in range(qa.panel_a.count())]
    shown = [t for t in items if t.startswith("stored #")]
    assert len(shown) == len(panels)
    for row in page["data"]:
        assert sum(t.startswith(f"stored #{row['id']}: ") for t in shown) == 1
    for p in panels:
        assert sum(f": {p.job} {p.part} " in t for t in shown) == 1
    win.close()


def test_unreachable_service_keeps_the_reading(qtbot, api, tmp_path):
    down = ServiceClient("http://127.0.0.1:9", "t", timeout_s=2.0)
    sink = ServiceSink(down, tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    from tests.ui.test_instruments import _spectral
    from ui.models.instruments import measurement_from_reading

    m = measurement_from_reading(_spectral(), PanelInfo("J-9", "hood"), "test")
    r = store.persist(m).receipt
    assert r is not None
    assert r.status == "queued" and "unreachable" in r.message and sink.pending() == 1
    sink.client = ServiceClient("http://testserver", _token(api, "admin"), client=api.http)  # back up
    assert [x.status for x in sink.flush().values()] == ["stored"] and sink.pending() == 0
    assert api.client.get("/api/v1/measurements", headers=api.auth("admin")).json()["count"] == 1
    down.close()
    sink.close()


def test_refused_token_is_reported_not_raised(qtbot, api, tmp_path):
    win = _window(api, "wrong-token", tmp_path)
    qtbot.addWidget(win)
    assert win.load_from_service() == 0
    assert "HTTP 401" in win.statusBar().currentMessage()
    with pytest.raises(ServiceError):
        assert win.service is not None
        win.service.list_designs()
    win.close()
