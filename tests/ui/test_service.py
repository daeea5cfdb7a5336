"""Service mode: the viewer loads the service's designs into its palette and saves the current design,
against the real FastAPI app on a fresh SQLite database (TestClient transport, no network)."""

from __future__ import annotations

import pytest

from station.model.design_io import design_to_dict
from tests.api.conftest import make_api
from ui.app import MainWindow
from ui.models.document import DEFAULT_DESIGN
from ui.models.service import ServiceClient, ServiceError

pytestmark = [pytest.mark.qt]


@pytest.fixture
def api(tmp_path):
    yield from make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)


def test_viewer_loads_and_saves_designs(qtbot, api, tmp_path):
    token = api.tokens[next(r for r in api.tokens if r.value in ("designer", "admin"))]
    other = DEFAULT_DESIGN.replace(face=(60.0, 30.0, 10.0), name="service red")
    r = api.client.post("/api/v1/designs", json={"name": "service red", "design": design_to_dict(other)},
                        headers={"Authorization": f"Bearer {token}"})
    assert r.status_code == 201, r.text
    win = MainWindow(service_url="http://testserver", measurements=tmp_path / "m.jsonl")
    win.service.close()
    win.service = ServiceClient("http://testserver", token, client=api.client)
    qtbot.addWidget(win)
    assert win.load_from_service() == 1
    name, design = win.designer.palette[-1]
    assert name == "service red" and design.face == other.face and design.flop == other.flop
    new_id = win.save_to_service()
    assert new_id is not None
    names = [n for _i, n, _d in win.service.list_designs()]
    assert names.count("untitled") == 1
    win.close()


def test_refused_token_is_reported_not_raised(qtbot, api, tmp_path):
    win = MainWindow(service_url="http://testserver", measurements=tmp_path / "m.jsonl")
    win.service.close()
    win.service = ServiceClient("http://testserver", "wrong-token", client=api.client)
    qtbot.addWidget(win)
    assert win.load_from_service() == 0
    assert "HTTP 401" in win.statusBar().currentMessage()
    with pytest.raises(ServiceError):
        win.service.list_designs()
    win.close()
