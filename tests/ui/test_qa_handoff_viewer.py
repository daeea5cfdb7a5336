"""Service mode: QA's corrected paint, sent on to the Formulation tab, is stored on the service as a design
the chemist lists, and the screen says so (the service's refusals read as its message, not raw JSON)."""

from __future__ import annotations

import pytest

from station.model import FaceFlopTravelGloss

pytestmark = [pytest.mark.qt]

PAINT = FaceFlopTravelGloss(
    (64.0, -4.5, -36.0), (25.0, 1.0, -19.0), 72.0, name="door B′", gloss_measured=False
)


def test_received_paint_is_stored_for_the_chemist(qtbot, tmp_path) -> None:
    from tests.api.conftest import make_api
    from ui.models.document import DesignDocument
    from ui.models.service import ServiceClient, ServiceError
    from ui.widgets.formulation_screen import FormulationScreen

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        qa = ServiceClient(
            "http://testserver", api.tokens[next(r for r in api.tokens if r.value == "qa")], client=api.http
        )
        screen = FormulationScreen(None, DesignDocument(), service=qa)
        qtbot.addWidget(screen)
        screen.receive(PAINT)
        rows = api.client.get("/api/v1/designs", headers=api.auth("chemist")).json()["data"]
        assert len(rows) == 1 and rows[0]["name"] == "door B′"
        assert rows[0]["design"]["gloss_gu"] is None  # not measured, still
        assert f"stored on the service as design #{rows[0]['id']} for the chemist" in screen.status.text()
        with pytest.raises(ServiceError) as refused:
            qa.call("POST", "/formulation/closed-loop", json={"design_id": rows[0]["id"]})
        assert str(refused.value).endswith(
            "HTTP 403 role qa lacks scope recipes:write (held by: chemist, admin)"
        )
        screen.close()
    finally:
        gen.close()
